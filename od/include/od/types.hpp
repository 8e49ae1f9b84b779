#pragma once
// Basic vocabulary of the object model: CANopen data types, object codes, access bits, results.
#include <cstdint>
#include <string_view>

#include "esc/wire/al.hpp"

namespace od {

// CANopen / ETG.1000.6 data type codes.
enum class DataType : uint16_t {
    Boolean = 0x0001,
    Integer8 = 0x0002,
    Integer16 = 0x0003,
    Integer32 = 0x0004,
    Unsigned8 = 0x0005,
    Unsigned16 = 0x0006,
    Unsigned32 = 0x0007,
    Real32 = 0x0008,
    VisibleString = 0x0009,
    OctetString = 0x000A,
    UnicodeString = 0x000B,
    Integer24 = 0x0010,
    Real64 = 0x0011,
    Integer64 = 0x0015,
    Unsigned24 = 0x0016,
    Unsigned64 = 0x001B,
    PdoMapping = 0x0021,
    Identity = 0x0023,
    SyncManagerParameter = 0x0029,  // not a scalar: used as the type of RECORD objects
    // Bit strings of 1..8 bits (ETG.1000.6 BIT1..BIT8, the ESI's BIT2, BIT3, ...): the status bits and
    // small enumerations of IO terminals, packed into PDOs without padding.
    Bit1 = 0x0030,
    Bit2 = 0x0031,
    Bit3 = 0x0032,
    Bit4 = 0x0033,
    Bit5 = 0x0034,
    Bit6 = 0x0035,
    Bit7 = 0x0036,
    Bit8 = 0x0037,
};

enum class ObjectCode : uint8_t { Var = 0x07, Array = 0x08, Record = 0x09 };

// The process-data direction of a PDO mapping object (the PDO's: Rx = outputs, master -> slave; Tx = inputs)
// or of a SyncManager's PDO assignment object (its SM's). None: not a process-data object.
enum class PdoDirection : uint8_t { None, Rx, Tx };

// The PDO assignment objects, 0x1C10 + n for SM n (ETG.1000.6, SyncManager PDO assignment).
constexpr bool is_assignment_index(uint16_t index) {
    return index >= 0x1C10 && index <= 0x1C2F;
}
// The direction ETG.1000.6's standard index ranges give: RxPDO mapping 0x1600-0x17FF and SM2's assignment
// 0x1C12, TxPDO mapping 0x1A00-0x1BFF and SM3's assignment 0x1C13. Only a default for a declaration that
// states no direction (Object::direction): vendors' devices put PDOs elsewhere (RxPdo 0x1A00 on Beckhoff's
// evaluation boards, TxPdo 0x1C00 on EL1262) and the direction then comes from their ESI.
constexpr PdoDirection standard_pdo_direction(uint16_t index) {
    if ((index >= 0x1600 && index <= 0x17FF) || index == 0x1C12) return PdoDirection::Rx;
    if ((index >= 0x1A00 && index <= 0x1BFF) || index == 0x1C13) return PdoDirection::Tx;
    return PdoDirection::None;
}

// EtherCAT AL states, for state-dependent access ("rw only in Pre-Op"): the AL vocabulary's
// (esc/wire/al.hpp).
using AlState = esc::AlState;

// Access and flag bits exactly as the SDO information "entry description" ObjectAccess word (ETG.1000.6):
namespace access {
constexpr uint16_t ReadPreOp = 0x0001;
constexpr uint16_t ReadSafeOp = 0x0002;
constexpr uint16_t ReadOp = 0x0004;
constexpr uint16_t WritePreOp = 0x0008;
constexpr uint16_t WriteSafeOp = 0x0010;
constexpr uint16_t WriteOp = 0x0020;
constexpr uint16_t RxPdo = 0x0040;     // mappable into an RxPDO (master -> slave)
constexpr uint16_t TxPdo = 0x0080;     // mappable into a TxPDO (slave -> master)
constexpr uint16_t Backup = 0x0100;    // stored by "store parameters" (0x1010)
constexpr uint16_t Settings = 0x0200;  // a setting (startup parameter)

constexpr uint16_t RO = ReadPreOp | ReadSafeOp | ReadOp;
constexpr uint16_t WO = WritePreOp | WriteSafeOp | WriteOp;
constexpr uint16_t RW = RO | WO;
constexpr uint16_t RW_PreOp = RO | WritePreOp;  // writable only in Pre-Operational
constexpr uint16_t ReadMask = RO;
constexpr uint16_t WriteMask = WO;
}  // namespace access

// Why an access failed. Each maps to exactly one SDO abort code (coe/) and is what the drive sees too.
enum class Status : uint8_t {
    Ok,
    NoObject,           // 0x06020000 object does not exist
    NoSubindex,         // 0x06090011 subindex does not exist
    ReadOnly,           // 0x06010002 attempt to write a read-only object
    SubindexZeroFirst,  // 0x06010003 subindex cannot be written, subindex 0 must be 0 for write access
    WriteOnly,          // 0x06010001 attempt to read a write-only object
    LengthMismatch,     // 0x06070010 data type does not match, length of service parameter does not match
    LengthTooHigh,      // 0x06070012
    LengthTooLow,       // 0x06070013
    ValueTooHigh,       // 0x06090031
    ValueTooLow,        // 0x06090032
    InvalidValue,       // 0x06090030 value range of parameter exceeded
    MaxBelowMin,        // 0x06090036
    NotMappable,        // 0x06040041 object cannot be mapped to the PDO
    PdoLengthExceeded,  // 0x06040042 number and length of objects to be mapped would exceed PDO length
    Incompatible,       // 0x06040043 general parameter incompatibility
    WrongState,         // 0x08000022 data cannot be transferred/stored because of the present device state
    CannotStore,        // 0x08000020 data cannot be transferred or stored
    HardwareError,      // 0x06060000 access failed due to a hardware error
    OutOfMemory,        // 0x05040005
    GeneralError,       // 0x08000000
};

std::string_view to_string(Status s);
std::string_view to_string(DataType t);

// Bit size of a scalar data type (0 for strings and structured types). constexpr, so a table of a product
// can be checked at compile time.
constexpr uint16_t bit_size(DataType t) {
    switch (t) {
        case DataType::Boolean:
            return 1;
        case DataType::Integer8:
        case DataType::Unsigned8:
            return 8;
        case DataType::Integer16:
        case DataType::Unsigned16:
            return 16;
        case DataType::Integer32:
        case DataType::Unsigned32:
        case DataType::Real32:
            return 32;
        case DataType::Integer64:
        case DataType::Unsigned64:
        case DataType::Real64:
            return 64;
        case DataType::Integer24:
        case DataType::Unsigned24:
            return 24;
        case DataType::Bit1:
        case DataType::Bit2:
        case DataType::Bit3:
        case DataType::Bit4:
        case DataType::Bit5:
        case DataType::Bit6:
        case DataType::Bit7:
        case DataType::Bit8:
            return static_cast<uint16_t>(static_cast<uint16_t>(t) - 0x002F);
        default:
            return 0;
    }
}

constexpr bool is_signed(DataType t) {
    return t == DataType::Integer8 || t == DataType::Integer16 || t == DataType::Integer24 ||
           t == DataType::Integer32 || t == DataType::Integer64;
}

constexpr bool is_real(DataType t) {
    return t == DataType::Real32 || t == DataType::Real64;
}

constexpr bool is_string(DataType t) {
    return t == DataType::VisibleString || t == DataType::OctetString || t == DataType::UnicodeString;
}

}  // namespace od
