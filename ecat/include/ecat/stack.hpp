#pragma once
// The slave stack core ("firmware"): EtherCAT state machine (ESM), mailbox, process data and the sync
// cycle. The Stack composes StateMachine (ecat/state_machine.hpp), SyncControl (ecat/sync_control.hpp) and
// Cycle (ecat/cycle.hpp), each owning its own state, over the shared StackContext. It reaches the ESC only
// through esc::Pdi (register reads/writes with PDI side effects) and, optionally, the PDI interrupt line, so
// the same code could drive an ESC chip over SPI.
//
// The runtime calls poll(now) after every burst of frames and when next_deadline_ns() has passed, each
// time after esc::Esc::tick() (so SYNC0 and the watchdogs are up to date), with the ESC's time base.
// pdi, dictionary, description and application must outlive the Stack, and the dictionary must not be
// replaced while it exists (the process-data plan and the 0x1C32/0x1C33 counters point into its values).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <iosfwd>

#include "ecat/application.hpp"
#include "ecat/cycle.hpp"
#include "ecat/event_sink.hpp"
#include "ecat/faults.hpp"
#include "ecat/latency.hpp"
#include "ecat/mailbox.hpp"
#include "ecat/mailbox_handler.hpp"
#include "ecat/process_data.hpp"
#include "ecat/stack_context.hpp"
#include "ecat/state_machine.hpp"
#include "ecat/sync_control.hpp"
#include "esc/pdi.hpp"
#include "esc/wire/al.hpp"
#include "od/device.hpp"
#include "od/dictionary.hpp"

namespace ecat {

class Stack {
  public:
    // The PDI interrupt line (esc::Esc::irq() or a GPIO); optional. When given, poll() skips its
    // register reads while the line is low and no deadline is due.
    using IrqLine = Cycle::IrqLine;

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
    void poll(uint64_t now_ns) { cycle_.poll(now_ns); }
    // True if poll(now_ns) would return at once without a register read beyond the interrupt line: nothing
    // signalled, no deadline due. Lets a caller with many stacks skip those with nothing to do.
    // registers_unchanged: see Cycle::quiet().
    bool quiet(uint64_t now_ns, bool registers_unchanged = false) const {
        return cycle_.quiet(now_ns, registers_unchanged);
    }
    // Time at which poll() must run again even if no frame arrives; UINT64_MAX if nothing is pending.
    uint64_t next_deadline_ns() const { return cycle_.next_deadline_ns(); }
    // Asks the memory system for the first cache lines of each unit a poll reads (the cycle, the state
    // machine, SYNC control, the process data, the mailbox) without waiting for them and without reading
    // anything: a caller that polls many stacks in turn lets their cache misses overlap (device::Line).
    void prefetch() const;

    // Application-detected error (e.g. a fatal device fault): sets the error indication with the code
    // and falls back to fallback if that is lower than the current state.
    void local_error(uint16_t code, od::AlState fallback) {
        esm_.fall_back(fallback, code, cycle_.last_now_ns());
    }

    od::AlState state() const { return esm_.state(); }
    bool error() const { return esm_.error(); }
    uint16_t status_code() const { return esm_.code(); }
    SyncMode sync_mode() const { return sync_.mode(); }
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
    void set_op_wait_timeout_ns(uint64_t ns) { esm_.set_op_wait_timeout_ns(ns); }
    // Where state changes, refused requests, local errors and watchdog expiries are reported (null: nowhere).
    void set_event_sink(EventSink* sink) { ctx_.events = sink; }
    // Housekeeping period for the mailbox handlers' poll() (transfer timeouts).
    static constexpr uint64_t kHousekeepingNs = Cycle::kHousekeepingNs;
    // AL event mask written at start: AL control, SYNC0, SM activation, PD watchdog, SM0..SM3.
    static constexpr uint32_t kEventMask = Cycle::kEventMask;

  private:
    Mailbox mailbox_;
    ProcessData pd_;
    StackStats stats_;
    StackFaults faults_;
    StackContext ctx_;
    SyncControl sync_;
    StateMachine esm_;
    Cycle cycle_;
};

}  // namespace ecat
