#pragma once
// Deliberate firmware faults of the state machine, mailbox and process data, for testing conformance tools
// (`ecat-slave --fault`, docs/decisions/faults.md). Each flag breaks exactly one observable behaviour the
// way a faulty slave would; all are off by default and cost one bool test where they apply.
namespace ecat {

struct MailboxFaults {
    bool counter_ignored = false;              // a request repeated with the same counter is executed again
    bool repeat_ignored = false;               // the repeat request (SM1 activate bit 1) is never served
    bool unsupported_protocol_silent = false;  // no mailbox error reply (0x0002) for an unsupported type
};

struct StackFaults {
    MailboxFaults mailbox;
    bool bootstrap_refused = false;       // Init -> Bootstrap refused (0x0013) although FoE is announced
    bool watchdog_ignored = false;        // the process-data watchdog never takes Op back to Safe-Op (0x001B)
    bool al_code_missing = false;         // a refused transition sets the error bit but leaves 0x0134 at 0
    bool invalid_request_silent = false;  // an invalid transition (e.g. Init -> Op) is ignored, no 0x0011
    bool error_ack_ignored = false;       // the acknowledge bit does not clear the error (only Init does)
    bool sm2_length_unchecked = false;    // Pre-Op -> Safe-Op accepts an SM2 length != the RxPDO size
    bool inputs_op_only = false;          // TxPDO inputs are written only in Op (not valid in Safe-Op)
    bool outputs_in_safe_op = false;      // RxPDO outputs are applied in Safe-Op already
};

}  // namespace ecat
