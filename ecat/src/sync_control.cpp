#include "ecat/sync_control.hpp"

#include <algorithm>
#include <array>

#include "util/le.hpp"

namespace ecat {
namespace {

constexpr uint16_t kSmType = 0x1C00;
constexpr uint16_t kSmOutputParams = 0x1C32;
constexpr uint16_t kSmInputParams = 0x1C33;
// 0x1C32/0x1C33 subindices (ETG.1000.6, SM output/input parameter objects; ETG.1020 Synchronization).
constexpr uint8_t kSiSyncMode = 1;
constexpr uint8_t kSiCycleTime = 2;
constexpr uint8_t kSiSyncModesSupported = 4;
constexpr uint8_t kSiMinCycleTime = 5;
constexpr uint8_t kSiSmEventMissed = 0x0B;
constexpr uint8_t kSiCycleExceeded = 0x0C;
constexpr uint8_t kSiSyncError = 0x20;

constexpr uint64_t kDefaultFreeRunCycleNs = 1'000'000;

// Whether a synchronization type written to 0x1C32:01 / 0x1C33:01 may be taken, given the :04 announcement
// (ETG.1020 Synchronization: bit 0 free run, bit 1 synchronous with the SM event, bit 2 DC SYNC0, bit 3 DC
// SYNC1; 34, synchronous with the SM2 event, only for the inputs' 0x1C33). As the SSC's CheckSyncTypeValue:
// free run is always taken (a device without it refuses it at Pre-Op -> Safe-Op, 0x0027); a type that is not
// announced, or no type at all, is refused with abort 0x06090030. Unlike the SSC, SM-synchronous does not
// depend on the outputs assigned so far: a master may write 0x1C32:01 before or after the PDO assignment.
bool sync_type_taken(uint16_t index, uint64_t type, uint64_t supported) {
    switch (type) {
        case static_cast<uint16_t>(SyncMode::FreeRun):
            return true;
        case static_cast<uint16_t>(SyncMode::SmSync):
            return supported & 0x0002;
        case static_cast<uint16_t>(SyncMode::DcSync0):
            return supported & 0x0004;
        case static_cast<uint16_t>(SyncMode::DcSync1):
            return supported & 0x0008;
        case static_cast<uint16_t>(SyncMode::SmSync2):
            return index == kSmInputParams && (supported & 0x0002);
        default:
            return false;
    }
}

// 0x0984 bit 0: first SYNC0 pulse pending (ESC datasheet, Distributed Clocks, activation status).
constexpr uint8_t kActFirstSync0Pending = 0x01;

}  // namespace

SyncControl::~SyncControl() {
    ctx_.dict.remove_hooks(this);
}

uint64_t SyncControl::get_u(uint16_t index, uint8_t sub, uint64_t fallback) const {
    const auto raw = ctx_.dict.raw(index, sub);
    if (raw.empty() || raw.size() > 8) return fallback;
    uint64_t v = 0;
    for (std::size_t i = 0; i < raw.size(); ++i)
        v |= static_cast<uint64_t>(raw[i]) << (8 * i);
    return v;
}

void SyncControl::set_u(uint16_t index, uint8_t sub, uint64_t value) {
    const od::Entry* e = ctx_.dict.find(index, sub);
    if (e == nullptr) return;
    const std::size_t n = e->byte_size();
    if (n == 0 || n > 8) return;
    uint8_t b[8];
    for (std::size_t i = 0; i < n; ++i)
        b[i] = static_cast<uint8_t>(value >> (8 * i));
    internal_write_ = true;
    ctx_.dict.set_raw(index, sub, std::span<const uint8_t>(b, n));
    internal_write_ = false;
}

// 0x1C00 as the SyncManager type object; not a PDO a device without CoE names 0x1C00 (EL1262's TxPdo
// 0x1C00: its mapping object, docs/decisions/esi.md "PDOs at any index").
bool SyncControl::has_sm_type_object() const {
    const od::Object* o = ctx_.dict.find(kSmType);
    return o != nullptr && !o->is_pdo_mapping();
}

uint64_t SyncControl::sm_type(unsigned n, uint64_t fallback) const {
    if (!has_sm_type_object()) return fallback;
    return get_u(kSmType, static_cast<uint8_t>(n + 1), fallback);
}

void SyncControl::init_objects() {
    od::Dictionary& dict = ctx_.dict;
    const od::DeviceDescription& desc = ctx_.desc;
    // 0x1C00 reflects the SyncManager types of the description.
    if (has_sm_type_object() && !desc.sync_managers.empty()) {
        for (std::size_t i = 0; i < desc.sync_managers.size() && i < 255; ++i)
            set_u(kSmType, static_cast<uint8_t>(i + 1), static_cast<uint8_t>(desc.sync_managers[i].kind));
    }
    // A synchronization type the device does not announce is refused when written (sync_type_taken) rather
    // than taken and refused only at Pre-Op -> Safe-Op: the master learns which write was wrong. The
    // announcement is the object's own :04, else 0x1C32:04, with the rule of configure() for a :04 without
    // mode bits (free run, SM-synchronous and DC SYNC0).
    for (const uint16_t index : {kSmOutputParams, kSmInputParams}) {
        if (dict.find(index, kSiSyncMode) == nullptr) continue;
        dict.add_validator(
            index,
            [this, index](const od::Entry& e, std::span<const uint8_t> v) {
                if (e.subindex != kSiSyncMode || v.empty() || v.size() > 8) return od::Status::Ok;
                uint64_t type = 0;
                for (std::size_t i = 0; i < v.size(); ++i)
                    type |= static_cast<uint64_t>(v[i]) << (8 * i);
                const uint64_t outputs = get_u(kSmOutputParams, kSiSyncModesSupported,
                                               get_u(kSmInputParams, kSiSyncModesSupported, 0x0007));
                uint64_t supported = index == kSmOutputParams
                                         ? outputs
                                         : get_u(kSmInputParams, kSiSyncModesSupported, outputs);
                if ((supported & 0x000F) == 0) supported = 0x0007;
                return sync_type_taken(index, type, supported) ? od::Status::Ok : od::Status::InvalidValue;
            },
            this);
    }
    // Notice master writes of the sync mode (SDO in Pre-Op), so Pre-Op -> Safe-Op can check them.
    if (dict.find(kSmOutputParams) != nullptr) {
        dict.add_listener(
            kSmOutputParams,
            [this](const od::Entry& e) {
                if (!internal_write_ && e.subindex == kSiSyncMode) master_wrote_sync_mode_ = true;
            },
            this);
    }
    for (int i = 0; i < 2; ++i) {
        const uint16_t index = i == 0 ? kSmOutputParams : kSmInputParams;
        const od::Entry* e = dict.find(index, kSiSmEventMissed);
        if (e != nullptr && e->byte_size() == 2) sm_missed_[i] = dict.ref<uint16_t>(index, kSiSmEventMissed);
        e = dict.find(index, kSiCycleExceeded);
        if (e != nullptr && e->byte_size() == 2)
            cycle_exceeded_[i] = dict.ref<uint16_t>(index, kSiCycleExceeded);
        e = dict.find(index, kSiSyncError);
        if (e != nullptr && e->byte_size() == 1) sync_error_[i] = dict.ref<uint8_t>(index, kSiSyncError);
    }
}

uint16_t SyncControl::configure() {
    esc::Pdi& pdi = ctx_.pdi;
    const ProcessData& pd = ctx_.pd;
    const uint8_t activation = pdi.read_reg<uint8_t>(esc::reg::kDcActivation);
    const uint32_t sync0_cycle = pdi.read_reg<uint32_t>(esc::reg::kDcSync0Cycle);
    // A 0x1C32:04 without any mode bit (bits 0-3: free run, SM, DC SYNC0/SYNC1) states no mode: 0, as
    // SOES-based devices' ESIs declare it, or 0x0400, an Inovance ESI's "0004" written big-endian (its device
    // runs DC). Such a device runs in every mode, as if the entry were absent.
    // The announcement is 0x1C32:04, else (a device with inputs only has 0x1C33 alone) 0x1C33:04.
    uint16_t supported = static_cast<uint16_t>(
        get_u(kSmOutputParams, kSiSyncModesSupported, get_u(kSmInputParams, kSiSyncModesSupported, 0x0007)));
    if ((supported & 0x000F) == 0) supported = 0x0007;
    const uint32_t min_cycle = static_cast<uint32_t>(get_u(kSmOutputParams, kSiMinCycleTime, 0));
    const bool cyclic = activation & esc::reg::kDcActCyclic;
    const bool sync0 = cyclic && (activation & esc::reg::kDcActSync0);
    const bool sync1 = cyclic && (activation & esc::reg::kDcActSync1);
    const bool has_pd = pd.rx_bytes() > 0 || pd.tx_bytes() > 0;

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
        const bool dc_mode = mode == SyncMode::DcSync0 || mode == SyncMode::DcSync1;
        // The activation in 0x0981 must say what 0x1C32:01 says.
        if (dc_mode != sync0 || (mode == SyncMode::DcSync1 && !sync1)) return al::InvalidDcSyncConfig;
    } else if (sync0) {
        // SYNC1 activated on a device that announces DC SYNC1 but not SYNC0 (0x1C32:04 bit 3 without bit 2,
        // as Beckhoff's EL15xx and EJ7xxx do with their AssignActivate 0x0700 op modes): DC SYNC1.
        mode = sync1 && (supported & 0x0008) && !(supported & 0x0004) ? SyncMode::DcSync1 : SyncMode::DcSync0;
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
            // ETG.1020 0x1C32:04: bit 2 DC SYNC0, bit 3 DC SYNC1 (the application synchronises to SYNC1,
            // which the ESC derives from SYNC0); each mode needs its own bit.
            if (!(supported & (mode == SyncMode::DcSync1 ? 0x0008 : 0x0004))) return al::SyncModeNotSupported;
            if (sync0_cycle == 0) return al::DcInvalidSyncCycleTime;
            // Start time already past when activated (0x0984 bit 2): SYNC0 would not come (ESC datasheet,
            // Distributed Clocks, activation status).
            if (pdi.read_reg<uint8_t>(esc::reg::kDcActivationStatus) & 0x04) return al::InvalidDcSyncConfig;
            if (min_cycle != 0 && sync0_cycle < min_cycle) return al::DcSync0CycleTime;
            cycle = sync0_cycle;
            break;
        case SyncMode::SmSync2:
            break;
    }
    sync_mode_ = mode;
    cycle_ns_ = cycle;

