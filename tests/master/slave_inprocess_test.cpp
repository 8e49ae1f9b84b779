// The master's AL state requests, mailbox and SDO client against the real slave stack, in process:
// esc::Esc + ecat::Stack + coe::CoeServer on the drive's object dictionary, the SII built by esi from the
// same description. The link hands each frame to the ESC and then runs the firmware, as the runtime does.
#include <gtest/gtest.h>
#include <unistd.h>

#include <deque>
#include <filesystem>
#include <memory>
#include <thread>
#include <vector>

#include "coe/sdo_server.hpp"
#include "ecat/application.hpp"
#include "ecat/stack.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "esi/sii.hpp"
#include "foe/image.hpp"
#include "foe/server.hpp"
#include "foe/store.hpp"
#include "master/coe.hpp"
#include "master/foe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "maxpos/maxpos.hpp"

#include "support/master_bring_up.hpp"
#include "support/wire_link.hpp"

using namespace master;

namespace {

struct Slave {
    esc::ManualClock clock;
    esc::SystemClock system_clock;
    bool real_time = false;     // DC tests: the ESC runs on CLOCK_MONOTONIC, as in ecat-slave
    bool firmware_runs = true;  // false: only the ESC answers frames, the stack behind is busy elsewhere
    const esc::Clock& clk() const { return real_time ? static_cast<const esc::Clock&>(system_clock) : clock; }
    od::DeviceDescription desc;
    od::Dictionary dict;
    std::unique_ptr<esc::Esc> esc;
    ecat::Application app;
    std::unique_ptr<ecat::Stack> stack;
    std::unique_ptr<coe::CoeServer> coe;
    std::filesystem::path store_dir;
    std::unique_ptr<foe::FirmwareStore> store;
    std::unique_ptr<foe::FoeServer> foe;

