#pragma once
// Text in and out for ecatctl: number parsing, hex dumps, typed register values. Pure functions, tested
// in tests/master/ecatctl_format_test.cpp.
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace ecatctl {

// How a process-data run ended when not in the state asked for: "ended in SAFEOP+ERR, not OP, AL status
// code 0x001b (Sync manager watchdog)"; an empty state name: the slave gave no AL status.
std::string end_state_text(std::string_view state, bool error, uint16_t code, std::string_view code_name,
                           std::string_view wanted);

// Exit codes (also listed in `ecatctl --help`).
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;       // anything not listed below
inline constexpr int kExitUsage = 2;         // bad command line, bad input file
inline constexpr int kExitNoInterface = 3;   // the interface does not exist or is down
inline constexpr int kExitNoPrivileges = 4;  // raw sockets need CAP_NET_RAW
inline constexpr int kExitNoSlave = 5;       // no slave answered
inline constexpr int kExitProtocol = 6;  // a slave answered, but not as expected (working counter, SII, AL)

// Decimal, 0x-hex, 0b-binary; nullopt if not a whole number within max.
std::optional<uint64_t> parse_number(std::string_view text, uint64_t max);

enum class ValueType { U8, U16, U32, U64, I8, I16, I32, I64, F32, F64 };  // F32/F64: REAL32/REAL64
std::optional<ValueType> parse_type(std::string_view name);
// The value type of a CoE basic data type code (ETG.1000.6: 0x0001 BOOLEAN .. 0x001B UNSIGNED64); nullopt
// for strings and structured types.
std::optional<ValueType> value_type_of(uint16_t coe_type);
std::size_t type_size(ValueType t);
// Little-endian bytes -> "0x1234 (4660)" (REAL32/REAL64: the number, e.g. "1.5"); data.size() must be
// type_size(t).
std::string format_value(ValueType t, std::span<const uint8_t> data);
// Text -> little-endian bytes of the type (negative numbers allowed for signed types); nullopt if out of
// range.
std::optional<std::vector<uint8_t>> encode_value(ValueType t, std::string_view text);

// 16 bytes per line: "0x0130: 02 00 00 00 ...", addresses starting at base.
std::string hex_dump(uint32_t base, std::span<const uint8_t> data);

}  // namespace ecatctl