    // 0x1C32/0x1C33 say what really runs.
    const bool dc_mode = mode == SyncMode::DcSync0 || mode == SyncMode::DcSync1;
    set_u(kSmOutputParams, kSiSyncMode, static_cast<uint16_t>(mode));
    uint16_t input_mode = static_cast<uint16_t>(mode);
    if (mode == SyncMode::SmSync && pd.rx_bytes() > 0) input_mode = static_cast<uint16_t>(SyncMode::SmSync2);
    set_u(kSmInputParams, kSiSyncMode, input_mode);
    if (dc_mode || mode == SyncMode::FreeRun) {
        set_u(kSmOutputParams, kSiCycleTime, cycle);
        set_u(kSmInputParams, kSiCycleTime, cycle);
    }
    return al::NoError;
}

void SyncControl::op_entered() {
    for (auto& r : sync_error_)
        if (r.valid()) r.set(0);
}

void SyncControl::start(uint64_t now_ns) {
    sync0_seen_ = false;
    last_sync0_ns_ = now_ns;
    next_cycle_ns_ = now_ns + cycle_ns_;
    next_sync0_sys_ = ctx_.pdi.read_reg<uint64_t>(esc::reg::kDcStartTime);
    // The activation found here is this session's (configure() checked it); not a new one at the first look.
    const uint8_t activation = ctx_.pdi.read_reg<uint8_t>(esc::reg::kDcActivation);
    was_running_ = (activation & (esc::reg::kDcActCyclic | esc::reg::kDcActSync0)) ==
                   (esc::reg::kDcActCyclic | esc::reg::kDcActSync0);
    sync0_deadline_ns_ = UINT64_MAX;
    last_sm_change_time_ = ctx_.pdi.read_reg<uint32_t>(esc::reg::kDcEcatBufferChange);
    for (int i = 0; i < 2; ++i) {
        if (sm_missed_[i].valid()) sm_missed_[i].set(0);
        if (cycle_exceeded_[i].valid()) cycle_exceeded_[i].set(0);
        if (sync_error_[i].valid()) sync_error_[i].set(0);
    }
}

