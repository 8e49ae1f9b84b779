#include "ecat/stack.hpp"

#include <algorithm>
#include <cstring>
#include <ostream>

#include "ecat/registers.hpp"

namespace ecat {
namespace {

using od::AlState;

constexpr uint16_t kSmType = 0x1C00;
constexpr uint16_t kSmOutputParams = 0x1C32;
constexpr uint16_t kSmInputParams = 0x1C33;
// 0x1C32/0x1C33 subindices (ethercat-protocol.md §11.5).
constexpr uint8_t kSiSyncMode = 1;
constexpr uint8_t kSiCycleTime = 2;
constexpr uint8_t kSiSyncModesSupported = 4;
constexpr uint8_t kSiMinCycleTime = 5;
constexpr uint8_t kSiSmEventMissed = 0x0B;
constexpr uint8_t kSiCycleExceeded = 0x0C;
constexpr uint8_t kSiSyncError = 0x20;

constexpr uint64_t kDefaultFreeRunCycleNs = 1'000'000;

bool known_state(unsigned s) {
    return s == 1 || s == 2 || s == 3 || s == 4 || s == 8;
}

// The ETG transition table (ethercat-protocol.md §6.2): true if from -> to is a defined transition.
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

bool process_data_state(AlState s) {
    return s == AlState::SafeOp || s == AlState::Op;
}

std::size_t max_mailbox(const od::DeviceDescription& d) {
    return std::max<std::size_t>({d.standard_mailbox.out_size, d.standard_mailbox.in_size,
                                  d.bootstrap_mailbox.out_size, d.bootstrap_mailbox.in_size});
}

}  // namespace

Stack::Stack(esc::Pdi& pdi, od::Dictionary& dictionary, const od::DeviceDescription& description,
             Application& application, IrqLine irq)
    : pdi_(pdi),
      dict_(dictionary),
      desc_(description),
      app_(application),
      irq_(std::move(irq)),
      mailbox_(pdi, max_mailbox(description)),
      pd_(dictionary) {
    sm2_buf_.reserve(1024);
    sm3_buf_.reserve(1024);
    // Init, no error; interrupts for the events this stack serves.
    pdi_.write_reg<uint32_t>(reg::kAlEventMask, kEventMask);
    write_status();
    // Mailbox and process-data SMs stay deactivated from the PDI side until their state starts them.
    for (unsigned n = 0; n < 4; ++n)
        set_sm_pdi_deactivated(n, true);
    sync_objects_init();
}

Stack::~Stack() {
    dict_.remove_hooks(this);
}

// ---- Dictionary helpers ------------------------------------------------------------------------------

uint64_t Stack::get_u(uint16_t index, uint8_t sub, uint64_t fallback) const {
    const auto raw = dict_.raw(index, sub);
    if (raw.empty() || raw.size() > 8) return fallback;
    uint64_t v = 0;
    for (std::size_t i = 0; i < raw.size(); ++i)
        v |= static_cast<uint64_t>(raw[i]) << (8 * i);
    return v;
}

void Stack::set_u(uint16_t index, uint8_t sub, uint64_t value) {
    const od::Entry* e = dict_.find(index, sub);
    if (e == nullptr) return;
    const std::size_t n = e->byte_size();
    if (n == 0 || n > 8) return;
    uint8_t b[8];
    for (std::size_t i = 0; i < n; ++i)
        b[i] = static_cast<uint8_t>(value >> (8 * i));
    internal_write_ = true;
    dict_.set_raw(index, sub, std::span<const uint8_t>(b, n));
    internal_write_ = false;
}

void Stack::sync_objects_init() {
    // 0x1C00 reflects the SyncManager types of the description.
    if (dict_.find(kSmType) != nullptr && !desc_.sync_managers.empty()) {
        for (std::size_t i = 0; i < desc_.sync_managers.size() && i < 255; ++i)
            set_u(kSmType, static_cast<uint8_t>(i + 1), static_cast<uint8_t>(desc_.sync_managers[i].kind));
    }
    // Notice master writes of the sync mode (SDO in Pre-Op), so Pre-Op -> Safe-Op can check them.
    if (dict_.find(kSmOutputParams) != nullptr) {
        dict_.add_listener(
            kSmOutputParams,
            [this](const od::Entry& e) {
                if (!internal_write_ && e.subindex == kSiSyncMode) master_wrote_sync_mode_ = true;
            },
            this);
    }
    for (int i = 0; i < 2; ++i) {
        const uint16_t index = i == 0 ? kSmOutputParams : kSmInputParams;
        const od::Entry* e = dict_.find(index, kSiSmEventMissed);
        if (e != nullptr && e->byte_size() == 2) sm_missed_[i] = dict_.ref<uint16_t>(index, kSiSmEventMissed);
        e = dict_.find(index, kSiCycleExceeded);
        if (e != nullptr && e->byte_size() == 2)
            cycle_exceeded_[i] = dict_.ref<uint16_t>(index, kSiCycleExceeded);
        e = dict_.find(index, kSiSyncError);
        if (e != nullptr && e->byte_size() == 1) sync_error_[i] = dict_.ref<uint8_t>(index, kSiSyncError);
    }
}

// ---- Registers --------------------------------------------------------------------------------------

Stack::SmRegs Stack::read_sm(unsigned n) {
    uint8_t b[8];
    pdi_.read(reg::sm_base(n), b);
    SmRegs r;
    r.start = static_cast<uint16_t>(b[0] | (b[1] << 8));
    r.length = static_cast<uint16_t>(b[2] | (b[3] << 8));
    r.control = b[4];
    r.status = b[5];
    r.activate = b[6];
    r.pdi_control = b[7];
    return r;
}

const od::SyncManagerDefault* Stack::sm_default(unsigned n) const {
    return n < desc_.sync_managers.size() ? &desc_.sync_managers[n] : nullptr;
}

uint8_t Stack::expected_control(unsigned n, uint8_t fallback) const {
    const od::SyncManagerDefault* d = sm_default(n);
    return d != nullptr ? d->control : fallback;
}

void Stack::set_sm_pdi_deactivated(unsigned n, bool deactivated) {
    uint8_t v = pdi_.read_reg<uint8_t>(reg::sm_base(n) + reg::kSmPdiControl);
    v = deactivated ? static_cast<uint8_t>(v | reg::kSmPdiDeactivate)
                    : static_cast<uint8_t>(v & ~reg::kSmPdiDeactivate);
    pdi_.write_reg<uint8_t>(reg::sm_base(n) + reg::kSmPdiControl, v);
}

void Stack::write_status() {
    uint16_t status = static_cast<uint16_t>(state_);
    if (error_) status |= reg::kAlErrorFlag;
    if (id_loaded_ && !error_) status |= reg::kAlIdFlag;
    pdi_.write_reg<uint16_t>(reg::kAlStatusCode, (id_loaded_ && !error_) ? id_value_ : code_);
    pdi_.write_reg<uint16_t>(reg::kAlStatus, status);
}

// ---- poll -------------------------------------------------------------------------------------------

void Stack::poll(uint64_t now_ns) {
    last_now_ns_ = now_ns;
    if (irq_ && irq_usable_ && !first_poll_ && !irq_() && now_ns < next_deadline_ns()) {
        return;  // nothing signalled and no timer due
    }
    if (!first_poll_ && esc_was_reset()) restart_after_esc_reset(now_ns);
    uint32_t events = pdi_.read_reg<uint32_t>(reg::kAlEventRequest);
    if (first_poll_) {
        first_poll_ = false;
        events |= reg::kEvAlControl;  // take over whatever the master requested before we started
    }
    if (events & reg::kEvAlControl) handle_al_control(now_ns);
    if (events & reg::kEvSmActivation) {
        // Reading the activation registers acknowledges the event; the mailbox checks the repeat bit.
        for (unsigned n = 0; n < 4; ++n)
            (void)pdi_.read_reg<uint8_t>(reg::sm_base(n) + reg::kSmActivate);
        if (process_data_state(state_)) check_process_data_sms(now_ns);
    }
    if ((events & reg::kEvWatchdogPd) && !faults_.watchdog_ignored) {
        const uint16_t wd = pdi_.read_reg<uint16_t>(reg::kWatchdogStatusPd);
        if (!(wd & 0x0001)) {
            ++stats_.watchdog_expiries;
            if (state_ == AlState::Op) {
                // Reported where it matters: outside Op no outputs are used, and one expires after every Op.
                if (events_ != nullptr) events_->watchdog_expired(state_);
                // Outputs are no longer refreshed: Safe-Op with error 0x001B (§3.8, §6.4 runtime).
                fall_back(AlState::SafeOp, al::SmWatchdog, now_ns);
            }
        }
    }
    if (process_data_state(state_)) process_data_events(events, now_ns);
    if (op_pending_) try_complete_op(now_ns);
    if (mailbox_.running()) {
        mailbox_.poll(now_ns);
        housekeeping_at_ns_ = now_ns + kHousekeepingNs;
    }
    if (restart_pending_) {
        // Last: AL status already says Init, so the application may restart the device from here.
        restart_pending_ = false;
        app_.on_restart();
    }
}

uint64_t Stack::next_deadline_ns() const {
    uint64_t t = UINT64_MAX;
    if (mailbox_.running()) t = std::min(t, housekeeping_at_ns_);
    if (op_pending_) t = std::min(t, op_deadline_ns_);
    if (process_data_state(state_)) {
        if (sync_mode_ == SyncMode::FreeRun) t = std::min(t, next_cycle_ns_);
        if (sync_mode_ == SyncMode::DcSync0 || sync_mode_ == SyncMode::DcSync1) {
            t = std::min(t, sync0_deadline_ns_);
            if (state_ == AlState::Op && cycle_ns_ > 0)
                t = std::min(t, last_sync0_ns_ + std::max<uint64_t>(10ull * cycle_ns_, 10'000'000));
        }
    }
    return t;
}

// ---- ESC reset --------------------------------------------------------------------------------------

bool Stack::esc_was_reset() {
    // The AL event mask is written only through the PDI (by this stack, at start); an ESC reset puts it
    // back to its reset value. On a device the ESC's reset would reset the controller behind it as well.
    return pdi_.read_reg<uint32_t>(reg::kAlEventMask) != kEventMask;
}

void Stack::restart_after_esc_reset(uint64_t now_ns) {
    ++stats_.esc_resets;
    // Down to Init as the ESC is: outputs lost, process data and mailbox stopped, the handlers drop their
    // transfers; the next Init -> Pre-Op starts the mailbox with fresh counters.
    op_pending_ = false;
    if (state_ != AlState::Init) go(AlState::Init, now_ns);
    error_ = false;
    code_ = al::NoError;
    id_loaded_ = false;
    sync_mode_ = SyncMode::FreeRun;
    master_wrote_sync_mode_ = false;
    cycle_ns_ = 0;
    outputs_seen_ = false;
    sync0_seen_ = false;
    sync0_deadline_ns_ = UINT64_MAX;
    // The register set-up of the constructor, lost with the reset.
    pdi_.write_reg<uint32_t>(reg::kAlEventMask, kEventMask);
    for (unsigned n = 0; n < 4; ++n)
        set_sm_pdi_deactivated(n, true);
    write_status();
    update_irq_usable();
    first_poll_ = true;       // take over whatever the master requested since the reset
    restart_pending_ = true;  // the application restarts as well (end of this poll)
}

// ---- ESM --------------------------------------------------------------------------------------------

void Stack::handle_al_control(uint64_t now_ns) {
    const uint16_t control = pdi_.read_reg<uint16_t>(reg::kAlControl);  // clears AL event bit 0
    const unsigned requested = control & reg::kAlStateMask;
    const bool ack = (control & reg::kAlErrorFlag) != 0 && !faults_.error_ack_ignored;
    const bool id_request = (control & reg::kAlIdFlag) != 0;

    // A new request supersedes a Safe-Op -> Op still waiting for outputs / SYNC0.
    op_pending_ = false;

    if (error_) {
        // While the error indication is set, only a request with the acknowledge bit (or a request for
        // Init, as SOES does) is taken; everything else is ignored (§6.2 error handling).
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
        if (events_ != nullptr) events_->state_refused(state_, static_cast<uint8_t>(requested), code_);
    } else if (static_cast<AlState>(requested) != state_) {
        request(static_cast<AlState>(requested), now_ns);
    }

    // Device identification (§6.2): the ID value (station alias 0x0012) in 0x0134 and AL status bit 5,
    // only while no error is pending.
    id_loaded_ = id_request && !error_;
    if (id_loaded_) id_value_ = pdi_.read_reg<uint16_t>(reg::kStationAlias);
    write_status();
}

void Stack::request(AlState to, uint64_t now_ns) {
    const AlState from = state_;
    const uint64_t refused_before = stats_.refused;
    request_checked(to, now_ns);
    if (events_ != nullptr && stats_.refused != refused_before)
        events_->state_refused(from, static_cast<uint8_t>(to), code_);
}

void Stack::request_checked(AlState to, uint64_t now_ns) {
    const AlState from = state_;
    const bool boot_supported = check_bootstrap() == 0;
    if (to == AlState::Boot && from == AlState::Init && (!boot_supported || faults_.bootstrap_refused)) {
        refuse(al::BootstrapNotSupported);
        return;
    }
    if (!valid_transition(from, to)) {
        if (faults_.invalid_request_silent) return;
        refuse(al::InvalidStateChange);
        return;
    }
    uint16_t code = al::NoError;
    const bool upward = rank(to) > rank(from) || (from == AlState::Init && to == AlState::Boot);
    if (upward) {
        if (from == AlState::Init && to == AlState::PreOp) {
            code = check_mailbox(desc_.standard_mailbox, al::InvalidMailboxConfigPreOp);
        } else if (from == AlState::Init && to == AlState::Boot) {
            code = check_mailbox(desc_.bootstrap_mailbox, al::InvalidMailboxConfigBoot);
        } else if (from == AlState::PreOp && to == AlState::SafeOp) {
            code = check_pre_op_to_safe_op();
        }
    }
    // Going down always succeeds (ref §6.2); the application vetoes only transitions up.
    if (code == al::NoError && upward) code = app_.check_transition(from, to);
    if (code != al::NoError) {
        if (from == AlState::PreOp && to == AlState::SafeOp) pd_.clear();
        refuse(code);
        return;
    }
    if (from == AlState::SafeOp && to == AlState::Op && !op_conditions_met()) {
        // Wait (in Safe-Op, no error) for the first outputs and, in DC mode, for SYNC0 (§6.4 S->O).
        op_pending_ = true;
        op_deadline_ns_ = now_ns + op_wait_timeout_ns_;
        return;
    }
    go(to, now_ns);
}

uint16_t Stack::check_bootstrap() {
    const bool foe = (desc_.mailbox_protocols & od::mailbox_protocol::FoE) != 0;
    const bool sized = desc_.bootstrap_mailbox.out_size > kMailboxHeaderSize &&
                       desc_.bootstrap_mailbox.in_size > kMailboxHeaderSize;
    return foe && sized ? al::NoError : al::BootstrapNotSupported;
}

uint16_t Stack::check_mailbox(const od::MailboxLayout& layout, uint16_t code) {
    if (layout.out_size == 0 && layout.in_size == 0) return al::NoError;  // device without mailbox
    const SmRegs sm0 = read_sm(0);
    const SmRegs sm1 = read_sm(1);
    // Mode and direction must match; event-enable and watchdog bits are the master's choice.
    const uint8_t c0 = static_cast<uint8_t>(expected_control(0, 0x26) & (reg::kSmModeMask | reg::kSmDirMask));
    const uint8_t c1 = static_cast<uint8_t>(expected_control(1, 0x22) & (reg::kSmModeMask | reg::kSmDirMask));
    const bool ok0 = sm0.start == layout.out_start && sm0.length == layout.out_size &&
                     (sm0.control & (reg::kSmModeMask | reg::kSmDirMask)) == c0 &&
                     (sm0.activate & reg::kSmEnable);
    const bool ok1 = sm1.start == layout.in_start && sm1.length == layout.in_size &&
                     (sm1.control & (reg::kSmModeMask | reg::kSmDirMask)) == c1 &&
                     (sm1.activate & reg::kSmEnable);
    // The two mailboxes must not overlap.
    const bool apart = sm0.start + sm0.length <= sm1.start || sm1.start + sm1.length <= sm0.start;
    return ok0 && ok1 && apart ? al::NoError : code;
}

uint16_t Stack::check_pre_op_to_safe_op() {
    // SM types as described (0x1C00).
    for (unsigned n = 0; n < desc_.sync_managers.size() && n < 4; ++n) {
        const uint64_t kind =
            get_u(kSmType, static_cast<uint8_t>(n + 1), static_cast<uint64_t>(desc_.sync_managers[n].kind));
        if (kind != static_cast<uint64_t>(desc_.sync_managers[n].kind)) return al::InvalidSmTypes;
    }
    // Take over the PDO assignment and mapping.
    if (const uint16_t code = pd_.build(); code != 0) return code;

    struct Side {
        unsigned sm;
        std::size_t bytes;
        uint8_t dir;
        uint16_t code;
        uint8_t fallback_control;
    };
    const Side sides[2] = {{2, pd_.rx_bytes(), reg::kSmDirWrite, al::InvalidOutputConfig, 0x64},
                           {3, pd_.tx_bytes(), reg::kSmDirRead, al::InvalidInputConfig, 0x20}};
    SmRegs regs[4];
    for (unsigned n = 0; n < 4; ++n)
        regs[n] = read_sm(n);
    for (const Side& s : sides) {
        const SmRegs& r = regs[s.sm];
        const bool enabled = (r.activate & reg::kSmEnable) && r.length > 0;
        if (s.bytes == 0) {
            if (enabled) return s.code;
            continue;
        }
        if (!enabled || (r.length != s.bytes && !(s.sm == 2 && faults_.sm2_length_unchecked))) return s.code;
        if ((r.control & reg::kSmModeMask) != reg::kSmModeBuffered) return al::InvalidSmTypes;
        const uint8_t expected = expected_control(s.sm, s.fallback_control);
        if ((r.control & reg::kSmDirMask) != (expected & reg::kSmDirMask) ||
            (r.control & reg::kSmDirMask) != s.dir)
            return s.code;
        const od::SyncManagerDefault* d = sm_default(s.sm);
        if (d != nullptr && d->start != 0 && r.start != d->start) return s.code;
    }
    // No overlap of the active SM areas (a buffered SM occupies three times its length, §3.14).
    struct Area {
        uint32_t begin, end;
    };
    Area areas[4];
    std::size_t count = 0;
    for (unsigned n = 0; n < 4; ++n) {
        const SmRegs& r = regs[n];
        if (!(r.activate & reg::kSmEnable) || r.length == 0) continue;
        const uint32_t factor = (r.control & reg::kSmModeMask) == reg::kSmModeBuffered ? 3 : 1;
        areas[count++] = {r.start, r.start + factor * r.length};
    }
    for (std::size_t i = 0; i < count; ++i)
        for (std::size_t j = i + 1; j < count; ++j)
            if (areas[i].begin < areas[j].end && areas[j].begin < areas[i].end) return al::InvalidSmConfig;

    sm2_start_ = regs[2].start;
    sm3_start_ = regs[3].start;
    if (const uint16_t code = check_sync_configuration(); code != 0) return code;
    return check_watchdog();
}

uint16_t Stack::check_sync_configuration() {
    const uint8_t activation = pdi_.read_reg<uint8_t>(reg::kDcActivation);
    const uint32_t sync0_cycle = pdi_.read_reg<uint32_t>(reg::kDcSync0CycleTime);
    const uint16_t supported = static_cast<uint16_t>(get_u(kSmOutputParams, kSiSyncModesSupported, 0x0007));
    const uint32_t min_cycle = static_cast<uint32_t>(get_u(kSmOutputParams, kSiMinCycleTime, 0));
    const bool cyclic = activation & reg::kDcActCyclic;
    const bool sync0 = cyclic && (activation & reg::kDcActSync0);
    const bool sync1 = cyclic && (activation & reg::kDcActSync1);
    const bool has_pd = pd_.rx_bytes() > 0 || pd_.tx_bytes() > 0;

    if (sync1 && !sync0) return al::InvalidDcSyncConfig;  // SYNC1 only together with SYNC0

    SyncMode mode;
    if (master_wrote_sync_mode_) {
        const auto requested = static_cast<uint16_t>(get_u(kSmOutputParams, kSiSyncMode, 0));
        switch (requested) {
            case 0:
                mode = SyncMode::FreeRun;
                break;
            case 1:
                mode = SyncMode::SmSync;
                break;
            case 2:
                mode = SyncMode::DcSync0;
                break;
            case 3:
                mode = SyncMode::DcSync1;
                break;
            default:
                return al::SyncModeNotSupported;
        }
        const bool dc = mode == SyncMode::DcSync0 || mode == SyncMode::DcSync1;
        // The activation in 0x0981 must say what 0x1C32:01 says.
        if (dc != sync0 || (mode == SyncMode::DcSync1 && !sync1)) return al::InvalidDcSyncConfig;
    } else if (sync0) {
        mode = SyncMode::DcSync0;
    } else if (has_pd && (supported & 0x0002)) {
        mode = SyncMode::SmSync;
    } else if (supported & 0x0001) {
        mode = SyncMode::FreeRun;
    } else if (supported & 0x0002) {
        mode = SyncMode::SmSync;
    } else {
        return al::FreeRunNotSupported;
    }

    uint32_t cycle = 0;
    switch (mode) {
        case SyncMode::FreeRun:
            if (!(supported & 0x0001)) return al::FreeRunNotSupported;
            cycle = static_cast<uint32_t>(get_u(kSmOutputParams, kSiCycleTime, kDefaultFreeRunCycleNs));
            if (cycle == 0) cycle = kDefaultFreeRunCycleNs;
            if (min_cycle != 0 && cycle < min_cycle) return al::CycleTimeTooSmall;
            break;
        case SyncMode::SmSync:
            if (!(supported & 0x0002)) return al::SyncModeNotSupported;
            cycle = static_cast<uint32_t>(get_u(kSmOutputParams, kSiCycleTime, 0));
            if (cycle != 0 && min_cycle != 0 && cycle < min_cycle) return al::CycleTimeTooSmall;
            break;
        case SyncMode::DcSync0:
        case SyncMode::DcSync1:
            if (!(supported & 0x0004) || (mode == SyncMode::DcSync1 && !(supported & 0x0008)))
                return al::SyncModeNotSupported;
            if (sync0_cycle == 0) return al::DcInvalidSyncCycleTime;
            // Start time already past when activated (0x0984 bit 2): SYNC0 would not come (ref §11.4).
            if (pdi_.read_reg<uint8_t>(reg::kDcActivationStatus) & 0x04) return al::InvalidDcSyncConfig;
            if (min_cycle != 0 && sync0_cycle < min_cycle) return al::DcSync0CycleTime;
            cycle = sync0_cycle;
            break;
        case SyncMode::SmSync2:
            break;
    }
    sync_mode_ = mode;
    cycle_ns_ = cycle;

    // 0x1C32/0x1C33 say what really runs.
    const bool dc = mode == SyncMode::DcSync0 || mode == SyncMode::DcSync1;
    set_u(kSmOutputParams, kSiSyncMode, static_cast<uint16_t>(mode));
    uint16_t input_mode = static_cast<uint16_t>(mode);
    if (mode == SyncMode::SmSync && pd_.rx_bytes() > 0) input_mode = static_cast<uint16_t>(SyncMode::SmSync2);
    set_u(kSmInputParams, kSiSyncMode, input_mode);
    if (dc || mode == SyncMode::FreeRun) {
        set_u(kSmOutputParams, kSiCycleTime, cycle);
        set_u(kSmInputParams, kSiCycleTime, cycle);
    }
    return al::NoError;
}

uint16_t Stack::check_watchdog() {
    if (pd_.rx_bytes() == 0) return al::NoError;
    const SmRegs sm2 = read_sm(2);
    if (!(sm2.control & reg::kSmWatchdogEnable)) return al::NoError;
    const uint16_t time = pdi_.read_reg<uint16_t>(reg::kWatchdogTimePd);
    if (time == 0) return al::NoError;  // watchdog off
    const uint16_t divider = pdi_.read_reg<uint16_t>(reg::kWatchdogDivider);
    const uint64_t timeout_ns = (static_cast<uint64_t>(divider) + 2) * 40 * time;
    // A watchdog shorter than one cycle would expire between two correct output updates.
    if (cycle_ns_ != 0 && timeout_ns < cycle_ns_) return al::InvalidWatchdogConfig;
    return al::NoError;
}

void Stack::check_process_data_sms(uint64_t now_ns) {
    // The master changed an SM while process data runs: SM2/SM3 must still be what Safe-Op was entered
    // with (ref §6.3: 0x001D / 0x001E, O,S -> S + E).
    auto still_valid = [this](unsigned n, std::size_t bytes, uint16_t start_address) {
        const SmRegs r = read_sm(n);
        const bool enabled = (r.activate & reg::kSmEnable) && r.length > 0;
        if (bytes == 0) return !enabled;
        const bool length_ok = r.length == bytes || (n == 2 && faults_.sm2_length_unchecked);
        return enabled && length_ok && r.start == start_address;
    };
    if (!still_valid(2, sm2_buf_.size(), sm2_start_)) {
        fall_back(AlState::SafeOp, al::InvalidOutputConfig, now_ns);
    } else if (!still_valid(3, sm3_buf_.size(), sm3_start_)) {
        fall_back(AlState::SafeOp, al::InvalidInputConfig, now_ns);
    }
}

bool Stack::op_conditions_met() {
    if (pd_.rx_bytes() > 0) {
        if (!outputs_seen_) return false;
        // Outputs seen once but since stopped: the process-data watchdog says they are stale.
        const bool watched = (read_sm(2).control & reg::kSmWatchdogEnable) &&
                             pdi_.read_reg<uint16_t>(reg::kWatchdogTimePd) != 0;
        if (watched && !(pdi_.read_reg<uint16_t>(reg::kWatchdogStatusPd) & 0x0001)) return false;
    }
    if ((sync_mode_ == SyncMode::DcSync0 || sync_mode_ == SyncMode::DcSync1) && !sync0_seen_) return false;
    return true;
}

void Stack::try_complete_op(uint64_t now_ns) {
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
        const bool dc = sync_mode_ == SyncMode::DcSync0 || sync_mode_ == SyncMode::DcSync1;
        refuse(dc && !sync0_seen_ ? al::NoSyncError : al::SmWatchdog);
        if (events_ != nullptr) events_->state_refused(state_, static_cast<uint8_t>(AlState::Op), code_);
        write_status();
    }
}

