#pragma once
// The master's view of the diagnosis history 0x10F3 (ETG.1020; layout as docs/decisions/coe.md and
// coe/diagnosis.hpp): decoding of the message bytes, the order of the ring, readable text. Pure functions,
// tested in tests/master/diag_test.cpp; `ecatctl diag` reads the object by SDO and prints with these.
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace master {

inline constexpr uint16_t kDiagIndex = 0x10F3;
inline constexpr uint8_t kDiagFirstMessage = 6;  // messages live in subindex 6..5+max, a ring

// :05 flag bits.
inline constexpr uint16_t kDiagFlagEmergency = 0x0001;
inline constexpr uint16_t kDiagFlagNoInfo = 0x0002;
inline constexpr uint16_t kDiagFlagNoWarning = 0x0004;
inline constexpr uint16_t kDiagFlagNoError = 0x0008;
inline constexpr uint16_t kDiagFlagAcknowledgeMode = 0x0010;
inline constexpr uint16_t kDiagFlagOverflow = 0x0020;

struct DiagParameter {
    uint16_t flags = 0;  // b15:12 kind (0 CoE data type in b11:0, 1 byte array, 2 ASCII, 3 Unicode), b11:0
    std::vector<uint8_t> data;
    unsigned kind() const { return flags >> 12; }
};

struct DiagEntry {
    uint8_t subindex = 0;
    uint32_t code = 0;
    uint8_t type = 0;  // 0 info, 1 warning, 2 error (flags b3:0)
    bool local_time = false;
    uint16_t text_id = 0;
    uint64_t timestamp_ns = 0;
    std::vector<DiagParameter> params;
    bool truncated = false;  // the flags announce more parameters than the bytes hold

    // ETG.1020 emergency-derived diag code: 0xE800 in the low word, the CiA 301/402 error code above.
    bool from_emergency() const { return (code & 0xFFFF) == 0xE800; }
    uint16_t emergency_code() const { return static_cast<uint16_t>(code >> 16); }
};

// The subindices :01..:05.
struct DiagHeader {
    uint8_t max_messages = 0;
    uint8_t newest = 0;        // 0 = none
    uint8_t acknowledged = 0;  // 0 = none
    bool new_available = false;
    uint16_t flags = 0;
};

// One message entry's bytes; nullopt for an empty slot or fewer than the 16 fixed bytes.
std::optional<DiagEntry> decode_diag_message(std::span<const uint8_t> bytes, uint8_t subindex = 0);

// Subindices holding messages, oldest first (or newest first), walking the ring backwards from the newest.
// only_new: only those after the acknowledged one (all when nothing is acknowledged).
std::vector<uint8_t> diag_message_order(const DiagHeader& h, bool newest_first, bool only_new);

std::string_view diag_type_name(uint8_t type);  // "info", "warning", "error"; "unknown" otherwise
// Size in bytes of a CoE basic data type used as a parameter value (0 if not a fixed-size basic type).
std::size_t diag_value_size(uint16_t data_type);
// "0x0000002a (42)", "\"text\"", "bytes 01 02 03" ...
std::string format_diag_param(const DiagParameter& p);
// Name lookup for emergency error codes (the device's own table), nullptr or an empty answer: not known.
using ErrorNameLookup = std::string_view (*)(uint16_t code);
// CiA 301 error code class ("current", "voltage", ...), "" for 0x0000.
std::string_view emergency_class_name(uint16_t code);
// Readable text of a message: the device's text for its text id (with the error's name after it for an
// emergency-derived code), else the device's error name for an emergency-derived code (else its CiA 301
// class), the ASCII parameter of a manufacturer message, "text id 0x...." otherwise.
// texts: the device's text ids (ETG.1020 text id -> text, e.g. from its ESI DiagMessages); without it, or for
// an id it does not know, "text id 0x....". A text that is the error's name is not followed by it again.
using TextIdLookup = std::function<std::string_view(uint16_t text_id)>;
std::string diag_text(const DiagEntry& e, ErrorNameLookup lookup = nullptr,
                      const TextIdLookup& texts = nullptr);
// DC system time in ns -> "12.345678901 s".
// A message's time stamp: DC system time set to the wall time as "2026-11-27 02:46:36.600 UTC", otherwise
// (local time, or a DC clock a year or less past its epoch) the time since the clock started,
// "[Nd ]hh:mm:ss.mmm".
std::string format_diag_time(uint64_t ns, bool local = false);
// "emergency, acknowledge mode, overflow, no info" ...; "none" for 0.
std::string format_diag_flags(uint16_t flags);
// One line: ":07  12.345678901 s  error    0x8611e800  Following error  params: ..."
// A text parameter that the text shown already says (it was taken from it, or it is the start of the
// device's name for the code, cut to the message's room) is not repeated among the parameters.
std::string format_diag_line(const DiagEntry& e, ErrorNameLookup lookup = nullptr,
                             const TextIdLookup& texts = nullptr);

}  // namespace master