void SyncControl::reset() {
    sync_mode_ = SyncMode::FreeRun;
    master_wrote_sync_mode_ = false;
    cycle_ns_ = 0;
    sync0_seen_ = false;
    was_running_ = false;
    sync0_deadline_ns_ = UINT64_MAX;
}

void SyncControl::free_run_advance(uint64_t now_ns) {
    next_cycle_ns_ += cycle_ns_;
    if (next_cycle_ns_ <= now_ns) next_cycle_ns_ = now_ns + cycle_ns_;  // do not run a backlog
}

uint64_t SyncControl::sync0_loss_ns() const {
    return last_sync0_ns_ + std::max<uint64_t>(10ull * cycle_ns_, 10'000'000);
}

uint64_t SyncControl::next_deadline_ns(bool op) const {
    uint64_t t = UINT64_MAX;
    if (sync_mode_ == SyncMode::FreeRun) t = std::min(t, next_cycle_ns_);
    if (dc()) {
        t = std::min(t, sync0_deadline_ns_);
        if (op && cycle_ns_ > 0) t = std::min(t, sync0_loss_ns());
    }
    return t;
}

// The pulse that started this cycle is the one before the next (0x0990), on the SYNC0 grid; sys is 0x0910
// read at the cycle start. A pulse that came between the two reads would make the difference negative or
// longer than a period: such a sample is not taken (cycles_exceeded counts periods without a cycle).
void SyncControl::sample_sync0_latency(uint64_t sys, uint64_t next_sync0, uint32_t period) {
    if (period == 0 || next_sync0 < period) return;
    const uint64_t pulse = next_sync0 - period;
    if (sys < pulse || sys - pulse >= period) return;
    ctx_.stats.sync0_latency.add(sys - pulse);
}

