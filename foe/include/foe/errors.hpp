#pragma once
// FoE opcodes and error codes (ETG.1000.6, FoE).
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

// The readable text sent with an FoE ERR packet ("Not defined" for codes the standard does not name).
std::string_view error_text(ErrorCode code);
std::string_view error_text(uint32_t code);

}  // namespace foe