void Stack::go(AlState to, uint64_t now_ns) {
    const AlState from = state_;
    if (from == to) return;
    // Downward: stop outputs, inputs, mailbox as the target state requires.
    if (from == AlState::Op) app_.on_outputs_lost();
    if (process_data_state(from) && !process_data_state(to)) stop_process_data();
    if (from != AlState::Init && (to == AlState::Init)) mailbox_.stop();
    // Upward: start the mailbox (standard or bootstrap layout), the process data.
    if (from == AlState::Init && to == AlState::PreOp) {
        master_wrote_sync_mode_ = false;
        mailbox_.start(desc_.standard_mailbox, AlState::PreOp);
    }
    if (from == AlState::Init && to == AlState::Boot) mailbox_.start(desc_.bootstrap_mailbox, AlState::Boot);
    if (from == AlState::PreOp && to == AlState::SafeOp) start_process_data(now_ns);
    if (to == AlState::Op) {
        for (auto& r : sync_error_)
            if (r.valid()) r.set(0);
    }
    state_ = to;
    ++stats_.transitions;
    update_irq_usable();
    mailbox_.set_state(from, to);
    if (events_ != nullptr) events_->state_changed(from, to);
    app_.on_state_change(from, to);
    if (from == AlState::Boot && to == AlState::Init)
        restart_pending_ = true;  // reported at the end of poll()
}

