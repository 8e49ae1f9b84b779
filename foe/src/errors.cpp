#include "foe/errors.hpp"

namespace foe {

std::string_view error_text(ErrorCode code) {
    return error_text(static_cast<uint32_t>(code));
}

std::string_view error_text(uint32_t code) {
    switch (static_cast<ErrorCode>(code)) {
        case ErrorCode::NotDefined:
            return "Not defined";
        case ErrorCode::NotFound:
            return "Not found";
        case ErrorCode::AccessDenied:
            return "Access denied";
        case ErrorCode::DiskFull:
            return "Disk full";
        case ErrorCode::Illegal:
            return "Illegal";
        case ErrorCode::PacketNumberWrong:
            return "Packet number wrong";
        case ErrorCode::AlreadyExists:
            return "Already exists";
        case ErrorCode::NoUser:
            return "No user";
        case ErrorCode::BootstrapOnly:
            return "Bootstrap only";
        case ErrorCode::NotInBootstrap:
            return "Not in bootstrap";
        case ErrorCode::NoRights:
            return "No rights";
        case ErrorCode::ProgramError:
            return "Program error";
        case ErrorCode::InvalidChecksum:
            return "Invalid checksum";
        case ErrorCode::InvalidFirmware:
            return "Invalid firmware";
        case ErrorCode::NoFileToRead:
            return "No file to read";
        case ErrorCode::FileHeaderError:
            return "File header missing or wrong";
        case ErrorCode::FlashError:
            return "Flash error";
    }
    return "Not defined";
}

}  // namespace foe
