#pragma once
// What the three parts of ecat::Stack (StateMachine, SyncControl, Cycle) share: the collaborators the Stack
// was built with, its statistics and faults, and the SyncManager register block as read through the PDI.
// Internal to the stack; applications use ecat/stack.hpp.
#include <cstdint>
#include <iosfwd>
#include <vector>

#include "ecat/application.hpp"
#include "ecat/event_sink.hpp"
#include "ecat/faults.hpp"
#include "ecat/latency.hpp"
#include "ecat/mailbox.hpp"
#include "ecat/process_data.hpp"
#include "esc/pdi.hpp"
#include "esc/wire/al.hpp"
#include "esc/wire/registers.hpp"
#include "od/device.hpp"
#include "od/dictionary.hpp"

namespace ecat {

// The AL status codes the stack writes to 0x0134 are the ESC's vocabulary (esc/wire/al.hpp).
namespace al = esc::al;

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

// The SyncManagers that carry process data: every SM of kind Outputs and of kind Inputs in the description,
// in SM order (ETG.2000 Sm elements; a device without mailbox has them from SM0 on, a device with one from
// SM2 on; EL1252 has three input SMs). `outputs`/`inputs` are the first of each (the SM whose events drive
// the cycle and whose watchdog watches the outputs). A description without SyncManagers: SM2/SM3. kNoSm: no
// SM for that direction.
struct ProcessDataSms {
    static constexpr unsigned kNoSm = ProcessData::kNoSm;
    unsigned outputs = 2;
    unsigned inputs = 3;
    std::vector<unsigned> all_outputs{2};
    std::vector<unsigned> all_inputs{3};
};

inline ProcessDataSms process_data_sms(const od::DeviceDescription& desc) {
    ProcessDataSms s;
    if (desc.sync_managers.empty()) return s;
    s.outputs = s.inputs = ProcessDataSms::kNoSm;
    s.all_outputs.clear();
    s.all_inputs.clear();
    for (unsigned n = 0; n < desc.sync_managers.size() && n < ProcessData::kMaxSms; ++n) {
        const od::SmKind k = desc.sync_managers[n].kind;
        if (k == od::SmKind::Outputs) s.all_outputs.push_back(n);
        if (k == od::SmKind::Inputs) s.all_inputs.push_back(n);
    }
    if (!s.all_outputs.empty()) s.outputs = s.all_outputs.front();
    if (!s.all_inputs.empty()) s.inputs = s.all_inputs.front();
    return s;
}

// An input SM after the first one that lies on the register space (below the process data RAM, ESC datasheet
// 0x1000): a Virtual SM of the ESI over the ESC's own registers (EL1252's DC latch 0x09AE and system time
// 0x0910, EL1262's 0x0998). Its data are those registers: the device writes nothing there and the master may
// map them by an FMMU alone, so its SM is not checked either.
inline bool inputs_on_registers(const ProcessDataSms& s, const od::DeviceDescription& desc, unsigned sm) {
    return sm != s.inputs && sm < desc.sync_managers.size() &&
           desc.sync_managers[sm].kind == od::SmKind::Inputs && desc.sync_managers[sm].start != 0 &&
           desc.sync_managers[sm].start < esc::reg::kRamBase;
}

// True if the description declares a mailbox: an SM of kind MBoxOut/MBoxIn (or, without SyncManagers,
// a standard mailbox with a size).
inline bool has_mailbox(const od::DeviceDescription& desc) {
    if (desc.sync_managers.empty())
        return desc.standard_mailbox.out_size != 0 || desc.standard_mailbox.in_size != 0;
    for (const od::SyncManagerDefault& sm : desc.sync_managers)
        if (sm.kind == od::SmKind::MBoxOut || sm.kind == od::SmKind::MBoxIn) return true;
    return false;
}

struct StackContext {
    esc::Pdi& pdi;
    od::Dictionary& dict;
    const od::DeviceDescription& desc;
    Application& app;
    Mailbox& mailbox;
    ProcessData& pd;
    StackStats& stats;
    const StackFaults& faults;
    EventSink* events = nullptr;
    ProcessDataSms sms{};
};

// States in which process data (SM2/SM3) runs.
constexpr bool process_data_state(od::AlState s) {
    return s == od::AlState::SafeOp || s == od::AlState::Op;
}

// One SyncManager's register block (ESC datasheet, SyncManager registers 0x0800 + 8n).
struct SmRegs {
    uint16_t start = 0;
    uint16_t length = 0;
    uint8_t control = 0;
    uint8_t status = 0;
    uint8_t activate = 0;
    uint8_t pdi_control = 0;
};

inline SmRegs read_sm(esc::Pdi& pdi, unsigned n) {
    uint8_t b[8];
    pdi.read(esc::reg::sm_base(n), b);
    SmRegs r;
    r.start = static_cast<uint16_t>(b[0] | (b[1] << 8));
    r.length = static_cast<uint16_t>(b[2] | (b[3] << 8));
    r.control = b[4];
    r.status = b[5];
    r.activate = b[6];
    r.pdi_control = b[7];
    return r;
}

// Sets or clears "deactivate SyncManager" in the PDI control register of SM n.
inline void set_sm_pdi_deactivated(esc::Pdi& pdi, unsigned n, bool deactivated) {
    uint8_t v = pdi.read_reg<uint8_t>(esc::reg::sm_base(n) + esc::reg::kSmPdiControl);
    v = deactivated ? static_cast<uint8_t>(v | esc::reg::kSmPdiDeactivate)
                    : static_cast<uint8_t>(v & ~esc::reg::kSmPdiDeactivate);
    pdi.write_reg<uint8_t>(esc::reg::sm_base(n) + esc::reg::kSmPdiControl, v);
}

// ESC configuration 0x0141 bit 0, device emulation (loaded from SII word 0): the ESC copies AL control into
// AL status itself (ESC datasheet, AL status; the ConfigData of IO terminals without a controller). Such a
// device has no state machine of its own that could refuse a request.
inline bool device_emulation(esc::Pdi& pdi) {
    return (pdi.read_reg<uint8_t>(esc::reg::kEscConfig) & 0x01) != 0;
}

// Holds SM n off from the PDI side until its state starts it (Init, an ESC reset, the way back from Safe-Op).
// A device with device emulation has nobody who would hold it: its SMs run as soon as the master enables
// them, in the state the ESC already reports, whenever the stack behind gets to look.
inline void hold_sm_until_started(esc::Pdi& pdi, unsigned n) {
    set_sm_pdi_deactivated(pdi, n, !device_emulation(pdi));
}

}  // namespace ecat
