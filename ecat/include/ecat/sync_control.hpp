#pragma once
// Sync handling of ecat::Stack: which synchronisation runs (free run, SM-synchronous, DC SYNC0/SYNC1), as
// negotiated at Pre-Op -> Safe-Op from 0x1C32/0x1C33 and the DC activation (ETG.1020 "Synchronization",
// ETG.1000.6 0x1C32/0x1C33), the SYNC0 events and their loss, the free-run timer, the SM2/SYNC0 latency
// samples and the 0x1C32/0x1C33 diagnostic counters. It owns this state alone; the cycle asks it when to run.
#include <cstdint>

#include "ecat/stack_context.hpp"

namespace ecat {

// Sync mode values of 0x1C32:01 / 0x1C33:01 (ETG.1020, Synchronization; ETG.1000.6 0x1C32).
enum class SyncMode : uint16_t { FreeRun = 0, SmSync = 1, DcSync0 = 2, DcSync1 = 3, SmSync2 = 0x22 };

class SyncControl {
  public:
    explicit SyncControl(StackContext& ctx) : ctx_(ctx) {}
    // Takes its hook off the dictionary, which may outlive the stack.
    ~SyncControl();
    SyncControl(const SyncControl&) = delete;
    SyncControl& operator=(const SyncControl&) = delete;

    // 0x1C00 from the description, the listener on master writes of 0x1C32:01, the counter handles.
    void init_objects();
    // 0x1C00:n+1 (SM n's type) as the master left it; fallback if absent.
    uint64_t sm_type(unsigned n, uint64_t fallback) const;
    bool has_sm_type_object() const;
    // Pre-Op -> Safe-Op: chooses the sync mode and cycle from 0x1C32/0x1C33 and 0x0980..0x09A3; an AL
    // status code if the configuration cannot run, else 0 (and 0x1C32/0x1C33 then say what runs).
    uint16_t configure();

    void pre_op_entered() { master_wrote_sync_mode_ = false; }
    void op_entered();            // 0x1C32/0x1C33:20 sync error cleared
    void start(uint64_t now_ns);  // process data starts (Safe-Op entered)
    void reset();                 // ESC reset: back to free run, nothing negotiated

    SyncMode mode() const { return sync_mode_; }
    bool dc() const { return sync_mode_ == SyncMode::DcSync0 || sync_mode_ == SyncMode::DcSync1; }
    uint32_t cycle_ns() const { return cycle_ns_; }
    bool sync0_seen() const { return sync0_seen_; }

    // Free run: whether the next cycle is due; advance() after running it (no backlog is run).
    bool free_run_due(uint64_t now_ns) const { return now_ns >= next_cycle_ns_; }
    void free_run_advance(uint64_t now_ns);

    // DC: what the SYNC0 events (AL event bit, 0x0990 moving on) since the last poll ask of the cycle.
    enum class Sync0 { None, RunCycle, Lost };
    // op: the stack is in Op; missed: Op with outputs but none new since the last SYNC0.
    Sync0 sync0_events(uint32_t events, uint64_t now_ns, bool op, bool has_outputs, bool new_outputs);

    // SM-synchronous: one latency sample if 0x09F0 moved on since the last cycle.
    void sample_sm2_latency();

    // Time at which poll() must run for the sync in the process-data states (UINT64_MAX: none).
    uint64_t next_deadline_ns(bool op) const;

  private:
    uint64_t get_u(uint16_t index, uint8_t sub, uint64_t fallback) const;
    void set_u(uint16_t index, uint8_t sub, uint64_t value);
    // period: the SYNC0 cycle time 0x09A0 read with next_sync0 (0: SYNC0 not running, no sample).
    void sample_sync0_latency(uint64_t sys, uint64_t next_sync0, uint32_t period);
    uint64_t sync0_loss_ns() const;

    StackContext& ctx_;
    SyncMode sync_mode_ = SyncMode::FreeRun;
    bool master_wrote_sync_mode_ = false;
    bool internal_write_ = false;
    uint32_t cycle_ns_ = 0;
    uint64_t next_cycle_ns_ = 0;
    uint64_t last_sync0_ns_ = 0;
    uint64_t next_sync0_sys_ = 0;              // 0x0990 as last read (system time of the next SYNC0)
    uint64_t sync0_deadline_ns_ = UINT64_MAX;  // when the next SYNC0 is due, in poll() time
    bool sync0_seen_ = false;                  // a SYNC0 pulse of the current activation came
    bool was_running_ = false;                 // SYNC0 activated (0x0981 cyclic + SYNC0) at the last look
    od::Ref<uint16_t> sm_missed_[2];
    od::Ref<uint16_t> cycle_exceeded_[2];
    od::Ref<uint8_t> sync_error_[2];
    uint32_t last_sm_change_time_ = 0;  // 0x09F0 as read at the last SM-synchronous cycle
};

}  // namespace ecat