    explicit Slave(uint16_t mailbox_size, bool real = false) : real_time(real) {
        desc = maxpos::description();
        desc.standard_mailbox.out_size = mailbox_size;
        desc.standard_mailbox.in_start =
            static_cast<uint16_t>(desc.standard_mailbox.out_start + mailbox_size);
        desc.standard_mailbox.in_size = mailbox_size;
        maxpos::place_sync_managers(desc);
        dict = maxpos::dictionary(desc);
        clock.set(1'000'000'000);
        esc = std::make_unique<esc::Esc>(esc::EscConfig{}, clk());
        esc->load_eeprom(esi::build_sii(desc, dict));
        stack = std::make_unique<ecat::Stack>(*esc, dict, desc, app);
        coe = std::make_unique<coe::CoeServer>(dict, [this] { return stack->state(); });
        stack->add_handler(*coe);
        store_dir = std::filesystem::temp_directory_path() /
                    ("master-foe-" + std::to_string(::getpid()) + "-" + std::to_string(counter()++));
        foe::StoreConfig sc;
        sc.dir = store_dir;
        sc.identity = foe::ImageIdentity::from(desc.identity);
        sc.device_name = desc.identity.device_name;
        store = std::make_unique<foe::FirmwareStore>(sc);
        store->open();
        foe = std::make_unique<foe::FoeServer>(*store, foe::ServerConfig::from(desc));
        stack->add_handler(*foe);
        stack->poll(clk().now_ns());
    }
    ~Slave() {
        std::error_code ec;
        std::filesystem::remove_all(store_dir, ec);
    }
    static int& counter() {
        static int n = 0;
        return n;
    }
};

// The master's link to this slave: each frame through the ESC, then the firmware, as the runtime does.
struct SlaveLink final : test_support::WireLink {
    explicit SlaveLink(Slave& s)
        : WireLink([&s](std::vector<uint8_t>& f) {
              if (!s.real_time) s.clock.advance(20'000);
              const bool back = s.esc->process_frame(f);
              s.esc->tick();
              if (s.firmware_runs)
                  s.stack->poll(s.clk().now_ns());  // firmware after the reply, as the runtime does
              return back;
          }) {}
};

MasterOptions options() {
    return test_support::in_process_master_options();
}

class WithSlave : public ::testing::TestWithParam<uint16_t> {
  protected:
    WithSlave()
        : slave(GetParam()), link(slave), m(link, options()), mbx(m, Address::station(0x1001)), sdo(mbx) {}
    void SetUp() override { ASSERT_NO_FATAL_FAILURE(test_support::one_slave_in_preop(m, mbx, a)); }
    Slave slave;
    SlaveLink link;
    Master m;
    const Address a = Address::station(0x1001);
    Mailbox mbx;
    SdoClient sdo;
};

}  // namespace

TEST_P(WithSlave, MailboxLayoutComesFromTheSii) {
    EXPECT_EQ(mbx.config().out_size, GetParam());
    EXPECT_EQ(mbx.config().in_size, GetParam());
    EXPECT_EQ(mbx.config().protocols & 0x0004, 0x0004);  // CoE
}

TEST_P(WithSlave, ExpeditedUploadOfTheIdentity) {
    uint8_t b[4];
    auto n = sdo.upload(0x1018, 1, b);
    ASSERT_TRUE(n.ok()) << to_string(n.error());
    ASSERT_EQ(*n, 4u);
    EXPECT_EQ(b[0] | (b[1] << 8) | (b[2] << 16) | (b[3] << 24), 0x000000FB);
    auto sii_vendor = m.sii_read_u32(a, sii::VendorId);
    EXPECT_EQ(*sii_vendor, 0x000000FBu);  // SII and 0x1018 agree
}

TEST_P(WithSlave, StringUploadNormalOrSegmented) {
    std::array<uint8_t, 256> b{};
    auto n = sdo.upload(0x1008, 0, b);
    ASSERT_TRUE(n.ok()) << to_string(n.error());
    EXPECT_EQ(std::string(b.begin(), b.begin() + static_cast<long>(*n)), slave.desc.identity.device_name);
}

TEST_P(WithSlave, DownloadThenUploadGivesTheValueBack) {
    const uint8_t v[4] = {0x20, 0x00, 0x7A, 0x60};  // 0x607A0020
    ASSERT_EQ(sdo.download(0x1600, 1, v), Error::Ok) << std::hex << sdo.last_abort();
    uint8_t b[4];
    ASSERT_EQ(sdo.upload(0x1600, 1, b).value(), 4u);
    EXPECT_EQ(std::vector<uint8_t>(b, b + 4), std::vector<uint8_t>(v, v + 4));
}

TEST_P(WithSlave, CompleteAccessRoundTrip) {
    std::array<uint8_t, 512> all{};
    auto n = sdo.upload(0x1600, 0, all, true);
    ASSERT_TRUE(n.ok()) << to_string(n.error()) << " abort 0x" << std::hex << sdo.last_abort();
    const uint8_t count = all[0];
    ASSERT_GE(*n, 2u + 4u * count);
    EXPECT_EQ(all[1], 0);  // subindex 0 padded to 16 bits
    uint8_t first[4];
    ASSERT_TRUE(sdo.upload(0x1600, 1, first).ok());
    EXPECT_EQ(std::vector<uint8_t>(all.begin() + 2, all.begin() + 6), std::vector<uint8_t>(first, first + 4));
    // Write the same object back with complete access (segmented on a small mailbox).
    ASSERT_EQ(sdo.download(0x1600, 0, std::span<const uint8_t>(all.data(), *n), true), Error::Ok)
        << std::hex << sdo.last_abort();
}

TEST_P(WithSlave, AbortsCarryTheirCode) {
    uint8_t b[8];
    EXPECT_EQ(sdo.upload(0x5FFF, 0, b).error(), Error::SdoAbort);
    EXPECT_EQ(sdo.last_abort(), 0x06020000u);
    EXPECT_EQ(sdo_abort_text(sdo.last_abort()), "Object does not exist in the object dictionary");
    const uint8_t v[4] = {1, 2, 3, 4};
    EXPECT_EQ(sdo.download(0x1018, 1, v), Error::SdoAbort);
    EXPECT_EQ(sdo.last_abort(), 0x06010002u);
    // The mailbox still works afterwards.
    EXPECT_TRUE(sdo.upload(0x1018, 2, b).ok());
}

TEST_P(WithSlave, LostMailboxReadIsRecoveredWithTheRepeatRequest) {
    uint8_t b[4];
    // Send the request, let the slave answer, then lose the reply to the SM1 read.
    const uint8_t req[10] = {0x00, 0x20, 0x40, 0x18, 0x10, 0x02, 0, 0, 0, 0};
    ASSERT_EQ(mbx.send(MailboxType::CoE, req), Error::Ok);
    link.drop_next();
    MailboxMessage msg;
    ASSERT_EQ(mbx.receive(msg), Error::Ok);
    EXPECT_EQ(mbx.repeats(), 1u);
    ASSERT_EQ(msg.type, MailboxType::CoE);
    ASSERT_GE(msg.payload.size(), 10u);
    EXPECT_EQ(msg.payload[3] | (msg.payload[4] << 8), 0x1018);
    EXPECT_EQ(msg.payload[5], 2);
    // And the next exchange is in step.
    auto n = sdo.upload(0x1018, 1, b);
    ASSERT_TRUE(n.ok());
    EXPECT_EQ(b[0], 0xFB);
}

TEST_P(WithSlave, RefusedStateReportsTheAlCode) {
    AlStatus st;
    // Pre-Op -> Op is not a valid transition (0x0011), the master acknowledges the error.
    EXPECT_EQ(m.request_state(a, AlState::Op, &st), Error::AlRefused);
    EXPECT_EQ(st.code, 0x0011);
    EXPECT_EQ(st.state, 0x02);
    auto now = m.al_status(a);
    ASSERT_TRUE(now.ok());
    EXPECT_FALSE(now->error);
    EXPECT_EQ(now->state, 0x02);
    EXPECT_EQ(m.request_state(a, AlState::Init), Error::Ok);
}

TEST_P(WithSlave, ASecondMasterProcessAdoptsTheMailboxAndIsNotTakenForARepeat) {
    uint8_t b[4];
    ASSERT_TRUE(sdo.upload(0x1018, 1, b).ok());  // the slave now remembers counter 1
    // A new process: fresh Mailbox, counter state lost, slave still in PREOP.
    Mailbox again(m, a);
    ASSERT_EQ(again.adopt_current(), Error::Ok);
    EXPECT_EQ(again.config().out_size, GetParam());
    SdoClient sdo2(again);
    for (int i = 0; i < 9; ++i) {
        auto n = sdo2.upload(0x1018, 1, b);
        ASSERT_TRUE(n.ok()) << i << ": " << to_string(n.error());
        EXPECT_EQ(b[0], 0xFB);
    }
}

TEST_P(WithSlave, AdoptRefusesAMailboxThatIsNotSetUp) {
    ASSERT_EQ(m.request_state(a, AlState::Init), Error::Ok);
    const uint8_t off[16] = {};
    ASSERT_EQ(m.write(a, reg::Sm0, off), Error::Ok);
    Mailbox again(m, a);
    EXPECT_EQ(again.adopt_current(), Error::MailboxNotConfigured);
    SdoClient none(again);
    uint8_t b[4];
    EXPECT_EQ(none.upload(0x1018, 1, b).error(), Error::MailboxNotConfigured);
}

TEST_P(WithSlave, ProcessDataSessionReachesOpAndExchanges) {
    ProcessDataSession pd(m, a, sdo);
    ASSERT_EQ(pd.discover(), Error::Ok);
    const auto& l = pd.layout();
    // The layout the slave expects: its own SM defaults and PDO sizes.
    ASSERT_GE(slave.desc.sync_managers.size(), 4u);
    ASSERT_EQ(l.sms.size(), 2u);
    EXPECT_EQ(l.sms[0].index, 2);
    EXPECT_TRUE(l.sms[0].outputs);
    EXPECT_EQ(l.sms[1].index, 3);
    EXPECT_FALSE(l.sms[1].outputs);
    EXPECT_EQ(l.sms[0].start, slave.desc.sync_managers[2].start);
    EXPECT_EQ(l.sms[1].start, slave.desc.sync_managers[3].start);
    EXPECT_EQ(l.sms[0].length, slave.desc.sync_managers[2].default_size);
    EXPECT_EQ(l.sms[1].length, slave.desc.sync_managers[3].default_size);
    EXPECT_EQ(l.pdos(true), (std::vector<uint16_t>{0x1600}));
    EXPECT_EQ(l.pdos(false), (std::vector<uint16_t>{0x1A00}));
    ASSERT_EQ(pd.configure(), Error::Ok) << std::hex << sdo.last_abort();
    AlStatus st;
    ASSERT_EQ(pd.request_state(AlState::SafeOp, std::chrono::microseconds(200), &st), Error::Ok)
        << "AL code 0x" << std::hex << st.code;
    ASSERT_EQ(pd.request_state(AlState::Op, std::chrono::microseconds(200), &st), Error::Ok)
        << "AL code 0x" << std::hex << st.code;
    EXPECT_EQ(pd.expected_wkc(), 3);
    ASSERT_EQ(pd.run(50, std::chrono::microseconds(100)), Error::Ok);
    EXPECT_EQ(pd.last_wkc(), 3);
    EXPECT_EQ(pd.stats().wkc_errors, 0u);
    EXPECT_EQ(pd.stats().lost, 0u);
    // Outputs reach the dictionary: controlword (0x6040) is the first mapped RxPDO entry.
    pd.outputs()[0] = 0x06;
    pd.outputs()[1] = 0x00;
    ASSERT_EQ(pd.run(3, std::chrono::microseconds(100)), Error::Ok);
    EXPECT_EQ(slave.dict.get<uint16_t>(0x6040, 0), 0x0006);
    // Inputs come from it: statusword (0x6041) is the first mapped TxPDO entry.
    EXPECT_EQ(pd.inputs()[0] | (pd.inputs()[1] << 8), slave.dict.get<uint16_t>(0x6041, 0));
    EXPECT_EQ(m.al_status(a)->state, 0x08);
    // The master's own longest pause between two cycles (what a slave's watchdog sees): counted from the
    // last reset, at least as long as the caller slept.
    pd.reset_gap_max();
    EXPECT_EQ(pd.stats().gap_max.count(), 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
    ASSERT_EQ(pd.cycle(), Error::Ok);
    EXPECT_GE(pd.stats().gap_max, std::chrono::milliseconds(30));
}

TEST_P(WithSlave, SdoInformationListsAndDescribesTheDictionary) {
    auto list = sdo.od_list(1);
    ASSERT_TRUE(list.ok()) << to_string(list.error()) << std::hex << sdo.last_abort();
    ASSERT_EQ(list->size(), slave.dict.objects().size());  // fragmented on the small mailbox
    for (std::size_t i = 0; i < list->size(); ++i)
        EXPECT_EQ((*list)[i], slave.dict.objects()[i].index);
    auto od = sdo.object_description(0x1018);
    ASSERT_TRUE(od.ok()) << to_string(od.error());
    EXPECT_EQ(od->name, slave.dict.find(0x1018)->name);
    EXPECT_EQ(od->object_code, 9);
    EXPECT_EQ(od->max_subindex, slave.dict.find(0x1018)->max_subindex());
    auto e = sdo.entry_description(0x1018, 1, 0x07);
    ASSERT_TRUE(e.ok()) << to_string(e.error());
    EXPECT_EQ(e->data_type, 0x0007);
    EXPECT_EQ(e->bit_length, 32);
    EXPECT_EQ(e->access & 0x3F, 0x07);
    EXPECT_EQ(e->name, slave.dict.find(0x1018, 1)->name);
    auto d = sdo.entry_description(0x1600, 1, 0x10);  // with the default value
    ASSERT_TRUE(d.ok());
    ASSERT_EQ(d->values.size(), 4u);
    EXPECT_EQ(d->values[3], 0x60);
    EXPECT_EQ(sdo.object_description(0x5FFF).error(), Error::SdoAbort);
    EXPECT_EQ(sdo.last_abort(), 0x06020000u);
    // Plain SDO traffic still in step afterwards.
    uint8_t b[4];
    EXPECT_TRUE(sdo.upload(0x1018, 1, b).ok());
}

TEST_P(WithSlave, UnsupportedProtocolGetsAMailboxErrorReply) {
    const uint8_t voe[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    ASSERT_EQ(mbx.send(MailboxType::VoE, voe), Error::Ok);
    MailboxMessage msg;
    ASSERT_EQ(mbx.receive(msg), Error::Ok);
    EXPECT_EQ(msg.type, MailboxType::Error);
    ASSERT_GE(msg.payload.size(), 4u);
    EXPECT_EQ(msg.payload[0] | (msg.payload[1] << 8), 0x0001);  // mailbox command error
    EXPECT_EQ(msg.payload[2] | (msg.payload[3] << 8), 0x0002);  // unsupported protocol
    // The mailbox stays in step for the next exchange.
    uint8_t b[4];
    EXPECT_TRUE(sdo.upload(0x1018, 1, b).ok());
}

TEST_P(WithSlave, ReceiveOnAnEmptyMailboxTimesOut) {
    MailboxMessage msg;
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_EQ(mbx.receive(msg, std::chrono::milliseconds(30)), Error::MailboxTimeout);
    EXPECT_GE(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(30));
    const uint8_t big[200] = {};
    EXPECT_EQ(mbx.send(MailboxType::CoE, std::span<const uint8_t>(big, mbx.max_out_payload() + 1)),
              Error::InvalidArgument);
}

TEST_P(WithSlave, DeviceIdentificationReturnsTheStationAlias) {
    slave.esc->write_reg<uint16_t>(0x0012, 0x4242);  // as the SII alias word would have loaded it
    auto id = m.identify(a);
    ASSERT_TRUE(id.ok()) << to_string(id.error());
    EXPECT_EQ(*id, 0x4242);
    auto st = m.al_status(a);
    ASSERT_TRUE(st.ok());
    EXPECT_FALSE(st->id_loaded);  // request withdrawn
    EXPECT_EQ(st->state, 0x02);
    EXPECT_EQ(st->code, 0x0000);
}

INSTANTIATE_TEST_SUITE_P(MailboxSizes, WithSlave, ::testing::Values(uint16_t{128}, uint16_t{32}));

TEST(ProcessDataDc, Sync0RunsAndTheSlaveReachesOpInDcMode) {
    Slave slave(128, true);
    SlaveLink link(slave);
    Master m(link, options());
    const Address a = Address::station(0x1001);
    Mailbox mbx(m, a);
    ASSERT_NO_FATAL_FAILURE(test_support::one_slave_in_preop(m, mbx, a));
    SdoClient sdo(mbx);
    ProcessDataSession pd(m, a, sdo);
    ASSERT_EQ(pd.discover(), Error::Ok);
    DcConfig dc;
    dc.enable = true;
    dc.cycle_ns = 1'000'000;
    dc.start_delay = std::chrono::milliseconds(20);
    ASSERT_EQ(pd.configure(dc), Error::Ok) << std::hex << sdo.last_abort();
    EXPECT_EQ(m.read_reg<uint8_t>(a, 0x0981).value(), 0x03);
    EXPECT_EQ(m.read_reg<uint32_t>(a, 0x09A0).value(), 1'000'000u);
    AlStatus st;
    ASSERT_EQ(pd.request_state(AlState::SafeOp, std::chrono::microseconds(1000), &st), Error::Ok)
        << "AL code 0x" << std::hex << st.code;
    ASSERT_EQ(pd.request_state(AlState::Op, std::chrono::microseconds(1000), &st), Error::Ok)
        << "AL code 0x" << std::hex << st.code;
    ASSERT_EQ(pd.run(100, std::chrono::microseconds(1000)), Error::Ok);
    EXPECT_EQ(pd.stats().wkc_errors, 0u);
    // The reference clock's system time follows the master's (set through the offset, 0x0920).
    EXPECT_NE(pd.reference_time(), 0u);
    // SYNC0 runs: the slave saw it (how many depends on how often it was polled on a loaded machine), and
    // the ESC's "next SYNC0" time (0x0990) moves on by whole cycles.
    EXPECT_GT(slave.stack->stats().sync0_events, 0u);
    const uint64_t next1 = m.read_reg<uint64_t>(a, 0x0990).value();
    ASSERT_EQ(pd.run(10, std::chrono::microseconds(1000)), Error::Ok);
    const uint64_t next2 = m.read_reg<uint64_t>(a, 0x0990).value();
    EXPECT_GT(next2, next1);
    EXPECT_EQ((next2 - next1) % dc.cycle_ns, 0u);
    EXPECT_EQ(slave.stack->sync_mode(), ecat::SyncMode::DcSync0);
    EXPECT_EQ(m.al_status(a)->state, 0x08);
}

TEST(FoeWithSlave, FirmwareWrittenInBootstrapIsReadBack) {
    Slave slave(128);
    SlaveLink link(slave);
    Master m(link, options());
    const Address a = Address::station(0x1001);
    // Outside Bootstrap a firmware write is refused with an FoE error.
    Mailbox std_mbx(m, a);
    ASSERT_NO_FATAL_FAILURE(test_support::one_slave_in_preop(m, std_mbx, a));
    FoeClient refused(std_mbx);
    const std::vector<uint8_t> payload(3000, 0x5A);
    const auto image = foe::build_image(payload, foe::ImageIdentity::from(slave.desc.identity), 0x01300000);
    EXPECT_EQ(refused.write(slave.desc.identity.device_name, image), Error::FoeError);
    EXPECT_EQ(refused.last_error(), 0x8008u);  // bootstrap only
    // INIT -> BOOT with the bootstrap mailbox from the SII.
    ASSERT_EQ(m.request_state(a, AlState::Init), Error::Ok);
    Mailbox boot(m, a);
    ASSERT_EQ(boot.configure_from_sii(true), Error::Ok);
    EXPECT_EQ(boot.config().out_size, slave.desc.bootstrap_mailbox.out_size);
    AlStatus st;
    ASSERT_EQ(m.request_state(a, AlState::Boot, &st), Error::Ok) << std::hex << st.code;
    FoeClient foe(boot);
    ASSERT_EQ(foe.write(slave.desc.identity.device_name, image), Error::Ok)
        << std::hex << foe.last_error() << " " << foe.last_error_text();
    auto back = foe.read(slave.desc.identity.device_name);
    ASSERT_TRUE(back.ok()) << to_string(back.error()) << std::hex << foe.last_error();
    EXPECT_EQ(*back, image);
    // A name that does not exist.
    EXPECT_EQ(foe.read("nothing.bin").error(), Error::FoeError);
    EXPECT_EQ(foe.last_error() & 0xFF00u, 0x8000u);
    // A transfer given up on leaves its late answer (here the error for a name that does not exist) in SM1:
    // the next transfer is not answered with it.
    boot.set_timeout(std::chrono::milliseconds(20));
    slave.firmware_runs = false;
    EXPECT_EQ(foe.read("nothing.bin").error(), Error::MailboxTimeout);
    slave.firmware_runs = true;
    slave.stack->poll(slave.clk().now_ns());
    boot.set_timeout(std::chrono::milliseconds(1000));
    ASSERT_EQ(foe.write(slave.desc.identity.device_name, image), Error::Ok)
        << std::hex << foe.last_error() << " " << foe.last_error_text();
    ASSERT_EQ(m.request_state(a, AlState::Init), Error::Ok);
}
