#include "od/types.hpp"

namespace od {

std::string_view to_string(Status s) {
    switch (s) {
        case Status::Ok:
            return "ok";
        case Status::NoObject:
            return "object does not exist";
        case Status::NoSubindex:
            return "subindex does not exist";
        case Status::ReadOnly:
            return "attempt to write a read-only object";
        case Status::WriteOnly:
            return "attempt to read a write-only object";
        case Status::SubindexZeroFirst:
            return "subindex 0 must be 0 for write access";
        case Status::LengthMismatch:
            return "length of service parameter does not match";
        case Status::LengthTooHigh:
            return "length of service parameter too high";
        case Status::LengthTooLow:
            return "length of service parameter too low";
        case Status::ValueTooHigh:
            return "value of parameter written too high";
        case Status::ValueTooLow:
            return "value of parameter written too low";
        case Status::InvalidValue:
            return "value range of parameter exceeded";
        case Status::MaxBelowMin:
            return "maximum value is less than minimum value";
        case Status::NotMappable:
            return "object cannot be mapped to the PDO";
        case Status::PdoLengthExceeded:
            return "number and length of mapped objects exceed PDO length";
        case Status::Incompatible:
            return "general parameter incompatibility";
        case Status::WrongState:
            return "not possible in the present device state";
        case Status::CannotStore:
            return "data cannot be transferred or stored";
        case Status::HardwareError:
            return "access failed due to a hardware error";
        case Status::OutOfMemory:
            return "out of memory";
        case Status::GeneralError:
            return "general error";
    }
    return "unknown status";
}

std::string_view to_string(DataType t) {
    switch (t) {
        case DataType::Boolean:
            return "BOOL";
        case DataType::Integer8:
            return "SINT";
        case DataType::Integer16:
            return "INT";
        case DataType::Integer32:
            return "DINT";
        case DataType::Unsigned8:
            return "USINT";
        case DataType::Unsigned16:
            return "UINT";
        case DataType::Unsigned32:
            return "UDINT";
        case DataType::Real32:
            return "REAL";
        case DataType::VisibleString:
            return "STRING";
        case DataType::OctetString:
            return "OCTET_STRING";
        case DataType::UnicodeString:
            return "UNICODE_STRING";
        case DataType::Real64:
            return "LREAL";
        case DataType::Integer64:
            return "LINT";
        case DataType::Unsigned64:
            return "ULINT";
        case DataType::PdoMapping:
            return "PDO_MAPPING";
        case DataType::Identity:
            return "IDENTITY";
        case DataType::SyncManagerParameter:
            return "SYNC_PAR";
        case DataType::Integer24:
            return "INT24";
        case DataType::Unsigned24:
            return "UINT24";
        case DataType::Bit1:
            return "BIT1";
        case DataType::Bit2:
            return "BIT2";
        case DataType::Bit3:
            return "BIT3";
        case DataType::Bit4:
            return "BIT4";
        case DataType::Bit5:
            return "BIT5";
        case DataType::Bit6:
            return "BIT6";
        case DataType::Bit7:
            return "BIT7";
        case DataType::Bit8:
            return "BIT8";
    }
    return "UNKNOWN";
}

}  // namespace od
