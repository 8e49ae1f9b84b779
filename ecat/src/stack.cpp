#include "ecat/stack.hpp"

#include <algorithm>
#include <ostream>

namespace ecat {

void Stack::prefetch() const {
    const auto lines = [](const void* p, std::size_t n) {
        const auto* b = static_cast<const char*>(p);
        for (std::size_t off = 0; off < std::min<std::size_t>(n, 4 * 64); off += 64)
            __builtin_prefetch(b + off, 1, 3);
    };
    lines(&cycle_, sizeof cycle_);
    lines(&esm_, sizeof esm_);
    lines(&sync_, sizeof sync_);
    lines(&ctx_, sizeof ctx_);
    lines(&pd_, sizeof pd_);
    lines(&mailbox_, 2 * 64);
    lines(&stats_, 64);
}
namespace {

std::size_t max_mailbox(const od::DeviceDescription& d) {
    return std::max<std::size_t>({d.standard_mailbox.out_size, d.standard_mailbox.in_size,
                                  d.bootstrap_mailbox.out_size, d.bootstrap_mailbox.in_size});
}

}  // namespace

Stack::Stack(esc::Pdi& pdi, od::Dictionary& dictionary, const od::DeviceDescription& description,
             Application& application, IrqLine irq)
    : mailbox_(pdi, max_mailbox(description)),
      pd_(dictionary),
      ctx_{pdi, dictionary, description, application, mailbox_,
           pd_, stats_,     faults_,     nullptr,     process_data_sms(description)},
      sync_(ctx_),
      esm_(ctx_, sync_, cycle_),
      cycle_(ctx_, esm_, sync_, std::move(irq)) {
    // Init, no error; interrupts for the events this stack serves.
    cycle_.set_up_registers();
    esm_.write_status();
    // Mailbox and process-data SMs stay deactivated from the PDI side until their state starts them.
    for (unsigned n = 0; n < 4; ++n)
        hold_sm_until_started(pdi, n);
    sync_.init_objects();
}

Stack::~Stack() = default;

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

}  // namespace ecat
