#pragma once
// The EtherCAT state machine (ESM) of ecat::Stack (ETG.1000.6 "EtherCAT State Machine"): AL control
// (0x0120) requests, the transition table, the checks each transition up makes (mailbox and process-data
// SyncManagers, sync configuration, watchdog), the wait of Safe-Op -> Op for outputs and SYNC0, and the AL
// status (0x0130), AL status code (0x0134) and device identification. It owns the AL state and error; it
// starts and stops the mailbox and, through the Cycle, the process data.
#include <cstdint>

#include "ecat/stack_context.hpp"

namespace ecat {

class SyncControl;
class Cycle;

class StateMachine {
  public:
    StateMachine(StackContext& ctx, SyncControl& sync, Cycle& cycle)
        : ctx_(ctx), sync_(sync), cycle_(cycle) {}
    StateMachine(const StateMachine&) = delete;
    StateMachine& operator=(const StateMachine&) = delete;

    // AL event "AL control": reads 0x0120 (acknowledging the event) and serves the request.
    void handle_al_control(uint64_t now_ns);
    // A Safe-Op -> Op request waiting for outputs / SYNC0: completes or times out.
    void try_complete_op(uint64_t now_ns);
    // The master changed an SM while process data runs: falls back if SM2/SM3 no longer fit.
    void check_process_data_sms(uint64_t now_ns);
    // Falls back to `to` (if lower) with the error indication and `code`, reported as a local error.
    void fall_back(od::AlState to, uint16_t code, uint64_t now_ns);
    // ESC reset: Init, no error, no identification, no pending request.
    void reset_to_init(uint64_t now_ns);
    // Writes AL status (0x0130) and AL status code (0x0134).
    void write_status();

    // Whether the application must restart (Boot -> Init, ESC reset); clears the request.
    bool take_restart();
    void request_restart() { restart_pending_ = true; }

    od::AlState state() const { return state_; }
    bool error() const { return error_; }
    uint16_t code() const { return code_; }
    bool op_pending() const { return op_pending_; }
    uint64_t op_deadline_ns() const { return op_deadline_ns_; }
    void set_op_wait_timeout_ns(uint64_t ns) { op_wait_timeout_ns_ = ns; }
    // ESC configuration 0x0141 bit 0: the ESC follows AL control itself, no state of the stack's own.
    bool device_emulation() const;

  private:
    void request(od::AlState to, uint64_t now_ns);
    void request_checked(od::AlState to, uint64_t now_ns);  // request() without the refusal report
    void follow(od::AlState to, uint64_t now_ns);           // device emulation: the state the ESC took
    uint16_t check_mailbox(const od::MailboxLayout& layout, uint16_t code);
    uint16_t check_bootstrap() const;
    uint16_t check_module_idents() const;
    uint16_t check_pre_op_to_safe_op();
    uint16_t check_watchdog();
    bool op_conditions_met();
    uint8_t expected_control(unsigned n, uint8_t fallback) const;
    const od::SyncManagerDefault* sm_default(unsigned n) const;
    void go(od::AlState to, uint64_t now_ns);
    void refuse(uint16_t code);

    StackContext& ctx_;
    SyncControl& sync_;
    Cycle& cycle_;

    od::AlState state_ = od::AlState::Init;
    bool error_ = false;
    bool id_loaded_ = false;
    uint16_t code_ = 0;
    uint16_t id_value_ = 0;

    // Safe-Op -> Op waiting for outputs / SYNC0.
    bool op_pending_ = false;
    uint64_t op_deadline_ns_ = 0;
    uint64_t op_wait_timeout_ns_ = 1'000'000'000;

    bool restart_pending_ = false;
};

}  // namespace ecat
