#pragma once
// Deliberate FoE faults for testing conformance tools (`ecat-slave --fault`, docs/decisions/faults.md).
// Each flag breaks exactly one observable behaviour the way a faulty slave would; all are off by default.
namespace foe {

struct FoeFaults {
    bool password_ignored = false;  // a write with a wrong password is accepted (no error 0x800A)
    bool any_file_name = false;     // a write to an unknown file name is accepted (no error 0x8001)
};

}  // namespace foe
