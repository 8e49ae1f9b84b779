#pragma once
// SDO abort codes (ETG.1000.6 / CiA 301 SDO abort codes) and the one mapping from od::Status.
#include <cstdint>

#include "od/types.hpp"

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

}  // namespace coe::abort

namespace coe {

// The abort code the standard names for an object-model result (0 for Ok).
uint32_t abort_code(od::Status s);

}  // namespace coe
