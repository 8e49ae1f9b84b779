#pragma once
// Deliberate CiA 402 faults for testing conformance tools (`ecat-slave --fault`, docs/decisions/faults.md).
// Each flag breaks exactly one observable behaviour the way a faulty drive would; all are off by default.
namespace drive {

struct AxisFaults {
    bool quick_stop_ignored =
        false;  // the quick stop command in Operation enabled is ignored (no transition 11)
    bool fault_reset_ignored = false;  // the fault reset edge (controlword bit 7) does not leave Fault
    bool mode_display_stuck = false;   // 0x6061 keeps showing the first mode, whatever 0x6060 selects
};

}  // namespace drive
