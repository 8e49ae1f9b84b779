// The master's per-cycle and per-message paths allocate nothing (ProcessDataSession::cycle, Mailbox
// send/receive, SDO expedited transfers), measured with a counting global operator new against the real
// ESC and slave stack behind a fixed-buffer link.
#include <gtest/gtest.h>

#include <array>

#include "coe/sdo_server.hpp"
#include "ecat/application.hpp"
#include "ecat/stack.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "esi/sii.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "maxpos/maxpos.hpp"
#include "support/alloc_counter.hpp"
#include "support/fixed_link.hpp"
#include "support/master_bring_up.hpp"

using namespace master;

namespace {}  // namespace

TEST(MasterAllocations, CyclesAndMailboxMessagesAllocateNothing) {
    esc::ManualClock clock;
    clock.set(1'000'000'000);
    od::DeviceDescription desc = maxpos::description();
    od::Dictionary dict = maxpos::dictionary(desc);
    esc::Esc esc(esc::EscConfig{}, clock);
    esc.load_eeprom(esi::build_sii(desc, dict));
    ecat::Application app;
    ecat::Stack stack(esc, dict, desc, app);
    coe::CoeServer coe(dict, [&] { return stack.state(); });
    stack.add_handler(coe);
    test_support::FixedLink link([&](std::span<uint8_t> f) {
        clock.advance(20'000);
        const bool back = esc.process_frame(f);
        esc.tick();
        stack.poll(clock.now_ns());
        return back;
    });
    MasterOptions o;
    o.timeout = std::chrono::milliseconds(20);
    Master m(link, o);
    const Address a = Address::station(0x1001);
    Mailbox mbx(m, a);
    ASSERT_NO_FATAL_FAILURE(test_support::one_slave_in_preop(m, mbx, a));
    SdoClient sdo(mbx);
    ProcessDataSession pd(m, a, sdo);
    ASSERT_EQ(pd.discover(), Error::Ok);
    ASSERT_EQ(pd.configure(), Error::Ok);
    ASSERT_EQ(pd.request_state(AlState::SafeOp, std::chrono::microseconds(0)), Error::Ok);
    ASSERT_EQ(pd.request_state(AlState::Op, std::chrono::microseconds(0)), Error::Ok);
    uint8_t b[4];
    ASSERT_TRUE(sdo.upload(0x1018, 1, b).ok());  // warm-up: buffers sized

    const alloc_counter::Scope counting;
    for (int i = 0; i < 200; ++i) {
        pd.outputs()[0] = static_cast<uint8_t>(i);
        ASSERT_EQ(pd.cycle(), Error::Ok);
    }
    for (int i = 0; i < 20; ++i) {
        ASSERT_TRUE(sdo.upload(0x1018, 1, b).ok());
        const uint8_t v[4] = {0x20, 0x00, 0x7A, 0x60};
        ASSERT_EQ(sdo.download(0x1600, 1, v), Error::SdoAbort);  // RWP: refused in OP, still no allocation
    }
    EXPECT_EQ(counting.count(), 0u) << "allocations on the cycle / mailbox paths (master and slave side)";
    EXPECT_EQ(pd.stats().wkc_errors, 0u);
}
