#include "ecat/state_machine.hpp"

#include <algorithm>
#include <array>
#include <vector>

#include "ecat/cycle.hpp"
#include "ecat/sync_control.hpp"

namespace ecat {
namespace {

using od::AlState;

// One of the AL states of the AL vocabulary (bits 3:0 of AL control).
bool known_state(unsigned s) {
    return esc::al_state_name(static_cast<uint8_t>(s)) != "UNKNOWN";
}

// The ESM transition table (ETG.1000.6, EtherCAT State Machine): true if from -> to is a defined transition.
bool valid_transition(AlState from, AlState to) {
    if (from == to) return true;
    switch (from) {
        case AlState::Init:
            return to == AlState::PreOp || to == AlState::Boot;
        case AlState::PreOp:
            return to == AlState::Init || to == AlState::SafeOp;
        case AlState::Boot:
            return to == AlState::Init;
        case AlState::SafeOp:
            return to == AlState::Init || to == AlState::PreOp || to == AlState::Op;
        case AlState::Op:
            return to == AlState::Init || to == AlState::PreOp || to == AlState::SafeOp;
    }
    return false;
}

// Rank for "lower than": Boot counts with Init (both below Pre-Op).
int rank(AlState s) {
    switch (s) {
        case AlState::Init:
            return 0;
        case AlState::Boot:
            return 0;
        case AlState::PreOp:
            return 1;
        case AlState::SafeOp:
            return 2;
        case AlState::Op:
            return 3;
    }
    return 0;
}

}  // namespace

void StateMachine::write_status() {
    if (device_emulation()) {
        // The ESC owns AL status; no error indication, no code.
        ctx_.pdi.write_reg<uint16_t>(esc::reg::kAlStatusCode, 0);
        return;
    }
    uint16_t status = static_cast<uint16_t>(state_);
    if (error_) status |= esc::reg::kAlErrorFlag;
    if (id_loaded_ && !error_) status |= esc::reg::kAlIdFlag;
    ctx_.pdi.write_reg<uint16_t>(esc::reg::kAlStatusCode, (id_loaded_ && !error_) ? id_value_ : code_);
    ctx_.pdi.write_reg<uint16_t>(esc::reg::kAlStatus, status);
}

bool StateMachine::take_restart() {
    const bool pending = restart_pending_;
    restart_pending_ = false;
    return pending;
}

const od::SyncManagerDefault* StateMachine::sm_default(unsigned n) const {
    return n < ctx_.desc.sync_managers.size() ? &ctx_.desc.sync_managers[n] : nullptr;
}

uint8_t StateMachine::expected_control(unsigned n, uint8_t fallback) const {
    const od::SyncManagerDefault* d = sm_default(n);
    return d != nullptr ? d->control : fallback;
}

void StateMachine::reset_to_init(uint64_t now_ns) {
    op_pending_ = false;
    if (state_ != AlState::Init) go(AlState::Init, now_ns);
    error_ = false;
    code_ = al::NoError;
    id_loaded_ = false;
}

void StateMachine::handle_al_control(uint64_t now_ns) {
    const uint16_t control = ctx_.pdi.read_reg<uint16_t>(esc::reg::kAlControl);  // clears AL event bit 0
    const unsigned requested = control & esc::reg::kAlStateMask;
    const bool ack = (control & esc::reg::kAlErrorFlag) != 0 && !ctx_.faults.error_ack_ignored;
    const bool id_request = (control & esc::reg::kAlIdFlag) != 0;

    // A new request supersedes a Safe-Op -> Op still waiting for outputs / SYNC0.
    op_pending_ = false;

    if (error_) {
        // While the error indication is set, only a request with the acknowledge bit (or a request for
        // Init, as SOES does) is taken; everything else is ignored (ETG.1000.6, ESM error handling).
        if (!ack && requested != static_cast<unsigned>(AlState::Init)) {
            id_loaded_ = false;
            write_status();
            return;
        }
        error_ = false;
        code_ = al::NoError;
    }

    if (!known_state(requested)) {
        refuse(al::UnknownState);
        if (ctx_.events != nullptr)
            ctx_.events->state_refused(state_, static_cast<uint8_t>(requested), code_);
    } else if (static_cast<AlState>(requested) != state_) {
        request(static_cast<AlState>(requested), now_ns);
    }

    // Device identification (ETG.1000.6, AL control/status): the ID value (station alias 0x0012) in
    // 0x0134 and AL status bit 5, only while no error is pending.
    id_loaded_ = id_request && !error_;
    if (id_loaded_) id_value_ = ctx_.pdi.read_reg<uint16_t>(esc::reg::kStationAlias);
    write_status();
}

void StateMachine::request(AlState to, uint64_t now_ns) {
    const AlState from = state_;
    const uint64_t refused_before = ctx_.stats.refused;
    request_checked(to, now_ns);
    if (ctx_.events != nullptr && ctx_.stats.refused != refused_before)
        ctx_.events->state_refused(from, static_cast<uint8_t>(to), code_);
}

void StateMachine::request_checked(AlState to, uint64_t now_ns) {
    if (device_emulation()) {
        follow(to, now_ns);
        return;
    }
    const AlState from = state_;
    const bool boot_supported = check_bootstrap() == 0;
    if (to == AlState::Boot && from == AlState::Init && (!boot_supported || ctx_.faults.bootstrap_refused)) {
        refuse(al::BootstrapNotSupported);
        return;
    }
    if (!valid_transition(from, to)) {
        if (ctx_.faults.invalid_request_silent) return;
        refuse(al::InvalidStateChange);
        return;
    }
    uint16_t code = al::NoError;
    const bool upward = rank(to) > rank(from) || (from == AlState::Init && to == AlState::Boot);
    if (upward) {
        if (from == AlState::Init && to == AlState::PreOp) {
            code = check_mailbox(ctx_.desc.standard_mailbox, al::InvalidMailboxConfigPreOp);
        } else if (from == AlState::Init && to == AlState::Boot) {
            code = check_mailbox(ctx_.desc.bootstrap_mailbox, al::InvalidMailboxConfigBoot);
        } else if (from == AlState::PreOp && to == AlState::SafeOp) {
            code = check_pre_op_to_safe_op();
        }
    }
    // Going down always succeeds (ETG.1000.6, ESM); the application vetoes only transitions up.
    if (code == al::NoError && upward) code = ctx_.app.check_transition(from, to);
    if (code != al::NoError) {
        if (from == AlState::PreOp && to == AlState::SafeOp) ctx_.pd.clear();
        refuse(code);
        return;
    }
    if (from == AlState::SafeOp && to == AlState::Op && !op_conditions_met()) {
        // Wait (in Safe-Op, no error) for the first outputs and, in DC mode, for SYNC0 (ETG.1000.6,
        // Safe-Op to Op; ETG.1020 Synchronization).
        op_pending_ = true;
        op_deadline_ns_ = now_ns + op_wait_timeout_ns_;
        return;
    }
    go(to, now_ns);
}

bool StateMachine::device_emulation() const {
    return ecat::device_emulation(ctx_.pdi);
}

void StateMachine::follow(AlState to, uint64_t now_ns) {
    // The state the ESC took: the stack goes along, setting up (or stopping) its process data on the way
    // and never raising an error (there is no AL status code without a controller). Bootstrap is not
    // followed: nothing to start without a bootstrap mailbox.
    if (to == AlState::Boot) return;
    const bool pd = rank(to) >= rank(AlState::SafeOp);
    if (rank(state_) < rank(AlState::PreOp) && rank(to) >= rank(AlState::PreOp)) go(AlState::PreOp, now_ns);
    if (pd && !process_data_state(state_)) {
        if (check_pre_op_to_safe_op() != al::NoError) ctx_.pd.clear();  // the ESC runs without data from us
        go(AlState::SafeOp, now_ns);
    }
    go(to, now_ns);
}

uint16_t StateMachine::check_bootstrap() const {
    // Bootstrap is supported when the device announces a bootstrap mailbox (SII words 0x14-0x17, the ESI's
    // Mailbox/BootStrap): what is served there is the mailbox handlers' business (FoE if declared; any other
    // request gets "unsupported protocol"). The MAXPOS declares FoE with its bootstrap mailbox; a device with
    // a mailbox but no bootstrap mailbox announced refuses Bootstrap (0x0013).
    const od::DeviceDescription& desc = ctx_.desc;
    const bool sized = desc.bootstrap_mailbox.out_size > kMailboxHeaderSize &&
                       desc.bootstrap_mailbox.in_size > kMailboxHeaderSize;
    return sized && has_mailbox(desc) ? al::NoError : al::BootstrapNotSupported;
}

uint16_t StateMachine::check_mailbox(const od::MailboxLayout& layout, uint16_t code) {
    // A device without mailbox (ETG.2000: no Mailbox element, no MBoxOut/MBoxIn SM) goes to Pre-Op with
    // whatever its SMs hold: SM0/SM1 are process-data SMs there, checked at Pre-Op -> Safe-Op.
    if (layout.out_size == 0 && layout.in_size == 0) return al::NoError;
    if (!has_mailbox(ctx_.desc)) return al::NoError;
    const SmRegs sm0 = read_sm(ctx_.pdi, 0);
    const SmRegs sm1 = read_sm(ctx_.pdi, 1);
    // Mode and direction must match; event-enable and watchdog bits are the master's choice.
    const uint8_t c0 =
        static_cast<uint8_t>(expected_control(0, 0x26) & (esc::reg::kSmModeMask | esc::reg::kSmDirMask));
    const uint8_t c1 =
        static_cast<uint8_t>(expected_control(1, 0x22) & (esc::reg::kSmModeMask | esc::reg::kSmDirMask));
    const bool ok0 = sm0.start == layout.out_start && sm0.length == layout.out_size &&
                     (sm0.control & (esc::reg::kSmModeMask | esc::reg::kSmDirMask)) == c0 &&
                     (sm0.activate & esc::reg::kSmEnable);
    const bool ok1 = sm1.start == layout.in_start && sm1.length == layout.in_size &&
                     (sm1.control & (esc::reg::kSmModeMask | esc::reg::kSmDirMask)) == c1 &&
                     (sm1.activate & esc::reg::kSmEnable);
    // The two mailboxes must not overlap.
    const bool apart = sm0.start + sm0.length <= sm1.start || sm1.start + sm1.length <= sm0.start;
    return ok0 && ok1 && apart ? al::NoError : code;
}

uint16_t StateMachine::check_module_idents() const {
    // ETG.5001.1 (Modular Device Profile): the master may write the modules it configured into 0xF030
    // (Configured Module Ident List); the device compares them with the modules it has, 0xF050 (Detected
    // Module Ident List), slot by slot, at Pre-Op -> Safe-Op and refuses a difference with 0x0070. A count
    // of 0 in 0xF030 configures nothing (no check); a slot past either count is empty (ident 0).
    const od::Dictionary& dict = ctx_.dict;
    if (dict.find(0xF030) == nullptr || dict.find(0xF050) == nullptr) return al::NoError;
    auto u8 = [&dict](uint16_t index) -> unsigned {
        const auto r = dict.raw(index, 0);
        return r.size() == 1 ? r[0] : 0u;
    };
    auto ident = [&dict](uint16_t index, unsigned sub, unsigned count) -> uint32_t {
        if (sub > count) return 0;
        const auto r = dict.raw(index, static_cast<uint8_t>(sub));
        if (r.size() != 4) return 0;
        return static_cast<uint32_t>(r[0] | r[1] << 8 | r[2] << 16 | static_cast<uint32_t>(r[3]) << 24);
    };
    const unsigned configured = u8(0xF030);
    if (configured == 0) return al::NoError;
    const unsigned detected = u8(0xF050);
    for (unsigned n = 1; n <= std::max(configured, detected); ++n)
        if (ident(0xF030, n, configured) != ident(0xF050, n, detected)) return al::ModuleIdentMismatch;
    return al::NoError;
}

uint16_t StateMachine::check_pre_op_to_safe_op() {
    const od::DeviceDescription& desc = ctx_.desc;
    ProcessData& pd = ctx_.pd;
    // The modules the master configured are the ones the device has (before the PDOs they bring).
    if (const uint16_t code = check_module_idents(); code != al::NoError) return code;
    // SM types as described (0x1C00).
    for (unsigned n = 0; n < desc.sync_managers.size() && n < 4; ++n) {
        const uint64_t kind = sync_.sm_type(n, static_cast<uint64_t>(desc.sync_managers[n].kind));
        if (kind != static_cast<uint64_t>(desc.sync_managers[n].kind)) return al::InvalidSmTypes;
    }
    // Take over the PDO assignment and mapping of every process-data SM. The PDOs of an input SM on the
    // register space map the ESC's own registers (Beckhoff's 0x1Dxx:yy for register 0xxxyy, EL1202-0100's
    // Virtual SM over 0x0990): where the dictionary has no object for them, that SM is left out of the
    // image, and the device's own process data runs without it.
    if (uint16_t code = pd.build(ctx_.sms.all_outputs, ctx_.sms.all_inputs); code != 0) {
        std::vector<unsigned> own;
        for (const unsigned n : ctx_.sms.all_inputs)
            if (!inputs_on_registers(ctx_.sms, desc, n)) own.push_back(n);
        if (own.size() == ctx_.sms.all_inputs.size()) return code;
        if (code = pd.build(ctx_.sms.all_outputs, own); code != 0) return code;
    }

    struct Side {
        unsigned sm;
        std::size_t bytes;
        uint8_t dir;
        uint16_t code;
        uint8_t fallback_control;
    };
    // Each process-data SM with the length its own assignment gives (ETG.1000.6: 0x1C10 + n for SM n).
    std::array<Side, 2 * ProcessData::kMaxSms> sides{};
    std::size_t n_sides = 0;
    for (const SmImage& im : pd.rx_sms())
        sides[n_sides++] = {im.sm, im.bytes, esc::reg::kSmDirWrite, al::InvalidOutputConfig, 0x64};
    for (const SmImage& im : pd.tx_sms())
        if (!inputs_on_registers(ctx_.sms, desc, im.sm))
            sides[n_sides++] = {im.sm, im.bytes, esc::reg::kSmDirRead, al::InvalidInputConfig, 0x20};
    SmRegs regs[ProcessData::kMaxSms];
    const std::size_t sm_regs = std::clamp<std::size_t>(desc.sync_managers.size(), 4, ProcessData::kMaxSms);
    for (unsigned n = 0; n < sm_regs; ++n)
        regs[n] = read_sm(ctx_.pdi, n);
    for (std::size_t i = 0; i < n_sides; ++i) {
        const Side& s = sides[i];
        if (s.sm >= sm_regs) {
            // No SM for this direction (a device with inputs only, or none): nothing mapped to check.
            if (s.bytes != 0) return s.code;
            continue;
        }
        const SmRegs& r = regs[s.sm];
        const bool enabled = (r.activate & esc::reg::kSmEnable) && r.length > 0;
        if (s.bytes == 0) {
            // The first SM of a direction must be off without PDOs; a further one without PDOs (iTegva's
            // second output byte, whose SM a master may enable with the FMMU over both) is left as it is.
            if (enabled && (s.sm == ctx_.sms.outputs || s.sm == ctx_.sms.inputs)) return s.code;
            continue;
        }
        // A further SM of a direction that the master leaves off: its PDOs are not exchanged (a master that
        // handles one SM per direction, as the project's own master library does), as an unused SM's. One
        // that is on must be as its assignment says.
        const bool first = s.sm == ctx_.sms.outputs || s.sm == ctx_.sms.inputs;
        if (!enabled && !first) continue;
        if (!enabled ||
            (r.length != s.bytes && !(s.sm == ctx_.sms.outputs && ctx_.faults.sm2_length_unchecked)))
            return s.code;
        // Buffered (three buffers), or the one-buffer (mailbox mode) handshake where the device declares it
        // for its process data (ETG.2000 Sm ControlByte #x22 on Inputs: Beckhoff AX2000/AX5000, EM7004,
        // EL1254; ESC datasheet, SyncManager: 1-buffer mode). Any other mode is not what the device serves.
        const uint8_t expected = expected_control(s.sm, s.fallback_control);
        const uint8_t mode = r.control & esc::reg::kSmModeMask;
        if (mode != esc::reg::kSmModeBuffered &&
            !(mode == esc::reg::kSmModeMailbox &&
              (expected & esc::reg::kSmModeMask) == esc::reg::kSmModeMailbox))
            return al::InvalidSmTypes;
        if ((r.control & esc::reg::kSmDirMask) != (expected & esc::reg::kSmDirMask) ||
            (r.control & esc::reg::kSmDirMask) != s.dir)
            return s.code;
        const od::SyncManagerDefault* d = sm_default(s.sm);
        if (d != nullptr && d->start != 0 && r.start != d->start) return s.code;
    }
    // No overlap of the active SM areas (a buffered SM occupies three times its length: ESC datasheet,
    // SyncManager, 3-buffer mode). A buffered SM of one byte and one over the register space (the
    // digital-output SMs of a digital I/O ESC, 0x0F00-0x0F03, one byte each) have no buffers: they cover
    // their own bytes only, as the ESC serves them (docs/decisions/esc.md).
    struct Area {
        uint32_t begin, end;
    };
    Area areas[ProcessData::kMaxSms];
    std::size_t count = 0;
    for (unsigned n = 0; n < sm_regs; ++n) {
        const SmRegs& r = regs[n];
        if (!(r.activate & esc::reg::kSmEnable) || r.length == 0) continue;
        const bool buffers = (r.control & esc::reg::kSmModeMask) == esc::reg::kSmModeBuffered &&
                             r.length > 1 && r.start >= esc::reg::kRamBase;
        const uint32_t factor = buffers ? 3 : 1;
        areas[count++] = {r.start, r.start + factor * r.length};
    }
    for (std::size_t i = 0; i < count; ++i)
        for (std::size_t j = i + 1; j < count; ++j)
            if (areas[i].begin < areas[j].end && areas[j].begin < areas[i].end) return al::InvalidSmConfig;

    std::array<uint16_t, ProcessData::kMaxSms> starts{};
    for (unsigned n = 0; n < sm_regs; ++n)
        starts[n] = regs[n].start;
    cycle_.set_sm_starts(starts);
    if (const uint16_t code = sync_.configure(); code != 0) return code;
    return check_watchdog();
}

uint16_t StateMachine::check_watchdog() {
    esc::Pdi& pdi = ctx_.pdi;
    if (ctx_.pd.rx_bytes() == 0 || ctx_.sms.outputs >= 4) return al::NoError;
    const SmRegs sm2 = read_sm(pdi, ctx_.sms.outputs);
    if (!(sm2.control & esc::reg::kSmWatchdogEnable)) return al::NoError;
    const uint16_t time = pdi.read_reg<uint16_t>(esc::reg::kWdTimePd);
    if (time == 0) return al::NoError;  // watchdog off
    const uint16_t divider = pdi.read_reg<uint16_t>(esc::reg::kWdDivider);
    const uint64_t timeout_ns = (static_cast<uint64_t>(divider) + 2) * 40 * time;
    // A watchdog shorter than one cycle would expire between two correct output updates.
    if (sync_.cycle_ns() != 0 && timeout_ns < sync_.cycle_ns()) return al::InvalidWatchdogConfig;
    return al::NoError;
}

void StateMachine::check_process_data_sms(uint64_t now_ns) {
    // The master changed an SM while process data runs: SM2/SM3 must still be what Safe-Op was entered
    // with (ETG.1000.6 AL status codes 0x001D / 0x001E, Op or Safe-Op -> Safe-Op with error).
    auto still_valid = [this](unsigned n, std::size_t bytes, uint16_t start_address) {
        if (n >= ProcessData::kMaxSms) return true;  // no SM for this direction
        const SmRegs r = read_sm(ctx_.pdi, n);
        const bool enabled = (r.activate & esc::reg::kSmEnable) && r.length > 0;
        const bool first = n == ctx_.sms.outputs || n == ctx_.sms.inputs;
        if (bytes == 0 || (!enabled && !first)) return !enabled || !first;
        const bool length_ok =
            r.length == bytes || (n == ctx_.sms.outputs && ctx_.faults.sm2_length_unchecked);
        return enabled && length_ok && r.start == start_address;
    };
    // Every SM of both directions, each with its own part of the image.
    for (const SmImage& im : ctx_.pd.rx_sms())
        if (!still_valid(im.sm, im.bytes, cycle_.sm_start(im.sm)))
            return fall_back(AlState::SafeOp, al::InvalidOutputConfig, now_ns);
    for (const SmImage& im : ctx_.pd.tx_sms())
        if (!inputs_on_registers(ctx_.sms, ctx_.desc, im.sm) &&
            !still_valid(im.sm, im.bytes, cycle_.sm_start(im.sm)))
            return fall_back(AlState::SafeOp, al::InvalidInputConfig, now_ns);
}

bool StateMachine::op_conditions_met() {
    esc::Pdi& pdi = ctx_.pdi;
    if (ctx_.pd.rx_bytes() > 0) {
        if (!cycle_.outputs_seen()) return false;
        // Outputs seen once but since stopped: the process-data watchdog says they are stale.
        const bool watched = ctx_.sms.outputs < 4 &&
                             (read_sm(pdi, ctx_.sms.outputs).control & esc::reg::kSmWatchdogEnable) &&
                             pdi.read_reg<uint16_t>(esc::reg::kWdTimePd) != 0;
        if (watched && !(pdi.read_reg<uint16_t>(esc::reg::kWdStatusPd) & 0x0001)) return false;
    }
    if (sync_.dc() && !sync_.sync0_seen()) return false;
    return true;
}

void StateMachine::try_complete_op(uint64_t now_ns) {
    if (state_ != AlState::SafeOp) {
        op_pending_ = false;
        return;
    }
    if (op_conditions_met()) {
        op_pending_ = false;
        go(AlState::Op, now_ns);
        write_status();
        return;
    }
    if (now_ns >= op_deadline_ns_) {
        op_pending_ = false;
        refuse(sync_.dc() && !sync_.sync0_seen() ? al::NoSyncError : al::SmWatchdog);
        if (ctx_.events != nullptr)
            ctx_.events->state_refused(state_, static_cast<uint8_t>(AlState::Op), code_);
        write_status();
    }
}

void StateMachine::go(AlState to, uint64_t now_ns) {
    const AlState from = state_;
    if (from == to) return;
    // Downward: stop outputs, inputs, mailbox as the target state requires.
    if (from == AlState::Op) ctx_.app.on_outputs_lost();
    if (process_data_state(from) && !process_data_state(to)) cycle_.stop_process_data();
    // A device without mailbox has no mailbox SMs to start or stop: SM0/SM1 carry its process data.
    const bool mailbox = has_mailbox(ctx_.desc);
    if (from != AlState::Init && (to == AlState::Init) && mailbox) ctx_.mailbox.stop();
    // Upward: start the mailbox (standard or bootstrap layout), the process data.
    if (from == AlState::Init && to == AlState::PreOp) {
        sync_.pre_op_entered();
        if (mailbox) ctx_.mailbox.start(ctx_.desc.standard_mailbox, AlState::PreOp);
    }
    if (from == AlState::Init && to == AlState::Boot)
        ctx_.mailbox.start(ctx_.desc.bootstrap_mailbox, AlState::Boot);
    if (from == AlState::PreOp && to == AlState::SafeOp) cycle_.start_process_data(now_ns);
    if (to == AlState::Op) sync_.op_entered();
    state_ = to;
    ++ctx_.stats.transitions;
    cycle_.update_irq_usable();
    cycle_.update_event_mask();
    ctx_.mailbox.set_state(from, to);
    if (ctx_.events != nullptr) ctx_.events->state_changed(from, to);
    ctx_.app.on_state_change(from, to);
    if (from == AlState::Boot && to == AlState::Init)
        restart_pending_ = true;  // reported at the end of poll()
}

void StateMachine::refuse(uint16_t code) {
    error_ = true;
    code_ = ctx_.faults.al_code_missing ? al::NoError : code;
    id_loaded_ = false;
    ++ctx_.stats.refused;
}

void StateMachine::fall_back(AlState to, uint16_t code, uint64_t now_ns) {
    // With device emulation the ESC keeps the state the master asked for (a watchdog expiry clears the
    // outputs in hardware): nothing to fall back to, no error indication to set.
    if (device_emulation()) return;
    op_pending_ = false;
    if (rank(to) < rank(state_)) go(to, now_ns);
    refuse(code);
    if (ctx_.events != nullptr) ctx_.events->local_error(state_, code);
    write_status();
}

}  // namespace ecat
