// Group pd, inputs of any device: the application refreshes the input SM every cycle (not only through the
// CiA 402 tests: an IO device whose application stopped writing its inputs shows the same values forever).
#include <algorithm>
#include <thread>

#include "esc/wire/registers.hpp"
#include "testkit.hpp"

namespace conform {

namespace {

using master::Error;
constexpr const char* kFresh =
    "ETG.1000.6 process data (SAFEOP and OP: inputs valid, written by the application); ESC datasheet "
    "SyncManager status 0x0805+8n bit 0 (buffer written) and bits 4-5 (last written buffer)";

// How many new input buffers a device must write, each after a read of the master, within the window.
constexpr unsigned kFreshWanted = 5;

// The master reads the inputs (LRW), waits, and reads the input SM's status: bit 0 (write event) says
// that the application completed a new buffer since that read, bits 4-5 which buffer it wrote last (ESC
// datasheet, SyncManager status). A device whose application wrote the inputs once and stopped shows
// neither after the first reads, whatever values the inputs hold (a value that never changes is legal,
// a buffer that is never written again is not). Any sync mode is fine: SM-synchronous devices write after
// each frame, free-running ones on their own cycle, both well within the window.
Outcome inputs_refreshed(Context& ctx, uint8_t state) {
    CONFORM_NEED(ctx.need_pd_layout());
    Error e = state == 8 ? ctx.to_op() : ctx.to_safeop();
    if (e != Error::Ok) return fail("cannot reach " + state_text(state) + ": " + err(e));
    if (!ctx.pds || !ctx.pds->layout().input_bytes())
        return skip("no inputs (no TxPDO assigned to an inputs SM)");
    const unsigned sm = ctx.pds->layout().first(false)->index;  // the first inputs SM with data
    const auto reg = static_cast<uint16_t>(esc::reg::sm_base(sm) + esc::reg::kSmStatus);
    (void)ctx.cycle(3);
    const auto end = std::chrono::steady_clock::now() + ctx.ms(500);
    unsigned reads = 0, fresh = 0;
    int last = -1;
    std::string trace;
    std::vector<uint8_t> before(ctx.pds->inputs().begin(), ctx.pds->inputs().end());
    unsigned changed = 0;
    while (fresh < kFreshWanted && std::chrono::steady_clock::now() < end) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        auto st = ctx.rd<uint8_t>(reg);
        if (!st) return fail("SM" + dec(sm) + " status unreadable", err(st.error()));
        const bool written = (*st & esc::reg::kSmStatusIrqWrite) || (last >= 0 && ((*st ^ last) & 0x30));
        if (trace.size() < 48) trace += hex(*st, 2) + " ";
        last = *st;
        (void)ctx.pds->cycle();  // reads the inputs: the write event clears, the next buffer is the device's
        // Inputs that changed since the last read were written too, whatever the status showed.
        const bool moved = !std::equal(before.begin(), before.end(), ctx.pds->inputs().begin());
        before.assign(ctx.pds->inputs().begin(), ctx.pds->inputs().end());
        if (reads > 0 && (written || moved)) ++fresh;
        if (reads > 0 && moved) ++changed;
        ++reads;
    }
    const std::string got = dec(fresh) + " new buffers after " + dec(reads) + " reads (" + dec(changed) +
                            " with changed inputs; SM" + dec(sm) + " status " + trace +
                            (trace.size() >= 48 ? "...)" : ")");
    if (fresh < kFreshWanted)
        return fail("inputs not refreshed in " + state_text(state) +
                        ": the input SM's status never shows a buffer written and the inputs do not change",
                    got, "a new input buffer after each read (" + dec(kFreshWanted) + " within the window)");
    return pass("inputs refreshed", got);
}

}  // namespace

void add_io_tests(Catalogue& c) {
    Adder add{c, "pd"};
    add(
        "safeop.inputs_refreshed",
        "SAFEOP: the application writes a new input buffer after each read (SM status write event)", kFresh,
        [](Context& ctx) { return inputs_refreshed(ctx, 4); }, "inputs (layout over CoE, else from the SII)");
    add(
        "op.inputs_refreshed",
        "OP: the application writes a new input buffer after each read (SM status write event)", kFresh,
        [](Context& ctx) { return inputs_refreshed(ctx, 8); }, "inputs (layout over CoE, else from the SII)");
}

}  // namespace conform
