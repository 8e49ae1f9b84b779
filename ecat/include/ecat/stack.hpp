#pragma once
// The slave stack core ("firmware"): EtherCAT state machine (ESM), mailbox, process data and the sync
// cycle. It reaches the ESC only through esc::Pdi (register reads/writes with PDI side effects) and,
// optionally, the PDI interrupt line, so the same code could drive an ESC chip over SPI.
//
// The runtime calls poll(now) after every burst of frames and when next_deadline_ns() has passed, each
// time after esc::Esc::tick() (so SYNC0 and the watchdogs are up to date), with the ESC's time base.
// pdi, dictionary, description and application must outlive the Stack, and the dictionary must not be
// replaced while it exists (the process-data plan and the 0x1C32/0x1C33 counters point into its values).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <vector>

#include "ecat/al_status.hpp"
#include "ecat/application.hpp"
#include "ecat/event_sink.hpp"
#include "ecat/faults.hpp"
#include "ecat/latency.hpp"
#include "ecat/mailbox.hpp"
#include "ecat/mailbox_handler.hpp"
#include "ecat/process_data.hpp"
#include "esc/pdi.hpp"
#include "od/device.hpp"
#include "od/dictionary.hpp"

namespace ecat {

// Sync mode values of 0x1C32:01 / 0x1C33:01 (ethercat-protocol.md §11.5).
enum class SyncMode : uint16_t { FreeRun = 0, SmSync = 1, DcSync0 = 2, DcSync1 = 3, SmSync2 = 0x22 };

struct StackStats {
    uint64_t transitions = 0;  // successful AL state changes
    uint64_t refused = 0;      // refused requests (error flag set)
    uint64_t cycles = 0;       // application cycles run
    uint64_t sync0_events = 0;
    uint64_t sm_events_missed = 0;   // DC: SYNC0 without new outputs since the last one (Op)
    uint64_t cycles_exceeded = 0;    // DC: SYNC0 periods that passed without a cycle
    uint64_t watchdog_expiries = 0;  // process-data watchdog events seen
    uint64_t esc_resets = 0;         // ESC resets (0x0040/0x0041) the stack restarted after
    // DC: how late each application cycle started after its SYNC0 pulse, against the DC system time:
    // 0x0910 read at the cycle start minus the pulse's system time (next pulse 0x0990 - SYNC0 cycle 0x09A0).
    LatencyHistogram sync0_latency;
    // SM-synchronous: from the ECAT-side SM buffer change (0x09F0, local time, 32 bit) to the cycle start
    // (local time = 0x0910 - offset 0x0920). Only samples where 0x09F0 changed since the last cycle count,
    // so an ESC that does not latch 0x09F0 leaves this empty rather than wrong.
    LatencyHistogram sm2_latency;
};

// Adds the counts and latency samples of `more` to `total` (a run's figures over several Stack instances).
void add_stats(StackStats& total, const StackStats& more);

// The statistics as "stack.<name> <value>" lines (latencies in ns), for logs and benchmark scripts.
void print_stats(std::ostream& out, const StackStats& stats);

class Stack {
  public:
    // The PDI interrupt line (esc::Esc::irq() or a GPIO); optional. When given, poll() skips its
    // register reads while the line is low and no deadline is due.
    using IrqLine = std::function<bool()>;

    Stack(esc::Pdi& pdi, od::Dictionary& dictionary, const od::DeviceDescription& description,
          Application& application, IrqLine irq = {});
    // Takes its hooks off the dictionary, which may outlive the stack (a firmware restart).
    ~Stack();
    Stack(const Stack&) = delete;
    Stack& operator=(const Stack&) = delete;

    void add_handler(MailboxHandler& handler) { mailbox_.add_handler(handler); }

    // Reads the AL event request register (0x0220) and reacts: AL control, SM events, SYNC0, watchdog,
    // mailbox, process-data cycle, timers. An ESC reset (0x0040/0x0041, seen through the PDI as the lost
    // register set-up) restarts the stack as a reset of the firmware behind the ESC would: Init, fresh
    // mailbox, transfers dropped, and Application::on_restart().
    void poll(uint64_t now_ns);
    // Time at which poll() must run again even if no frame arrives; UINT64_MAX if nothing is pending.
    uint64_t next_deadline_ns() const;

    // Application-detected error (e.g. a fatal device fault): sets the error indication with the code
    // and falls back to fallback if that is lower than the current state.
    void local_error(uint16_t code, od::AlState fallback);

    od::AlState state() const { return state_; }
    bool error() const { return error_; }
    uint16_t status_code() const { return code_; }
    SyncMode sync_mode() const { return sync_mode_; }
    const StackStats& stats() const { return stats_; }
    // print_stats() of stats(); the runtime prints it at exit (slave::FirmwareAdapter forwards it).
    void report(std::ostream& out) const { print_stats(out, stats_); }
    const Mailbox& mailbox() const { return mailbox_; }
    // The outgoing mailbox, for spontaneous messages (e.g. CoE emergencies from the application).
    Mailbox& mailbox() { return mailbox_; }
    const ProcessData& process_data() const { return pd_; }