void Stack::update_irq_usable() {
    constexpr uint8_t kPdiEvent = 0x20;
    bool usable = true;
    if (mailbox_.running()) {
        usable = usable && (read_sm(0).control & kPdiEvent) && (read_sm(1).control & kPdiEvent);
    }
    if (process_data_state(state_)) {
        if (!sm2_buf_.empty()) usable = usable && (read_sm(2).control & kPdiEvent);
        if (!sm3_buf_.empty()) usable = usable && (read_sm(3).control & kPdiEvent);
    }
    irq_usable_ = usable;
}

void Stack::refuse(uint16_t code) {
    error_ = true;
    code_ = faults_.al_code_missing ? al::NoError : code;
    id_loaded_ = false;
    ++stats_.refused;
}

void Stack::fall_back(AlState to, uint16_t code, uint64_t now_ns) {
    op_pending_ = false;
    if (rank(to) < rank(state_)) go(to, now_ns);
    refuse(code);
    if (events_ != nullptr) events_->local_error(state_, code);
    write_status();
}

void add_stats(StackStats& t, const StackStats& s) {
    t.transitions += s.transitions;
    t.refused += s.refused;
    t.cycles += s.cycles;
    t.sync0_events += s.sync0_events;
    t.sm_events_missed += s.sm_events_missed;
    t.cycles_exceeded += s.cycles_exceeded;
    t.watchdog_expiries += s.watchdog_expiries;
    t.sync0_latency.merge(s.sync0_latency);
    t.sm2_latency.merge(s.sm2_latency);
}

