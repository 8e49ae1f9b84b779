#pragma once
// The CoE vocabulary (ETG.1000.6 §5.6.2, CiA 301): the CoE header and its services, the SDO command
// specifiers, the SDO abort codes with their texts and the SDO information opcodes. SDO server (coe/) and
// SDO client (tools/lib/master) both take them from here.
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace coe {

// CoE header (2 bytes): bits 8:0 number, bits 15:12 service.
enum class Service : uint8_t {
    Emergency = 1,
    SdoRequest = 2,
    SdoResponse = 3,
    TxPdo = 4,
    RxPdo = 5,
    TxPdoRemote = 6,
    RxPdoRemote = 7,
    SdoInfo = 8,
};
constexpr std::size_t kCoeHeaderSize = 2;
constexpr uint16_t coe_header(Service s, uint16_t number = 0) {
    return static_cast<uint16_t>((number & 0x01FF) | (static_cast<uint16_t>(s) << 12));
}
constexpr Service service_of(uint16_t header) {
    return static_cast<Service>(header >> 12);
}

// SDO command byte (after the CoE header): bits 7:5 command specifier.
namespace sdo {
// Client command specifiers (request).
constexpr uint8_t kCcsDownloadSegment = 0;
constexpr uint8_t kCcsDownloadInitiate = 1;
constexpr uint8_t kCcsUploadInitiate = 2;
constexpr uint8_t kCcsUploadSegment = 3;
constexpr uint8_t kCcsAbort = 4;
// Server command specifiers (response).
constexpr uint8_t kScsUploadSegment = 0;
constexpr uint8_t kScsDownloadSegment = 1;
constexpr uint8_t kScsUploadInitiate = 2;
constexpr uint8_t kScsDownloadInitiate = 3;
constexpr uint8_t command_specifier(uint8_t command) {
    return command >> 5;
}
// The command byte's bits 7:5 for a specifier.
constexpr uint8_t cs(uint8_t specifier) {
    return static_cast<uint8_t>(specifier << 5);
}
// Command byte bits.
constexpr uint8_t kCmdCompleteAccess = 0x10;  // initiate: complete access
constexpr uint8_t kCmdToggle = 0x10;          // segments: toggle
constexpr uint8_t kCmdExpedited = 0x02;
constexpr uint8_t kCmdSizeIndicated = 0x01;
constexpr uint8_t kCmdLastSegment = 0x01;
// Sizes.
constexpr std::size_t kSdoFrame = 10;    // CoE header 2 + command 1 + index 2 + subindex 1 + data 4
constexpr std::size_t kSegmentHead = 3;  // CoE header 2 + command 1
}  // namespace sdo

// SDO information opcodes (ETG.1000.6 §5.6.3; byte 2 bits 6:0, bit 7 = more fragments follow).
namespace info {
constexpr uint8_t kOdListReq = 0x01;
constexpr uint8_t kOdListResp = 0x02;
constexpr uint8_t kObjDescReq = 0x03;
constexpr uint8_t kObjDescResp = 0x04;
constexpr uint8_t kEntryDescReq = 0x05;
constexpr uint8_t kEntryDescResp = 0x06;
constexpr uint8_t kError = 0x07;
constexpr uint8_t kIncomplete = 0x80;
constexpr uint8_t kOpcodeMask = 0x7F;
constexpr std::size_t kHead = 6;  // CoE header 2 + opcode 1 + reserved 1 + fragments left 2
// Value info bits of an entry description request.
constexpr uint8_t kValueInfoUnit = 0x08;
constexpr uint8_t kValueInfoDefault = 0x10;
constexpr uint8_t kValueInfoMin = 0x20;
constexpr uint8_t kValueInfoMax = 0x40;
}  // namespace info

}  // namespace coe

