#include "ecat/cycle.hpp"

#include <algorithm>
#include <array>

#include "ecat/state_machine.hpp"
#include "ecat/sync_control.hpp"
#include "util/le.hpp"

namespace ecat {

using od::AlState;

Cycle::Cycle(StackContext& ctx, StateMachine& esm, SyncControl& sync, IrqLine irq)
    : ctx_(ctx), esm_(esm), sync_(sync), irq_(std::move(irq)) {
    out_sm_ = ctx_.sms.outputs < 4 ? ctx_.sms.outputs : 2;
    in_sm_ = ctx_.sms.inputs < 4 ? ctx_.sms.inputs : 3;
    event_mask_ = kEventMask & ~(esc::alev::sm(0) | esc::alev::sm(2) | esc::alev::sm(3));
    if (has_mailbox(ctx_.desc)) event_mask_ |= esc::alev::sm(0);
    if (ctx_.sms.outputs < 4) event_mask_ |= esc::alev::sm(ctx_.sms.outputs);
    if (ctx_.sms.inputs < 4) event_mask_ |= esc::alev::sm(ctx_.sms.inputs);
    base_event_mask_ = event_mask_;
    sm2_buf_.reserve(1024);
    sm3_buf_.reserve(1024);
}

void Cycle::set_up_registers() {
    write_mask(event_mask_);
}

void Cycle::write_mask(uint32_t mask) {
    ctx_.pdi.write_reg<uint32_t>(esc::reg::kAlEventMask, mask);
    written_mask_ = mask;
}

// ---- poll -------------------------------------------------------------------------------------------

void Cycle::poll(uint64_t now_ns) {
    esc::Pdi& pdi = ctx_.pdi;
    last_now_ns_ = now_ns;
    if (quiet(now_ns)) return;  // nothing signalled and no timer due
    // The reset check and the AL event request in one PDI access: 0x0204 (AL event mask) to 0x0223 (AL event
    // request), a range whose read has no side effect (the ECAT event request 0x0210 between them).
    std::array<uint8_t, esc::reg::kAlEvent + 4 - esc::reg::kAlEventMask> regs{};
    pdi.read(esc::reg::kAlEventMask, regs);
    uint32_t events = util::get32(regs.data() + (esc::reg::kAlEvent - esc::reg::kAlEventMask));
    if (!first_poll_ && esc_was_reset(util::get32(regs.data()))) {
        restart_after_esc_reset(now_ns);
        events = pdi.read_reg<uint32_t>(esc::reg::kAlEvent);
    }
    if (first_poll_) {
        first_poll_ = false;
        events |= esc::alev::kAlControl;  // take over whatever the master requested before we started
    }
    if (events & esc::alev::kAlControl) esm_.handle_al_control(now_ns);
    if (events & esc::alev::kSmActivation) {
        // Reading the activation registers acknowledges the event; the mailbox checks the repeat bit.
        for (unsigned n = 0; n < 4; ++n)
            (void)pdi.read_reg<uint8_t>(esc::reg::sm_base(n) + esc::reg::kSmActivate);
        if (process_data_state(esm_.state())) esm_.check_process_data_sms(now_ns);
    }
    if ((events & esc::alev::kWatchdogPd) && !ctx_.faults.watchdog_ignored) {
        const uint16_t wd = pdi.read_reg<uint16_t>(esc::reg::kWdStatusPd);
        if (!(wd & 0x0001)) {
            ++ctx_.stats.watchdog_expiries;
            if (esm_.state() == AlState::Op && esm_.device_emulation()) {
                // No controller to change the state: the ESC itself resets its digital outputs at the expiry,
                // or with the next output event when the digital I/O configuration 0x0150 bit 3 says so
                // (ESC datasheet section II, 0x0150 PDI configuration, 0x0F00 digital I/O output data).
                if (ctx_.events != nullptr) ctx_.events->watchdog_expired(esm_.state());
                if (pdi.read_reg<uint8_t>(esc::reg::kPdiConfig) & kOutputsResetAtNextEvent) {
                    outputs_reset_pending_ = true;
                } else {
                    ctx_.app.on_outputs_lost();
                }
            } else if (esm_.state() == AlState::Op) {
                // Reported where it matters: outside Op no outputs are used, and one expires after every Op.
                if (ctx_.events != nullptr) ctx_.events->watchdog_expired(esm_.state());
                // Outputs are no longer refreshed: Safe-Op with error 0x001B (ETG.1000.6, process-data
                // watchdog; ESC datasheet, watchdog).
                esm_.fall_back(AlState::SafeOp, al::SmWatchdog, now_ns);
            }
        }
    }
    if (process_data_state(esm_.state())) process_data_events(events, now_ns);
    if (esm_.op_pending()) esm_.try_complete_op(now_ns);
    if (ctx_.mailbox.running()) {
        ctx_.mailbox.poll(now_ns);
        housekeeping_at_ns_ = now_ns + kHousekeepingNs;
    }
    // Last: AL status already says Init, so the application may restart the device from here.
    if (esm_.take_restart()) ctx_.app.on_restart();
}

bool Cycle::quiet(uint64_t now_ns, bool registers_unchanged) const {
    return irq_ && (irq_usable_ || registers_unchanged) && !first_poll_ && ctx_.mailbox.queued() == 0 &&
           !irq_() && now_ns < next_deadline_ns();
}

uint64_t Cycle::next_deadline_ns() const {
    uint64_t t = UINT64_MAX;
    if (ctx_.mailbox.running()) t = std::min(t, housekeeping_at_ns_);
    if (esm_.op_pending()) t = std::min(t, esm_.op_deadline_ns());
    if (process_data_state(esm_.state()))
        t = std::min(t, sync_.next_deadline_ns(esm_.state() == AlState::Op));
    return t;
}

// ---- ESC reset --------------------------------------------------------------------------------------

bool Cycle::esc_was_reset(uint32_t mask) const {
    // The AL event mask is written only through the PDI (by this stack, at start); an ESC reset puts it
    // back to its reset value. On a device the ESC's reset would reset the controller behind it as well.
    return mask != written_mask_;
}

void Cycle::restart_after_esc_reset(uint64_t now_ns) {
    ++ctx_.stats.esc_resets;
    // Down to Init as the ESC is: outputs lost, process data and mailbox stopped, the handlers drop their
    // transfers; the next Init -> Pre-Op starts the mailbox with fresh counters.
    esm_.reset_to_init(now_ns);
    sync_.reset();
    outputs_seen_ = false;
    // The register set-up of the constructor, lost with the reset.
    set_up_registers();
    for (unsigned n = 0; n < 4; ++n)
        hold_sm_until_started(ctx_.pdi, n);
    esm_.write_status();
    update_irq_usable();
    first_poll_ = true;      // take over whatever the master requested since the reset
    esm_.request_restart();  // the application restarts as well (end of this poll)
}

void Cycle::update_irq_usable() {
    constexpr uint8_t kPdiEvent = 0x20;
    esc::Pdi& pdi = ctx_.pdi;
    bool usable = true;
    if (ctx_.mailbox.running()) {
        usable = usable && (read_sm(pdi, 0).control & kPdiEvent) && (read_sm(pdi, 1).control & kPdiEvent);
    }
    if (process_data_state(esm_.state())) {
        if (!sm2_buf_.empty()) usable = usable && (read_sm(pdi, out_sm_).control & kPdiEvent);
        if (!sm3_buf_.empty()) usable = usable && (read_sm(pdi, in_sm_).control & kPdiEvent);
    }
    irq_usable_ = usable;
}

void Cycle::update_event_mask() {
    // In Op, DC-synchronous, with SYNC0 in the AL event register: SYNC0 wakes the stack for the cycle, which
    // reads the SM2 status itself, so the SM2/SM3 events of each frame are masked (written_mask()). Safe-Op
    // keeps them: on the way to Op every frame's poll also looks at the DC activation, which a master may
    // have renewed (the wait for the first SYNC0 of a new start time). Without the SYNC0 event the stack
    // keeps them too, with its own estimate of the next SYNC0 as a deadline.
    const bool masked = sync0_event_ && esm_.state() == AlState::Op;
    const uint32_t mask =
        masked ? event_mask_ & ~(esc::alev::sm(out_sm_) | esc::alev::sm(in_sm_)) : event_mask_;
    if (mask != written_mask_) write_mask(mask);
}

// ---- Process data -----------------------------------------------------------------------------------

void Cycle::start_process_data(uint64_t now_ns) {
    ProcessData& pd = ctx_.pd;
    // The SMs whose events drive the cycle: the first of each direction that carries PDOs (EL4732 assigns
    // none to its first input SM), else the first of the direction; their events join the mask.
    event_mask_ = base_event_mask_;
    auto trigger = [this](std::span<const SmImage> images, unsigned& sm) {
        for (const SmImage& im : images)
            if (im.bytes > 0 && im.sm < ProcessData::kMaxSms) {
                sm = im.sm;
                event_mask_ |= esc::alev::sm(sm);
                return;
            }
    };
    trigger(pd.rx_sms(), out_sm_);
    trigger(pd.tx_sms(), in_sm_);
    sm2_buf_.assign(pd.rx_bytes(), 0);
    sm3_buf_.assign(pd.tx_bytes(), 0);
    outputs_seen_ = false;
    outputs_reset_pending_ = false;
    sync_.start(now_ns);
    constexpr uint8_t kSync0ToAlEvent = 0x08;  // 0x0151 bit 3
    sync0_event_ = sync_.dc() && (ctx_.pdi.read_reg<uint8_t>(esc::reg::kSyncLatchConfig) & kSync0ToAlEvent);
    for (const auto& images : {pd.rx_sms(), pd.tx_sms()})
        for (const SmImage& im : images)
            if (im.bytes > 0) set_sm_pdi_deactivated(ctx_.pdi, im.sm, false);
    if (pd.tx_bytes() > 0) write_inputs();  // valid inputs from the first Safe-Op frame on
}

void Cycle::stop_process_data() {
    sync0_event_ = false;
    for (const auto* list : {&ctx_.sms.all_outputs, &ctx_.sms.all_inputs})
        for (const unsigned n : *list)
            hold_sm_until_started(ctx_.pdi, n);
    ctx_.pd.clear();
    out_sm_ = ctx_.sms.outputs < 4 ? ctx_.sms.outputs : 2;
    in_sm_ = ctx_.sms.inputs < 4 ? ctx_.sms.inputs : 3;
    event_mask_ = base_event_mask_;
    sm2_buf_.clear();
    sm3_buf_.clear();
    outputs_seen_ = false;
}

void Cycle::write_inputs() {
    if (sm3_buf_.empty() || (ctx_.faults.inputs_op_only && esm_.state() != AlState::Op)) return;
    ctx_.pd.dictionary_to_inputs(sm3_buf_);
    const std::span<const uint8_t> image(sm3_buf_);
    for (const SmImage& im : ctx_.pd.tx_sms()) {
        if (im.bytes == 0) continue;
        if (inputs_on_registers(ctx_.sms, ctx_.desc, im.sm)) {
            // An input SM on the register space carries the ESC's own registers (DC latch, system time): the
            // device does not write them; the entries its PDOs map show them (control socket, SDO).
            const std::span<uint8_t> part = std::span<uint8_t>(sm3_buf_).subspan(im.offset, im.bytes);
            ctx_.pdi.read(ctx_.desc.sync_managers[im.sm].start, part);
            ctx_.pd.inputs_to_dictionary(sm3_buf_, im);
            continue;
        }
        ctx_.pdi.write(sm_start(im.sm), image.subspan(im.offset, im.bytes));
    }
}

void Cycle::run_cycle(uint64_t now_ns, bool fresh_outputs) {
    if (outputs_reset_pending_) {
        // The output event after an expiry of the watchdog (0x0150 bit 3): it puts out zeros, not the data.
        outputs_reset_pending_ = false;
        ctx_.app.on_outputs_lost();
        fresh_outputs = false;
    }
    if (!sm2_buf_.empty()) {
        // Reading each output SM from its first to its last byte takes its newest buffer and releases it.
        if (fresh_outputs) {
            const std::span<uint8_t> image(sm2_buf_);
            for (const SmImage& im : ctx_.pd.rx_sms())
                if (im.bytes > 0) ctx_.pdi.read(sm_start(im.sm), image.subspan(im.offset, im.bytes));
        }
        // Safe-Op: outputs are ignored, the application keeps its safe values.
        if ((esm_.state() == AlState::Op || ctx_.faults.outputs_in_safe_op) && fresh_outputs)
            ctx_.pd.outputs_to_dictionary(sm2_buf_);
    }
    ctx_.app.on_cycle(now_ns);
    write_inputs();
    ++ctx_.stats.cycles;
}

void Cycle::process_data_events(uint32_t events, uint64_t now_ns) {
    esc::Pdi& pdi = ctx_.pdi;
    const bool has_outputs = !sm2_buf_.empty();
    // Outputs in an SM on the register space (the digital-output registers 0x0F00 of an ESC with digital
    // I/O) signal a write like those in the RAM: the ESC closes such an SM at its last byte
    // (docs/decisions/esc.md, "SyncManager over the register space").
    bool new_outputs = false;
    if (has_outputs) {
        const uint8_t st = pdi.read_reg<uint8_t>(esc::reg::sm_base(out_sm_) + esc::reg::kSmStatus);
        new_outputs = (st & esc::reg::kSmStatusIrqWrite) != 0 || (events & esc::alev::sm(out_sm_)) != 0;
        if (new_outputs) outputs_seen_ = true;
    }
    switch (sync_.mode()) {
        case SyncMode::SmSync:
        case SyncMode::SmSync2:
            if (has_outputs) {
                if (new_outputs) {
                    sync_.sample_sm2_latency();
                    run_cycle(now_ns, true);
                }
            } else if (!sm3_buf_.empty()) {
                // Inputs only: a new cycle each time the master has read the inputs.
                const uint8_t st = pdi.read_reg<uint8_t>(esc::reg::sm_base(in_sm_) + esc::reg::kSmStatus);
                if ((st & esc::reg::kSmStatusIrqRead) || (events & esc::alev::sm(in_sm_)))
                    run_cycle(now_ns, false);
            }
            break;
        case SyncMode::FreeRun:
            if (sync_.free_run_due(now_ns)) {
                run_cycle(now_ns, new_outputs);
                sync_.free_run_advance(now_ns);
            }
            break;
        case SyncMode::DcSync0:
        case SyncMode::DcSync1: {
            const bool op = esm_.state() == AlState::Op;
            switch (sync_.sync0_events(events, now_ns, op, has_outputs, new_outputs)) {
                case SyncControl::Sync0::RunCycle:
                    run_cycle(now_ns, new_outputs);
                    break;
                case SyncControl::Sync0::Lost:
                    esm_.fall_back(AlState::SafeOp, al::FatalSyncError, now_ns);
                    break;
                case SyncControl::Sync0::None:
                    break;
            }
            break;
        }
    }
}

}  // namespace ecat