// 0x09F0 holds the local time (low 32 bits) of the last ECAT-side buffer change; the local time now is the
// system time copy minus the offset. Differences are taken modulo 2^32 (valid up to 4.29 s).
void SyncControl::sample_sm2_latency() {
    esc::Pdi& pdi = ctx_.pdi;
    const uint32_t changed = pdi.read_reg<uint32_t>(esc::reg::kDcEcatBufferChange);
    if (changed == last_sm_change_time_) return;  // not latched by this ESC, or no new event
    last_sm_change_time_ = changed;
    const uint64_t sys = pdi.read_reg<uint64_t>(esc::reg::kDcSystemTime);
    const uint64_t offset = pdi.read_reg<uint64_t>(esc::reg::kDcOffset);
    const auto local = static_cast<uint32_t>(sys - offset);
    ctx_.stats.sm2_latency.add(static_cast<uint32_t>(local - changed));
}

SyncControl::Sync0 SyncControl::sync0_events(uint32_t events, uint64_t now_ns, bool op, bool has_outputs,
                                             bool new_outputs) {
    esc::Pdi& pdi = ctx_.pdi;
    StackStats& stats = ctx_.stats;
    // SYNC0 is seen as the AL event (when 0x0151 maps it) and, in any case, as the "next SYNC0" time 0x0990
    // moving on; the latter also says how many periods passed since the last look.
    uint64_t periods = 0;
    // 0x0990 is the next pulse only while SYNC0 runs; otherwise it is whatever the master wrote.
    // 0x0981 (activation) to 0x0984 (activation status) in one PDI access, and 0x0990 (next SYNC0) to 0x09A3
    // (SYNC0 cycle time) in another: neither range has a read side effect (0x098E, the acknowledge, is read
    // on its own). Fewer accesses, the same registers.
    std::array<uint8_t, esc::reg::kDcActivationStatus + 1 - esc::reg::kDcActivation> act{};
    pdi.read(esc::reg::kDcActivation, act);
    const uint8_t activation = act[0];
    const bool running = (activation & (esc::reg::kDcActCyclic | esc::reg::kDcActSync0)) ==
                         (esc::reg::kDcActCyclic | esc::reg::kDcActSync0);
    // 0x0984 bit 0: the first SYNC0 pulse of this activation is still pending (ESC datasheet, Distributed
    // Clocks, activation status). Until it comes, 0x0990 holds the programmed start time, and whatever was
    // seen before belongs to an earlier activation: a SYNC0 event still latched in 0x0220 bit 2 (it stays set
    // until 0x098E is read, also across a deactivation of 0x0981, so a session that ended in Pre-Op leaves
    // one behind) or the 0x0990 of the pulses before.
    const bool first_pending = running && (act[esc::reg::kDcActivationStatus - esc::reg::kDcActivation] &
                                           kActFirstSync0Pending) != 0;
    if (events & esc::alev::kSync0) {
        (void)pdi.read_reg<uint8_t>(esc::reg::kDcSync0Status);  // acknowledges the SYNC0 event
        if (!first_pending) periods = 1;
    }
    uint64_t next = next_sync0_sys_;
    uint32_t period = 0;
    if (running) {
        std::array<uint8_t, esc::reg::kDcSync0Cycle + 4 - esc::reg::kDcStartTime> times{};
        pdi.read(esc::reg::kDcStartTime, times);
        next = util::get64(times.data());
        period = util::get32(times.data() + (esc::reg::kDcSync0Cycle - esc::reg::kDcStartTime));
    }
    const uint64_t sys = pdi.read_reg<uint64_t>(esc::reg::kDcSystemTime);  // local copy of system time
    if (first_pending || (running && !was_running_)) {
        // A new activation (ETG.1020, DC start-up: 0x0981 cleared, start time, 0x0981 set): forget the
        // previous one. SYNC0 is judged from its start time on; periods before it are no cycles missed.
        sync0_seen_ = false;
        next_sync0_sys_ = next;
        // Activated since the last look and already pulsed: that pulse is the first of this activation. A
        // 0x0990 more than a period ahead is still the start time (an ESC that does not show the pending
        // bit).
        const bool pulsed = !first_pending && (cycle_ns_ == 0 || next <= sys + cycle_ns_);
        if (pulsed) {
            periods = 1;
        } else {
            periods = 0;
            last_sync0_ns_ = now_ns + (next > sys ? next - sys : 0);  // the loss is measured from the start
        }
    }
    was_running_ = running;
    if (next != next_sync0_sys_) {
        if (cycle_ns_ > 0 && next > next_sync0_sys_) periods = (next - next_sync0_sys_) / cycle_ns_;
        if (periods == 0) periods = 1;
        next_sync0_sys_ = next;
    }
    sync0_deadline_ns_ = running && next > sys ? now_ns + (next - sys) : UINT64_MAX;
    if (periods > 0) {
        ++stats.sync0_events;
        if (sync0_seen_ && periods > 1) {
            // SYNC0 periods that passed without a cycle of ours.
            stats.cycles_exceeded += periods - 1;
            for (auto& r : cycle_exceeded_)
                if (r.valid()) r.set(static_cast<uint16_t>(r.get() + (periods - 1)));
        }
        sync0_seen_ = true;
        last_sync0_ns_ = now_ns;
        const bool missed = op && has_outputs && !new_outputs;
        if (missed) {
            ++stats.sm_events_missed;
            for (auto& r : sm_missed_)
                if (r.valid()) r.set(static_cast<uint16_t>(r.get() + 1));
        }
        for (auto& r : sync_error_)
            if (r.valid()) r.set(missed ? 1 : 0);
        sample_sync0_latency(sys, next, period);
        return Sync0::RunCycle;
    }
    if (op && cycle_ns_ > 0 && now_ns >= sync0_loss_ns()) {
        // SYNC0 stopped arriving: fatal sync error (ETG.1000.6 AL status code 0x002C), outputs are lost.
        return Sync0::Lost;
    }
    return Sync0::None;
}

}  // namespace ecat