    // Testing aid: deliberate deviations (ecat/faults.hpp); none by default.
    void set_faults(const StackFaults& faults) {
        faults_ = faults;
        mailbox_.set_faults(faults.mailbox);
    }

    // How long a Safe-Op -> Op request may wait for the first outputs / the first SYNC0 events.
    void set_op_wait_timeout_ns(uint64_t ns) { op_wait_timeout_ns_ = ns; }
    // Where state changes, refused requests, local errors and watchdog expiries are reported (null: nowhere).
    void set_event_sink(EventSink* sink) { events_ = sink; }
    // Housekeeping period for the mailbox handlers' poll() (transfer timeouts).
    static constexpr uint64_t kHousekeepingNs = 10'000'000;
    // AL event mask written at start: AL control, SYNC0, SM activation, PD watchdog, SM0..SM3.
    static constexpr uint32_t kEventMask = 0x00000F55;

  private:
    struct SmRegs {
        uint16_t start = 0;
        uint16_t length = 0;
        uint8_t control = 0;
        uint8_t status = 0;
        uint8_t activate = 0;
        uint8_t pdi_control = 0;
    };
    SmRegs read_sm(unsigned n);
    uint8_t expected_control(unsigned n, uint8_t fallback) const;
    const od::SyncManagerDefault* sm_default(unsigned n) const;

    bool esc_was_reset();
    void restart_after_esc_reset(uint64_t now_ns);
    void handle_al_control(uint64_t now_ns);
    void request(od::AlState to, uint64_t now_ns);
    void request_checked(od::AlState to, uint64_t now_ns);  // request() without the refusal report
    uint16_t check_mailbox(const od::MailboxLayout& layout, uint16_t code);
    uint16_t check_bootstrap();
    uint16_t check_pre_op_to_safe_op();
    uint16_t check_sync_configuration();
    uint16_t check_watchdog();
    bool op_conditions_met();
    void check_process_data_sms(uint64_t now_ns);
    void try_complete_op(uint64_t now_ns);

    void go(od::AlState to, uint64_t now_ns);
    void refuse(uint16_t code);
    void fall_back(od::AlState to, uint16_t code, uint64_t now_ns);
    void write_status();

    void start_process_data(uint64_t now_ns);
    void stop_process_data();
    void set_sm_pdi_deactivated(unsigned n, bool deactivated);
    void process_data_events(uint32_t events, uint64_t now_ns);
    void run_cycle(uint64_t now_ns, bool copy_outputs);
    void sample_sync0_latency(uint64_t sys, uint64_t next_sync0, bool running);
    void sample_sm2_latency();
    void write_inputs();

    uint64_t get_u(uint16_t index, uint8_t sub, uint64_t fallback) const;
    void set_u(uint16_t index, uint8_t sub, uint64_t value);
    void sync_objects_init();

    esc::Pdi& pdi_;
    od::Dictionary& dict_;
    const od::DeviceDescription& desc_;
    Application& app_;
    EventSink* events_ = nullptr;
    IrqLine irq_;
    Mailbox mailbox_;
    ProcessData pd_;

    od::AlState state_ = od::AlState::Init;
    bool error_ = false;
    bool id_loaded_ = false;
    uint16_t code_ = 0;
    uint16_t id_value_ = 0;

    // Safe-Op -> Op waiting for outputs / SYNC0.
    bool op_pending_ = false;
    uint64_t op_deadline_ns_ = 0;
    uint64_t op_wait_timeout_ns_ = 1'000'000'000;

    // Process data.
    std::vector<uint8_t> sm2_buf_;
    std::vector<uint8_t> sm3_buf_;
    uint16_t sm2_start_ = 0;
    uint16_t sm3_start_ = 0;
    bool outputs_seen_ = false;

    // Synchronisation.
    SyncMode sync_mode_ = SyncMode::FreeRun;
    bool master_wrote_sync_mode_ = false;
    bool internal_write_ = false;
    uint32_t cycle_ns_ = 0;
    uint64_t next_cycle_ns_ = 0;
    uint64_t last_sync0_ns_ = 0;
    uint64_t next_sync0_sys_ = 0;              // 0x0990 as last read (system time of the next SYNC0)
    uint64_t sync0_deadline_ns_ = UINT64_MAX;  // when the next SYNC0 is due, in poll() time
    bool sync0_seen_ = false;
    od::Ref<uint16_t> sm_missed_[2];
    od::Ref<uint16_t> cycle_exceeded_[2];
    od::Ref<uint8_t> sync_error_[2];
    uint32_t last_sm_change_time_ = 0;  // 0x09F0 as read at the last SM-synchronous cycle

    // Whether the interrupt line covers every SM event the stack waits on (SM control bit 5 set).
    bool irq_usable_ = true;
    void update_irq_usable();

    bool restart_pending_ = false;
    uint64_t housekeeping_at_ns_ = 0;
    uint64_t last_now_ns_ = 0;
    bool first_poll_ = true;
    StackStats stats_;
    StackFaults faults_;
};

}  // namespace ecat