// SDO abort codes (ETG.1000.6 §5.6.2.7, CiA 301 §7.2.4.3.17).
namespace coe::abort {

constexpr uint32_t ToggleBit = 0x05030000;
constexpr uint32_t Timeout = 0x05040000;
constexpr uint32_t UnknownCommand = 0x05040001;
constexpr uint32_t InvalidBlockSize = 0x05040002;
constexpr uint32_t InvalidSequence = 0x05040003;
constexpr uint32_t CrcError = 0x05040004;
constexpr uint32_t OutOfMemory = 0x05040005;
constexpr uint32_t UnsupportedAccess = 0x06010000;
constexpr uint32_t WriteOnly = 0x06010001;
constexpr uint32_t ReadOnly = 0x06010002;
constexpr uint32_t SubindexZeroFirst = 0x06010003;
constexpr uint32_t CompleteAccessUnsupported = 0x06010004;
constexpr uint32_t ObjectTooLong = 0x06010005;
constexpr uint32_t MappedToRxPdo = 0x06010006;
constexpr uint32_t NoObject = 0x06020000;
constexpr uint32_t NotMappable = 0x06040041;
constexpr uint32_t PdoLength = 0x06040042;
constexpr uint32_t Incompatible = 0x06040043;
constexpr uint32_t InternalIncompatible = 0x06040047;
constexpr uint32_t HardwareError = 0x06060000;
constexpr uint32_t LengthMismatch = 0x06070010;
constexpr uint32_t LengthTooHigh = 0x06070012;
constexpr uint32_t LengthTooLow = 0x06070013;
constexpr uint32_t NoSubindex = 0x06090011;
constexpr uint32_t ValueRange = 0x06090030;
constexpr uint32_t ValueTooHigh = 0x06090031;
constexpr uint32_t ValueTooLow = 0x06090032;
constexpr uint32_t MaxBelowMin = 0x06090036;
constexpr uint32_t ResourceUnavailable = 0x060A0023;
constexpr uint32_t General = 0x08000000;
constexpr uint32_t CannotStore = 0x08000020;
constexpr uint32_t LocalControl = 0x08000021;
constexpr uint32_t WrongState = 0x08000022;
constexpr uint32_t NoDictionary = 0x08000023;
constexpr uint32_t NoData = 0x08000024;

// The text of an abort code ("" for a code not in the table).
constexpr std::string_view text(uint32_t code) {
    switch (code) {
        case ToggleBit:
            return "Toggle bit not changed";
        case Timeout:
            return "SDO protocol timeout";
        case UnknownCommand:
            return "Client/server command specifier not valid or unknown";
        case InvalidBlockSize:
            return "Invalid block size (block mode only)";
        case InvalidSequence:
            return "Invalid sequence number (block mode only)";
        case CrcError:
            return "CRC error (block mode only)";
        case OutOfMemory:
            return "Out of memory";
        case UnsupportedAccess:
            return "Unsupported access to an object";
        case WriteOnly:
            return "Attempt to read a write-only object";
        case ReadOnly:
            return "Attempt to write a read-only object";
        case SubindexZeroFirst:
            return "Subindex cannot be written, SI0 must be 0 for write access";
        case CompleteAccessUnsupported:
            return "SDO complete access not supported";
        case ObjectTooLong:
            return "Object length exceeds mailbox size";
        case MappedToRxPdo:
            return "Object mapped to RxPDO, SDO download blocked";
        case NoObject:
            return "Object does not exist in the object dictionary";
        case NotMappable:
            return "Object cannot be mapped into the PDO";
        case PdoLength:
            return "Number and length of mapped objects would exceed PDO length";
        case Incompatible:
            return "General parameter incompatibility";
        case InternalIncompatible:
            return "General internal incompatibility in the device";
        case HardwareError:
            return "Access failed due to a hardware error";
        case LengthMismatch:
            return "Data type does not match, length of service parameter does not match";
        case LengthTooHigh:
            return "Data type does not match, length too high";
        case LengthTooLow:
            return "Data type does not match, length too low";
        case NoSubindex:
            return "Subindex does not exist";
        case ValueRange:
            return "Value range of parameter exceeded";
        case ValueTooHigh:
            return "Value written too high";
        case ValueTooLow:
            return "Value written too low";
        case MaxBelowMin:
            return "Maximum value is less than minimum value";
        case ResourceUnavailable:
            return "Resource not available";
        case General:
            return "General error";
        case CannotStore:
            return "Data cannot be transferred or stored to the application";
        case LocalControl:
            return "Data cannot be transferred or stored because of local control";
        case WrongState:
            return "Data cannot be transferred or stored because of the present device state";
        case NoDictionary:
            return "Object dictionary not present";
        case NoData:
            return "No data available";
        default:
            return "";
    }
}

}  // namespace coe::abort