void print_stats(std::ostream& out, const StackStats& s) {
    out << "stack.transitions " << s.transitions << '\n'
        << "stack.refused " << s.refused << '\n'
        << "stack.cycles " << s.cycles << '\n'
        << "stack.sync0_events " << s.sync0_events << '\n'
        << "stack.sm_events_missed " << s.sm_events_missed << '\n'
        << "stack.cycles_exceeded " << s.cycles_exceeded << '\n'
        << "stack.watchdog_expiries " << s.watchdog_expiries << '\n'
        << "stack.esc_resets " << s.esc_resets << '\n';
    s.sync0_latency.print(out, "stack.sync0_latency");
    s.sm2_latency.print(out, "stack.sm2_latency");
}

void Stack::local_error(uint16_t code, AlState fallback) {
    fall_back(fallback, code, last_now_ns_);
}

// ---- Process data -----------------------------------------------------------------------------------

void Stack::start_process_data(uint64_t now_ns) {
    sm2_buf_.assign(pd_.rx_bytes(), 0);
    sm3_buf_.assign(pd_.tx_bytes(), 0);
    outputs_seen_ = false;
    sync0_seen_ = false;
    last_sync0_ns_ = now_ns;
    next_cycle_ns_ = now_ns + cycle_ns_;
    next_sync0_sys_ = pdi_.read_reg<uint64_t>(reg::kDcStartTime);
    sync0_deadline_ns_ = UINT64_MAX;
    last_sm_change_time_ = pdi_.read_reg<uint32_t>(reg::kDcEcatBufferChangeTime);
    for (int i = 0; i < 2; ++i) {
        if (sm_missed_[i].valid()) sm_missed_[i].set(0);
        if (cycle_exceeded_[i].valid()) cycle_exceeded_[i].set(0);
        if (sync_error_[i].valid()) sync_error_[i].set(0);
    }
    if (pd_.rx_bytes() > 0) set_sm_pdi_deactivated(2, false);
    if (pd_.tx_bytes() > 0) {
        set_sm_pdi_deactivated(3, false);
        write_inputs();  // valid inputs from the first Safe-Op frame on
    }
}

