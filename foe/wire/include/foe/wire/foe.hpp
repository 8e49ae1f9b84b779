#pragma once
// The FoE vocabulary (ETG.1000.6 §5.8): opcodes, the 6-byte FoE header and the error codes with the texts
// sent in an ERR packet. FoE server (foe/) and FoE client (tools/lib/master) both take them from here.
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace foe {

enum class Opcode : uint8_t { Read = 1, Write = 2, Data = 3, Ack = 4, Error = 5, Busy = 6 };

enum class ErrorCode : uint32_t {
    NotDefined = 0x8000,
    NotFound = 0x8001,
    AccessDenied = 0x8002,
    DiskFull = 0x8003,
    Illegal = 0x8004,
    PacketNumberWrong = 0x8005,
    AlreadyExists = 0x8006,
    NoUser = 0x8007,
    BootstrapOnly = 0x8008,
    NotInBootstrap = 0x8009,
    NoRights = 0x800A,
    ProgramError = 0x800B,
    InvalidChecksum = 0x800C,
    InvalidFirmware = 0x800D,
    NoFileToRead = 0x800F,
    FileHeaderError = 0x8010,
    FlashError = 0x8011,
};

// FoE header: opcode (1 byte), reserved (1), then a 32-bit field: password (READ/WRITE), packet number
// (DATA/ACK/BUSY: done/entire) or error code (ERR); the file name, data or error text follows.
constexpr std::size_t kFoeHeaderSize = 6;

// The readable text sent with an FoE ERR packet ("Not defined" for codes the standard does not name).
constexpr std::string_view error_text(uint32_t code) {
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
constexpr std::string_view error_text(ErrorCode code) {
    return error_text(static_cast<uint32_t>(code));
}

}  // namespace foe
