#include "coe/abort.hpp"

namespace coe {

uint32_t abort_code(od::Status s) {
    using od::Status;
    switch (s) {
        case Status::Ok:
            return 0;
        case Status::NoObject:
            return abort::NoObject;
        case Status::NoSubindex:
            return abort::NoSubindex;
        case Status::ReadOnly:
            return abort::ReadOnly;
        case Status::WriteOnly:
            return abort::WriteOnly;
        case Status::SubindexZeroFirst:
            return abort::SubindexZeroFirst;
        case Status::LengthMismatch:
            return abort::LengthMismatch;
        case Status::LengthTooHigh:
            return abort::LengthTooHigh;
        case Status::LengthTooLow:
            return abort::LengthTooLow;
        case Status::ValueTooHigh:
            return abort::ValueTooHigh;
        case Status::ValueTooLow:
            return abort::ValueTooLow;
        case Status::InvalidValue:
            return abort::ValueRange;
        case Status::MaxBelowMin:
            return abort::MaxBelowMin;
        case Status::NotMappable:
            return abort::NotMappable;
        case Status::PdoLengthExceeded:
            return abort::PdoLength;
        case Status::Incompatible:
            return abort::Incompatible;
        case Status::WrongState:
            return abort::WrongState;
        case Status::CannotStore:
            return abort::CannotStore;
        case Status::HardwareError:
            return abort::HardwareError;
        case Status::OutOfMemory:
            return abort::OutOfMemory;
        case Status::GeneralError:
            return abort::General;
    }
    return abort::General;
}

}  // namespace coe