void Stack::stop_process_data() {
    set_sm_pdi_deactivated(2, true);
    set_sm_pdi_deactivated(3, true);
    pd_.clear();
    sm2_buf_.clear();
    sm3_buf_.clear();
    outputs_seen_ = false;
}

void Stack::write_inputs() {
    if (sm3_buf_.empty() || (faults_.inputs_op_only && state_ != AlState::Op)) return;
    pd_.dictionary_to_inputs(sm3_buf_);
    pdi_.write(sm3_start_, sm3_buf_);
}

void Stack::run_cycle(uint64_t now_ns, bool fresh_outputs) {
    if (!sm2_buf_.empty()) {
        // Reading SM2 from its first to its last byte takes the newest buffer and releases it.
        if (fresh_outputs) pdi_.read(sm2_start_, sm2_buf_);
        // Safe-Op: outputs are ignored, the application keeps its safe values.
        if ((state_ == AlState::Op || faults_.outputs_in_safe_op) && fresh_outputs)
            pd_.outputs_to_dictionary(sm2_buf_);
    }
    app_.on_cycle(now_ns);
    write_inputs();
    ++stats_.cycles;
}

// The pulse that started this cycle is the one before the next (0x0990), on the SYNC0 grid; sys is 0x0910
// read at the cycle start. A pulse that came between the two reads would make the difference negative or
// longer than a period: such a sample is not taken (cycles_exceeded counts periods without a cycle).
void Stack::sample_sync0_latency(uint64_t sys, uint64_t next_sync0, bool running) {
    if (!running) return;
    const uint32_t period = pdi_.read_reg<uint32_t>(reg::kDcSync0CycleTime);
    if (period == 0 || next_sync0 < period) return;
    const uint64_t pulse = next_sync0 - period;
    if (sys < pulse || sys - pulse >= period) return;
    stats_.sync0_latency.add(sys - pulse);
}

