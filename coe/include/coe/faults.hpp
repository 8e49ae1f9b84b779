#pragma once
// Deliberate CoE faults for testing conformance tools (`ecat-slave --fault`, docs/decisions/faults.md).
// Each flag breaks exactly one observable behaviour the way a faulty slave would; all are off by default
// and cost one bool test where they apply.
namespace coe {

struct CoeFaults {
    bool ca_no_padding = false;     // complete-access upload from subindex 0: subindex 0 as 8 bits, not 16
    bool info_error_short = false;  // SDO information error reply 2 bytes short (abort code cut to 16 bits)
    bool abort_missing_object = false;    // missing object aborted with 0x06090011 instead of 0x06020000
    bool download_abort_command = false;  // the abort of a failed download echoes the request's command byte
    bool pdo_map_in_safe_op = false;      // PDO mapping/assignment objects written in Safe-Op (no 0x08000022)
    bool download_toggle_unchecked = false;  // download segments with a wrong toggle bit are taken
    bool upload_toggle_stuck = false;        // upload segment responses always carry toggle 0
    bool expedited_size_wrong = false;       // expedited upload responses say 4 bytes whatever the size
    bool read_only_write_confirmed = false;  // a download to a read-only entry is confirmed (value unchanged)
    bool value_range_unchecked = false;  // a value outside the entry's limits is confirmed (value unchanged)
    bool info_entry_wrong_type = false;  // entry descriptions of subindex > 0 say UNSIGNED8 (0x0005)
};

}  // namespace coe
