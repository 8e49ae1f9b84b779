#pragma once
// Deliberate ESC faults for testing conformance tools (`ecat-slave --fault`, docs/decisions/faults.md).
// Each flag breaks exactly one observable behaviour the way a faulty slave would; all are off by default
// and cost one bool test where they apply.
namespace esc {

struct EscFaults {
    bool wkc_aprd = false;          // APRD answers with working counter 2 instead of 1
    bool alias_ignored = false;     // FPxx never match the station alias (0x0012), even with 0x0100 bit 24
    bool fprd_any_address = false;  // FPRD is answered whatever its station address
    bool source_mac_unchanged = false;  // bit 1 of the first source MAC byte is not set in returned frames
    bool sii_checksum_wrong = false;    // SII reads return word 7 (checksum of words 0-6) wrong
    bool dc_time_frozen = false;        // ECAT reads of the system time 0x0910 do not advance
    bool sync0_never = false;           // cyclic operation activates (0x0981) but SYNC0 pulses never come
};

}  // namespace esc