// 0x09F0 holds the local time (low 32 bits) of the last ECAT-side buffer change; the local time now is the
// system time copy minus the offset. Differences are taken modulo 2^32 (valid up to 4.29 s).
void Stack::sample_sm2_latency() {
    const uint32_t changed = pdi_.read_reg<uint32_t>(reg::kDcEcatBufferChangeTime);
    if (changed == last_sm_change_time_) return;  // not latched by this ESC, or no new event
    last_sm_change_time_ = changed;
    const uint64_t sys = pdi_.read_reg<uint64_t>(reg::kDcSystemTime);
    const uint64_t offset = pdi_.read_reg<uint64_t>(reg::kDcSystemTimeOffset);
    const auto local = static_cast<uint32_t>(sys - offset);
    stats_.sm2_latency.add(static_cast<uint32_t>(local - changed));
}

void Stack::process_data_events(uint32_t events, uint64_t now_ns) {
    const bool has_outputs = !sm2_buf_.empty();
    bool new_outputs = false;
    if (has_outputs) {
        const uint8_t st = pdi_.read_reg<uint8_t>(reg::sm_base(2) + reg::kSmStatus);
        new_outputs = (st & reg::kSmStatusIrqWrite) != 0 || (events & reg::ev_sm(2)) != 0;
        if (new_outputs) outputs_seen_ = true;
    }
    switch (sync_mode_) {
        case SyncMode::SmSync:
        case SyncMode::SmSync2:
            if (has_outputs) {
                if (new_outputs) {
                    sample_sm2_latency();
                    run_cycle(now_ns, true);
                }
            } else if (!sm3_buf_.empty()) {
                // Inputs only: a new cycle each time the master has read the inputs.
                const uint8_t st = pdi_.read_reg<uint8_t>(reg::sm_base(3) + reg::kSmStatus);
                if ((st & reg::kSmStatusIrqRead) || (events & reg::ev_sm(3))) run_cycle(now_ns, false);
            }
            break;
        case SyncMode::FreeRun:
            if (now_ns >= next_cycle_ns_) {
                run_cycle(now_ns, new_outputs);
                next_cycle_ns_ += cycle_ns_;
                if (next_cycle_ns_ <= now_ns) next_cycle_ns_ = now_ns + cycle_ns_;  // do not run a backlog
            }
            break;
        case SyncMode::DcSync0:
        case SyncMode::DcSync1: {
            // SYNC0 is seen as the AL event (when 0x0151 maps it) and, in any case, as the "next SYNC0"
            // time 0x0990 moving on; the latter also says how many periods passed since the last look.
            uint64_t periods = 0;
            if (events & reg::kEvSync0) {
                (void)pdi_.read_reg<uint8_t>(reg::kDcSync0Status);  // acknowledges the SYNC0 event
                periods = 1;
            }
            // 0x0990 is the next pulse only while SYNC0 runs; otherwise it is whatever the master wrote.
            const uint8_t activation = pdi_.read_reg<uint8_t>(reg::kDcActivation);
            const bool running = (activation & (reg::kDcActCyclic | reg::kDcActSync0)) ==
                                 (reg::kDcActCyclic | reg::kDcActSync0);
            const uint64_t next = running ? pdi_.read_reg<uint64_t>(reg::kDcStartTime) : next_sync0_sys_;
            if (next != next_sync0_sys_) {
                if (cycle_ns_ > 0 && next > next_sync0_sys_) periods = (next - next_sync0_sys_) / cycle_ns_;
                if (periods == 0) periods = 1;
                next_sync0_sys_ = next;
            }
            const uint64_t sys = pdi_.read_reg<uint64_t>(reg::kDcSystemTime);  // local copy of system time
            sync0_deadline_ns_ = running && next > sys ? now_ns + (next - sys) : UINT64_MAX;
            if (periods > 0) {
                ++stats_.sync0_events;
                if (sync0_seen_ && periods > 1) {
                    // SYNC0 periods that passed without a cycle of ours.
                    stats_.cycles_exceeded += periods - 1;
                    for (auto& r : cycle_exceeded_)
                        if (r.valid()) r.set(static_cast<uint16_t>(r.get() + (periods - 1)));
                }
                sync0_seen_ = true;
                last_sync0_ns_ = now_ns;
                const bool missed = state_ == AlState::Op && has_outputs && !new_outputs;
                if (missed) {
                    ++stats_.sm_events_missed;
                    for (auto& r : sm_missed_)
                        if (r.valid()) r.set(static_cast<uint16_t>(r.get() + 1));
                }
                for (auto& r : sync_error_)
                    if (r.valid()) r.set(missed ? 1 : 0);
                sample_sync0_latency(sys, next, running);
                run_cycle(now_ns, new_outputs);
            } else if (state_ == AlState::Op && cycle_ns_ > 0 &&
                       now_ns >= last_sync0_ns_ + std::max<uint64_t>(10ull * cycle_ns_, 10'000'000)) {
                // SYNC0 stopped arriving: fatal sync error (§6.3 0x002C), outputs are lost.
                fall_back(AlState::SafeOp, al::FatalSyncError, now_ns);
            }
            break;
        }
    }
}

}  // namespace ecat
