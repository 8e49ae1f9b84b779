// device::Device built from an od::Product made by hand (as the ESI reader makes them): a digital IO
// terminal without mailbox (process data in SM0/SM1, reaches Op with process data only, the IO model's
// mirror / counter / keep and `set`), and an analog terminal with CoE but no drive (SDO, no FoE, no drive;
// every mailbox protocol it does not serve answered with the mailbox error "unsupported protocol").
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "device/control.hpp"
#include "device/device.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "esi/device/product.hpp"
#include "esi/esi_reader.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "od/product.hpp"
#include "products.hpp"

#include "powered_device.hpp"
#include "support/master_bring_up.hpp"
#include "support/temp_dir.hpp"
#include "support/wire_link.hpp"

using namespace master;
using test_products::byte_outputs_terminal;
using test_products::coe_terminal;
using test_products::io_terminal;
using test_products::two_sm_terminal;

namespace {

// One device made from `product`, "powered" on a manual clock, with a state directory of its own.
struct Unit : test_device::PoweredDevice {
    std::filesystem::path dir;

    explicit Unit(std::shared_ptr<const od::Product> product, const esc::EscConfig& config = {})
        : dir(test_support::make_temp_dir("softecat-product-")) {
        device::DeviceOptions o;
        o.product = std::move(product);
        o.state_dir = dir;
        power_on(o, config);
    }
    ~Unit() {
        dev.reset();
        std::error_code ec;
        std::filesystem::remove_all(dir, ec);
    }
};

using UnitLink = test_device::PoweredLink;

uint16_t u16(std::span<const uint8_t> b, std::size_t at) {
    return static_cast<uint16_t>(b[at] | (b[at + 1] << 8));
}

// Safe-Op, then Op, `fill` before every exchange, then `cycles` more exchanges in Op, each without error.
void session_to_op(ProcessDataSession& pd, const std::function<void()>& fill, uint64_t cycles) {
    AlStatus st;
    ASSERT_EQ(pd.request_state(AlState::SafeOp, std::chrono::microseconds(100), &st, fill), Error::Ok)
        << "AL code 0x" << std::hex << st.code;
    ASSERT_EQ(pd.request_state(AlState::Op, std::chrono::microseconds(100), &st, fill), Error::Ok)
        << "AL code 0x" << std::hex << st.code;
    ASSERT_EQ(pd.run(cycles, std::chrono::microseconds(100), fill), Error::Ok);
}

// The one slave addressed and taken to Pre-Op, no mailbox configured.
void preop_without_mailbox(Master& m, Address a) {
    ASSERT_NO_FATAL_FAILURE(test_support::one_slave_addressed(m));
    AlStatus st;
    ASSERT_EQ(m.request_state(a, AlState::PreOp, &st), Error::Ok) << "AL code 0x" << std::hex << st.code;
}

// A device with CoE made from `product`, addressed and in Pre-Op with its mailbox, and an SDO client.
struct CoeUnitInPreOp {
    explicit CoeUnitInPreOp(std::shared_ptr<const od::Product> product) : u(std::move(product)) {}
    void to_preop() { ASSERT_NO_FATAL_FAILURE(test_support::one_slave_in_preop(m, mbx, a)); }
    Unit u;
    UnitLink link{u};
    Master m{link, test_support::in_process_master_options()};
    const Address a = Address::station(0x1001);
    Mailbox mbx{m, a};
    SdoClient sdo{mbx};
};

// A device without mailbox made from `product` (on an ESC of that configuration), the in-process master
// before it and a process-data session for it, its layout to be read from the SII (discover_sii).
struct SiiUnit {
    explicit SiiUnit(std::shared_ptr<const od::Product> product, const esc::EscConfig& config = {})
        : u(std::move(product), config) {}
    Unit u;
    UnitLink link{u};
    Master m{link, test_support::in_process_master_options()};
    const Address a = Address::station(0x1001);
    ProcessDataSession pd{m, std::span<const Address>(&a, 1)};
};

}  // namespace

TEST(ProductWithoutMailbox, HasOnlyTheProcessDataPartsAndSaysItsWarningsOnce) {
    Unit u(io_terminal());
    EXPECT_FALSE(u.dev->has_coe());
    EXPECT_FALSE(u.dev->has_foe());
    EXPECT_FALSE(u.dev->has_parameters());
    EXPECT_FALSE(u.dev->has_drive());
    ASSERT_NE(u.dev->io_model(), nullptr);
    const std::string log = u.log.str();
    const std::string w = "Element 'Info/VendorSpecific' is not emulated";
    ASSERT_NE(log.find(w), std::string::npos) << log;
    EXPECT_EQ(log.find(w), log.rfind(w));
    // Drive commands have no machine to act on.
    EXPECT_EQ(device::ControlSocket::apply(*u.dev, "input 1 on").rfind("error:", 0), 0u);
}

TEST(ProductWithoutMailbox, ReachesOpWithProcessDataOnlyAndItsInputsFollowTheDefaultModel) {
    Unit u(io_terminal());
    UnitLink link(u);
    Master m(link, test_support::in_process_master_options());
    const Address a = Address::station(0x1001);
    ASSERT_NO_FATAL_FAILURE(preop_without_mailbox(m, a));
    AlStatus st;

    ProcessDataSession pd(m, std::span<const Address>(&a, 1));
    ASSERT_EQ(pd.discover_sii(0), Error::Ok);
    const ProcessDataLayout& l = pd.layout(0);
    ASSERT_EQ(l.sms.size(), 2u);
    EXPECT_EQ(l.sms[0].index, 0);
    EXPECT_EQ(l.sms[1].index, 1);
    EXPECT_EQ(l.sms[0].start, 0x0F00);
    EXPECT_EQ(l.sms[1].start, 0x1000);
    ASSERT_EQ(l.output_bytes(), 3u);
    ASSERT_EQ(l.input_bytes(), 5u);
    ASSERT_EQ(pd.configure(), Error::Ok);
    auto fill = [&] {
        auto o = pd.outputs();
        o[0] = 0x34;
        o[1] = 0x12;
        o[2] = 0x01;  // Output = 1
    };
    ASSERT_EQ(pd.request_state(AlState::SafeOp, std::chrono::microseconds(100), &st, fill), Error::Ok)
        << "AL code 0x" << std::hex << st.code;
    {
        const Error e = pd.request_state(AlState::Op, std::chrono::microseconds(100), &st, fill);
        std::string regs;
        for (uint16_t r :
             {0x0130, 0x0134, 0x0220, 0x0440, 0x0800, 0x0802, 0x0804, 0x0806, 0x0808, 0x080A, 0x080C, 0x080E})
            regs += " " + std::to_string(r) + "=" + std::to_string(m.read_reg<uint16_t>(a, r).value());
        ASSERT_EQ(e, Error::Ok) << "AL code 0x" << std::hex << st.code << regs << " " << u.log.str();
    }
    EXPECT_EQ(u.dev->stack().state(), od::AlState::Op);
    EXPECT_EQ(pd.expected_wkc(), 3);

    ASSERT_EQ(pd.run(5, std::chrono::microseconds(100), fill), Error::Ok);
    EXPECT_EQ(pd.last_wkc(), 3);
    // The output taken, and shown by entry name with its value.
    EXPECT_EQ(u.dev->dictionary().get<uint16_t>(0x7000, 1), 0x1234);
    const std::string status = device::ControlSocket::apply(*u.dev, "status");
    EXPECT_NE(status.find("ok state OP"), std::string::npos) << status;
    EXPECT_NE(status.find("0x7000:01 \"Value\"=4660"), std::string::npos) << status;
    EXPECT_NE(status.find("0x7000:02 \"Output\"=1"), std::string::npos) << status;
    EXPECT_NE(status.find("0x6000:03 \"Status\"=4660"), std::string::npos) << status;
    // Mirror, counter (wrapping at 8 bits), kept value.
    auto in = pd.inputs();
    EXPECT_EQ(u16(in, 0), 0x1234);
    EXPECT_EQ(u16(in, 3), 0x1234);
    const uint8_t c0 = in[2];
    ASSERT_EQ(pd.cycle(), Error::Ok);
    const uint8_t c1 = pd.inputs()[2];
    EXPECT_EQ(static_cast<uint8_t>(c1 - c0), 1);
    // Exactly one count per process-data cycle: 260 cycles past 250 wrap.
    for (int i = 0; i < 10; ++i)
        ASSERT_EQ(pd.cycle(), Error::Ok);
    EXPECT_EQ(static_cast<uint8_t>(pd.inputs()[2] - c1), 10);

    // Set at run time, by name and by index:subindex: held there, neither mirrored nor counted.
    EXPECT_EQ(device::ControlSocket::apply(*u.dev, "set Status 0x55AA"), "ok 0x6000:03=21930");
    EXPECT_EQ(device::ControlSocket::apply(*u.dev, "set 0x6000:2 7"), "ok 0x6000:02=7");
    EXPECT_EQ(device::ControlSocket::apply(*u.dev, "set Inputs/Value 9"), "ok 0x6000:01=9");
    for (int i = 0; i < 3; ++i)
        ASSERT_EQ(pd.cycle(), Error::Ok);
    in = pd.inputs();
    EXPECT_EQ(u16(in, 0), 9);
    EXPECT_EQ(in[2], 7);
    EXPECT_EQ(u16(in, 3), 0x55AA);
    EXPECT_EQ(device::ControlSocket::apply(*u.dev, "get Cycle Counter").rfind("error:", 0), 0u);  // 2 words
    EXPECT_EQ(device::ControlSocket::apply(*u.dev, "get \"cycle counter\""),
              "ok 0x6000:02 \"Cycle Counter\"=7");
    // Ambiguous names, outputs, out-of-range values and unknown entries are refused.
    EXPECT_NE(device::ControlSocket::apply(*u.dev, "set Value 1").find("names 2 entries"), std::string::npos);
    EXPECT_EQ(device::ControlSocket::apply(*u.dev, "set Output 1").rfind("error:", 0), 0u);
    EXPECT_EQ(device::ControlSocket::apply(*u.dev, "set Status 65536").rfind("error:", 0), 0u);
    EXPECT_EQ(device::ControlSocket::apply(*u.dev, "set 0x6000:09 1").rfind("error:", 0), 0u);
    EXPECT_EQ(u16(pd.inputs(), 3), 0x55AA);
}

// An entry mapped both as output and as input holds what the master writes: the input model neither counts it
// (although its name says counter) nor changes it, and the input shows the output written; an input-only
// counter beside it still counts.
TEST(ProductWithoutMailbox, AnEntryMappedBothWaysEchoesTheOutputAndIsNotModelled) {
    Unit u(test_products::echo_terminal());
    UnitLink link(u);
    Master m(link, test_support::in_process_master_options());
    const Address a = Address::station(0x1001);
    ASSERT_NO_FATAL_FAILURE(preop_without_mailbox(m, a));
    ProcessDataSession pd(m, std::span<const Address>(&a, 1));
    ASSERT_EQ(pd.discover_sii(0), Error::Ok);
    ASSERT_EQ(pd.layout(0).output_bytes(), 2u);
    ASSERT_EQ(pd.layout(0).input_bytes(), 4u);
    ASSERT_EQ(pd.configure(), Error::Ok);
    uint16_t written = 0x0100;
    auto fill = [&] {
        auto o = pd.outputs();
        o[0] = static_cast<uint8_t>(written);
        o[1] = static_cast<uint8_t>(written >> 8);
    };
    AlStatus st;
    ASSERT_EQ(pd.request_state(AlState::SafeOp, std::chrono::microseconds(100), &st, fill), Error::Ok)
        << "AL code 0x" << std::hex << st.code;
    ASSERT_EQ(pd.request_state(AlState::Op, std::chrono::microseconds(100), &st, fill), Error::Ok)
        << "AL code 0x" << std::hex << st.code;
    for (uint16_t v : {uint16_t{7}, uint16_t{7}, uint16_t{8}, uint16_t{0x1234}}) {
        written = v;
        const uint16_t cycles_before = u16(pd.inputs(), 2);
        ASSERT_EQ(pd.run(3, std::chrono::microseconds(100), fill), Error::Ok);
        EXPECT_EQ(u16(pd.inputs(), 0), v) << "the input shows the output written";
        EXPECT_EQ(u.dev->dictionary().get<uint16_t>(0x6000, 0), v);
        EXPECT_NE(u16(pd.inputs(), 2), cycles_before) << "the input-only counter counts";
    }
}

// Outputs lost: an IO terminal's outputs go to their safe state, 0 (EL2xxx switch their outputs off on the
// watchdog; the ESC's process-data watchdog: the PDI side sets the outputs safe), whether the master leaves
// Op or stops writing (watchdog); they come back with the next outputs written in Op.
TEST(ProductWithoutMailbox, LostOutputsGoToTheirSafeStateZero) {
    for (const int variant : {0, 1, 2, 3}) {
        const bool watchdog = variant & 1;
        const bool registers = variant & 2;
        SCOPED_TRACE(std::string(watchdog ? "watchdog" : "master leaves Op") +
                     (registers ? ", outputs SM on 0x0F00" : ", outputs SM in the RAM"));
        // The terminal's own SM0 on the ESC's digital-output registers 0x0F00 (its writes trigger the SM
        // watchdog, decisions/esc.md), or the process data in ordinary SyncManagers in the RAM.
        auto p = std::make_shared<od::Product>(*io_terminal());
        if (!registers)
            p->description.sync_managers = {test_products::sm(od::SmKind::Outputs, 0x1100, 3, 0x64),
                                            test_products::sm(od::SmKind::Inputs, 0x1180, 5, 0x20)};
        Unit u(p);
        UnitLink link(u);
        Master m(link, test_support::in_process_master_options());
        const Address a = Address::station(0x1001);
        ASSERT_NO_FATAL_FAILURE(preop_without_mailbox(m, a));
        AlStatus st;
        ProcessDataSession pd(m, std::span<const Address>(&a, 1));
        ASSERT_EQ(pd.discover_sii(0), Error::Ok);
        ASSERT_EQ(pd.configure(), Error::Ok);
        auto fill = [&] {
            auto o = pd.outputs();
            o[0] = 0x34;
            o[1] = 0x12;
            o[2] = 0x01;
        };
        ASSERT_EQ(pd.request_state(AlState::SafeOp, std::chrono::microseconds(100), &st, fill), Error::Ok);
        ASSERT_EQ(pd.request_state(AlState::Op, std::chrono::microseconds(100), &st, fill), Error::Ok);
        ASSERT_EQ(pd.run(5, std::chrono::microseconds(100), fill), Error::Ok);
        ASSERT_EQ(u.dev->dictionary().get<uint16_t>(0x7000, 1), 0x1234);
        ASSERT_EQ(u.dev->dictionary().get<uint8_t>(0x7000, 2), 1);
        if (watchdog) {
            // No process data for 500 ms: the SM watchdog (100 ms by default) expires.
            for (int i = 0; i < 500; ++i) {
                u.clock.advance(1'000'000);
                u.service();
            }
            EXPECT_NE(u.dev->stack().state(), od::AlState::Op);
        } else {
            ASSERT_EQ(m.request_state(a, AlState::SafeOp, &st), Error::Ok);
        }
        EXPECT_EQ(u.dev->dictionary().get<uint16_t>(0x7000, 1), 0);
        EXPECT_EQ(u.dev->dictionary().get<uint8_t>(0x7000, 2), 0);
        const std::string status = device::ControlSocket::apply(*u.dev, "status");
        EXPECT_NE(status.find("0x7000:01 \"Value\"=0"), std::string::npos) << status;
        if (watchdog) continue;
        // Back in Op, the master's outputs are taken again.
        ASSERT_EQ(pd.request_state(AlState::Op, std::chrono::microseconds(100), &st, fill), Error::Ok);
        ASSERT_EQ(pd.run(3, std::chrono::microseconds(100), fill), Error::Ok);
        EXPECT_EQ(u.dev->dictionary().get<uint16_t>(0x7000, 1), 0x1234);
    }
}

TEST(ProductWithoutMailbox, InitToPreOpNeedsNoMailboxSmsAndStartsNone) {
    Unit u(io_terminal());
    UnitLink link(u);
    Master m(link, test_support::in_process_master_options());
    const Address a = Address::station(0x1001);
    ASSERT_NO_FATAL_FAILURE(preop_without_mailbox(m, a));
    AlStatus st;
    // SM0/SM1 stay deactivated from the PDI until Safe-Op starts the process data in them.
    EXPECT_NE(m.read_reg<uint8_t>(a, 0x0807).value() & 0x01, 0);
    EXPECT_NE(m.read_reg<uint8_t>(a, 0x080F).value() & 0x01, 0);
    // No Bootstrap without a mailbox.
    ASSERT_NE(m.request_state(a, AlState::Init, &st), Error::Timeout);
    EXPECT_NE(m.request_state(a, AlState::Boot, &st), Error::Ok);
}

TEST(ProductWithCoe, ServesSdoWithoutDriveAndFoe) {
    Unit u(coe_terminal());
    EXPECT_TRUE(u.dev->has_coe());
    EXPECT_FALSE(u.dev->has_foe());
    EXPECT_FALSE(u.dev->has_drive());
    EXPECT_FALSE(u.dev->has_parameters());
    UnitLink link(u);
    Master m(link, test_support::in_process_master_options());
    const Address a = Address::station(0x1001);
    Mailbox mbx(m, a);
    ASSERT_NO_FATAL_FAILURE(test_support::one_slave_in_preop(m, mbx, a));
    SdoClient sdo(mbx);
    uint8_t b[4] = {};
    ASSERT_TRUE(sdo.upload(0x1018, 2, b).ok());
    EXPECT_EQ(b[0] | (b[1] << 8), 0x5678);

    ProcessDataSession pd(m, a, sdo);
    ASSERT_EQ(pd.discover(), Error::Ok);
    EXPECT_EQ(pd.layout().output_bytes(), 3u);
    EXPECT_EQ(pd.layout().input_bytes(), 5u);
    ASSERT_EQ(pd.configure(), Error::Ok);
    auto fill = [&] {
        auto o = pd.outputs();
        o[0] = 0x21;
        o[1] = 0x43;
    };
    ASSERT_NO_FATAL_FAILURE(session_to_op(pd, fill, 3));
    EXPECT_EQ(u16(pd.inputs(), 0), 0x4321);
}

// A device with one synchronisation type declares its sync modes read-only and refuses their write with
// 0x06010002: the master takes the mode the device has (the state transition judges it), as it takes an
// absent 0x1C32/0x1C33, and reaches Op.
TEST(ProductWithCoe, SyncModesTheDeviceFixesAreTakenAsTheyAre) {
    CoeUnitInPreOp t(coe_terminal(true));
    ASSERT_NO_FATAL_FAILURE(t.to_preop());
    Master& m = t.m;
    const Address a = t.a;
    SdoClient& sdo = t.sdo;
    const uint8_t sm_synchronous[2] = {0x22, 0};
    ASSERT_EQ(sdo.download(0x1C33, 1, sm_synchronous), Error::SdoAbort);
    ASSERT_EQ(sdo.last_abort(), 0x06010002u);

    ProcessDataSession pd(m, a, sdo);
    ASSERT_EQ(pd.discover(), Error::Ok);
    ASSERT_EQ(pd.configure(), Error::Ok);
    AlStatus st;
    ASSERT_EQ(pd.request_state(AlState::SafeOp, std::chrono::microseconds(100), &st), Error::Ok)
        << "AL code 0x" << std::hex << st.code;
    ASSERT_EQ(pd.request_state(AlState::Op, std::chrono::microseconds(100), &st), Error::Ok)
        << "AL code 0x" << std::hex << st.code;
    EXPECT_EQ(pd.run(3, std::chrono::microseconds(100)), Error::Ok);
}

// A device with a mailbox and no process-data SM: the master finds no process data (not a broken SII) and
// takes it to Op as it takes a coupler.
TEST(ProductWithCoe, MailboxOnlyDeviceHasNoProcessDataAndReachesOp) {
    CoeUnitInPreOp t(test_products::mailbox_only_terminal());
    ASSERT_NO_FATAL_FAILURE(t.to_preop());
    Master& m = t.m;
    const Address a = t.a;
    SdoClient& sdo = t.sdo;
    ProcessDataSession pd(m, a, sdo);
    ASSERT_EQ(pd.discover(), Error::Ok);
    EXPECT_EQ(pd.layout().output_bytes(), 0u);
    EXPECT_EQ(pd.layout().input_bytes(), 0u);
    AlStatus st;
    for (const AlState s : {AlState::SafeOp, AlState::Op})
        ASSERT_EQ(m.request_state(a, s, &st), Error::Ok) << "AL code 0x" << std::hex << st.code;
}

// The CoE terminal, addressed and in Pre-Op with its mailbox.
class CoeTerminalInPreOp : public ::testing::Test {
  protected:
    void to_preop() { ASSERT_NO_FATAL_FAILURE(test_support::one_slave_in_preop(m, mbx, a)); }
    Unit u{coe_terminal()};
    UnitLink link{u};
    Master m{link, test_support::in_process_master_options()};
    const Address a = Address::station(0x1001);
    Mailbox mbx{m, a};
};

// A device without drive reports a refused AL request as an emergency (ETG.1000.6 CoE emergency): code
// 0xA000 (EtherCAT state machine transition error), error register 0x11 (CiA 301: generic, communication),
// the AL status code in the first two bytes of the manufacturer-specific field.
TEST_F(CoeTerminalInPreOp, ARefusedAlRequestIsReportedAsAnEmergency) {
    ASSERT_NO_FATAL_FAILURE(to_preop());
    AlStatus st;
    EXPECT_NE(m.request_state(a, AlState::Op, &st), Error::Ok);  // Pre-Op -> Op: invalid (0x0011)
    EXPECT_TRUE(st.error);
    EXPECT_EQ(st.code, 0x0011);
    MailboxMessage msg;
    ASSERT_EQ(mbx.receive(msg), Error::Ok);
    ASSERT_EQ(msg.type, MailboxType::CoE);
    ASSERT_EQ(msg.payload.size(), 10u);
    EXPECT_EQ(msg.payload[1] >> 4, 1);  // CoE service: emergency
    EXPECT_EQ(u16(msg.payload, 2), 0xA000);
    EXPECT_EQ(msg.payload[4], 0x11);
    EXPECT_EQ(u16(msg.payload, 5), 0x0011);
}

// Every mailbox protocol the device does not serve (here all but CoE, FoE among them since it is not
// declared) is answered with the mailbox error reply "unsupported protocol" (ETG.1000.4, code 0x0002).
TEST_F(CoeTerminalInPreOp, EveryProtocolItDoesNotServeGetsTheUnsupportedProtocolError) {
    ASSERT_NO_FATAL_FAILURE(to_preop());
    for (const MailboxType type :
         {MailboxType::AoE, MailboxType::EoE, MailboxType::FoE, MailboxType::SoE, MailboxType::VoE,
          static_cast<MailboxType>(0x6), static_cast<MailboxType>(0xE)}) {
        std::vector<uint8_t> body(40, 0);
        ASSERT_EQ(mbx.send(type, body), Error::Ok);
        MailboxMessage reply;
        ASSERT_EQ(mbx.receive(reply), Error::Ok) << "type " << static_cast<int>(type);
        EXPECT_EQ(reply.type, MailboxType::Error) << "type " << static_cast<int>(type);
        ASSERT_GE(reply.payload.size(), 4u);
        EXPECT_EQ(u16(reply.payload, 0), 0x0001);  // mailbox command: error
        EXPECT_EQ(u16(reply.payload, 2), 0x0002) << "type " << static_cast<int>(type);
    }
    // CoE still served after them.
    SdoClient sdo(mbx);
    uint8_t b[4] = {};
    EXPECT_TRUE(sdo.upload(0x1018, 1, b).ok());
}

// A device whose ESC does device emulation (ESC configuration bit 0 from SII word 0, as IO terminals without
// a controller declare in their ConfigData): the ESC copies AL control into AL status, so any request is
// taken as it comes (Init -> Op directly, no refusal, AL status code 0), and the stack follows it with its
// process data.
namespace {

// The IO terminal with device emulation (ESC configuration 0x0141 bit 0) and the in-process master before it.
struct EmulatedTerminal : SiiUnit {
    explicit EmulatedTerminal(std::optional<uint16_t> pdi_config = std::nullopt)
        : SiiUnit(product(pdi_config)) {}
    static std::shared_ptr<od::Product> product(std::optional<uint16_t> pdi_config) {
        auto p = std::make_shared<od::Product>(*io_terminal());
        p->description.esc_config = 0x01;
        if (pdi_config) p->description.pdi_config = *pdi_config;
        return p;
    }
    // The one slave addressed, its process data from the SII, Init -> Op in one request taken without error.
    void to_op() {
        ASSERT_NO_FATAL_FAILURE(test_support::one_slave_addressed(m));
        ASSERT_EQ(pd.discover_sii(0), Error::Ok);
        ASSERT_EQ(pd.configure(), Error::Ok);
        AlStatus st;
        ASSERT_EQ(m.request_state(a, AlState::Op, &st), Error::Ok) << "AL code 0x" << std::hex << st.code;
        EXPECT_EQ(st.code, 0);
    }
};

}  // namespace

TEST(ProductWithDeviceEmulation, FollowsTheStateTheEscTookWithItsProcessData) {
    EmulatedTerminal t;
    ASSERT_NO_FATAL_FAILURE(t.to_op());
    AlStatus st;
    EXPECT_EQ(t.u.dev->stack().state(), od::AlState::Op);
    auto fill = [&] {
        t.pd.outputs()[0] = 0x21;
        t.pd.outputs()[1] = 0x43;
    };
    ASSERT_EQ(t.pd.run(5, std::chrono::microseconds(100), fill), Error::Ok);
    EXPECT_EQ(u16(t.pd.inputs(), 0), 0x4321);
    // An invalid request is not refused either: the ESC took it.
    ASSERT_EQ(t.m.request_state(t.a, AlState::Init, &st), Error::Ok);
    ASSERT_EQ(t.m.request_state(t.a, AlState::SafeOp, &st), Error::Ok);
    EXPECT_EQ(st.code, 0);
    EXPECT_EQ(t.u.dev->stack().state(), od::AlState::SafeOp);
}

// Device emulation means no controller is needed for the state or the process data: the ESC reports the state
// the master asked for at once, and its SMs run as the master set them up, however late the stack behind gets
// to look (a busy controller, a line's runtime under load). The stack holds no SM off from the PDI side, from
// power-on and on every way back down; the first cycle after the request has the full working counter.
TEST(ProductWithDeviceEmulation, RunsItsProcessDataBeforeTheControllerLooks) {
    EmulatedTerminal t;
    t.u.firmware_runs = false;  // after power-on the controller does not get to look until the end
    ASSERT_NO_FATAL_FAILURE(t.to_op());
    auto fill = [&] {
        t.pd.outputs()[0] = 0x21;
        t.pd.outputs()[1] = 0x43;
    };
    EXPECT_EQ(t.pd.run(3, std::chrono::microseconds(100), fill), Error::Ok)
        << "working counter " << t.pd.last_wkc() << " of " << t.pd.expected_wkc();
    EXPECT_EQ(t.u.dev->stack().state(), od::AlState::Init) << "the controller has not looked yet";
    t.u.firmware_runs = true;
    ASSERT_EQ(t.pd.run(3, std::chrono::microseconds(100), fill), Error::Ok);
    EXPECT_EQ(t.u.dev->stack().state(), od::AlState::Op);
    EXPECT_EQ(t.u.dev->dictionary().get<uint16_t>(0x7000, 1), 0x4321);
    // Down to Init, seen by the controller, and up again while it is busy.
    for (const AlState down : {AlState::Init, AlState::PreOp, AlState::SafeOp}) {
        SCOPED_TRACE(static_cast<int>(down));
        t.u.firmware_runs = true;
        ASSERT_EQ(t.m.request_state(t.a, down), Error::Ok);
        t.u.service();
        t.u.firmware_runs = false;
        ASSERT_EQ(t.m.request_state(t.a, AlState::Op), Error::Ok);
        EXPECT_EQ(t.pd.run(3, std::chrono::microseconds(100), fill), Error::Ok)
            << "working counter " << t.pd.last_wkc() << " of " << t.pd.expected_wkc();
    }
}

// Device emulation with the outputs on the digital-output registers (0x0F00, SM control 0x44): the master's
// writes through that SM trigger the process-data watchdog; when it expires the ESC keeps Op, shows the
// expiry in 0x0440 bit 0, and the device's outputs go to 0 at once (0x0150 bit 3 = 0) or are held until the
// next output event (bit 3 = 1); the master's next writes bring them back (ESC datasheet section II, 0x0150
// PDI configuration, 0x0F00 digital I/O output data, 0x0440 watchdog status process data).
TEST(ProductWithDeviceEmulation, OutputsOnTheRegistersGoToZeroWhenTheWatchdogExpires) {
    for (const bool at_next_event : {false, true}) {
        SCOPED_TRACE(at_next_event ? "0x0150 bit 3 = 1" : "0x0150 bit 3 = 0");
        EmulatedTerminal t(at_next_event ? 0x08 : 0x00);
        ASSERT_NO_FATAL_FAILURE(t.to_op());
        ASSERT_EQ(t.pd.layout(0).first(true)->start, 0x0F00);
        auto fill = [&] {
            auto o = t.pd.outputs();
            o[0] = 0x34;
            o[1] = 0x12;
            o[2] = 0x01;
        };
        ASSERT_EQ(t.pd.run(5, std::chrono::microseconds(100), fill), Error::Ok);
        ASSERT_EQ(t.u.dev->dictionary().get<uint16_t>(0x7000, 1), 0x1234);
        EXPECT_EQ(t.m.read_reg<uint16_t>(t.a, 0x0440).value() & 1, 1);
        // No process data for 500 ms: the SM watchdog (100 ms by default) expires.
        for (int i = 0; i < 500; ++i) {
            t.u.clock.advance(1'000'000);
            t.u.service();
        }
        EXPECT_EQ(t.m.read_reg<uint16_t>(t.a, 0x0440).value() & 1, 0);
        EXPECT_EQ(t.u.dev->stack().state(), od::AlState::Op);
        EXPECT_EQ(t.u.dev->dictionary().get<uint16_t>(0x7000, 1), at_next_event ? 0x1234 : 0);
        EXPECT_EQ(t.u.dev->dictionary().get<uint8_t>(0x7000, 2), at_next_event ? 1 : 0);
        ASSERT_EQ(t.pd.run(5, std::chrono::microseconds(100), fill), Error::Ok);
        EXPECT_EQ(t.u.dev->dictionary().get<uint16_t>(0x7000, 1), 0x1234);
        EXPECT_EQ(t.m.read_reg<uint16_t>(t.a, 0x0440).value() & 1, 1);
    }
}

// A product with its own EEPROM image (ESI Eeprom/Data) is served byte for byte, by make_sii and by the ESC
// (read through the master's SII access); a unit of a line gets its serial number in words 0x0E/0x0F only.
TEST(ProductWithEepromImage, IsServedByteForByte) {
    auto p = std::make_shared<od::Product>(*io_terminal());
    device::DeviceOptions probe;
    probe.product = p;
    std::vector<uint8_t> image = device::make_sii(probe);  // a valid image to start from
    image[0x40 * 2 + 100] ^= 0x5A;                         // and made different from what would be built
    p->eeprom = image;
    device::DeviceOptions o;
    o.product = p;
    EXPECT_EQ(device::make_sii(o), image);
    Unit u(p);
    UnitLink link(u);
    Master m(link, test_support::in_process_master_options());
    ASSERT_NO_FATAL_FAILURE(test_support::one_slave_addressed(m));
    auto served = m.sii_read_image(Address::station(0x1001));
    ASSERT_TRUE(served.ok());
    ASSERT_LE(served->size(), image.size());
    EXPECT_TRUE(std::equal(served->begin(), served->end(), image.begin()));
    o.serial_number = 7;
    const std::vector<uint8_t> unit = device::make_sii(o);
    ASSERT_EQ(unit.size(), image.size());
    EXPECT_EQ(unit[0x1C], 7);
    for (std::size_t i = 0; i < image.size(); ++i)
        if (i < 0x1C || i > 0x1F) {
            ASSERT_EQ(unit[i], image[i]) << "byte " << i;
        }
}

// A vendor's drive whose 0x6502 announces more than the drive core can serve: the example drive
// (esi/examples/drive402.xml: PP, PV, PT, HM, IP, CSP, CSV, CST with their objects) announcing the velocity
// mode (not implemented) and four manufacturer-specific modes as well. The running device announces what it
// serves, says once at start what it took out, and refuses that in 0x6060; the description (what --write-esi
// writes) keeps the ESI's value (docs/decisions/device.md, "Modes a vendor's 0x6502 announces").
TEST(ProductWithDrive, Announces6502AsServedAndSaysWhatItTookOut) {
    std::ifstream in(SOFTECAT_ESI_EXAMPLES "/drive402.xml", std::ios::binary);
    std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string announced = "<DefaultData>ed030000</DefaultData>";
    const std::size_t at = xml.find(announced);
    ASSERT_NE(at, std::string::npos);
    xml.replace(at, announced.size(), "<DefaultData>ef030f00</DefaultData>");  // 0x000F03EF
    auto product =
        std::make_shared<od::Product>(esi::load_product(esi::read_esi_text(xml, "drive402-more.xml"), ""));
    EXPECT_EQ(product->make_dictionary(product->description).get<uint32_t>(0x6502, 0), 0x000F03EFu);
    Unit u(product);
    ASSERT_TRUE(u.dev->has_drive());
    EXPECT_EQ(u.dev->dictionary().get<uint32_t>(0x6502, 0), 0x000003EDu);
    EXPECT_EQ(u.dev->drive().withheld_modes(), 0x000F0002u);
    const std::string log = u.log.str();
    const std::string w =
        "0x6502 announces modes the drive core does not serve on this dictionary (bits 0x000f0002)";
    ASSERT_NE(log.find(w), std::string::npos) << log;
    EXPECT_EQ(log.find(w), log.rfind(w));
    auto write_mode = [&](uint8_t m) {
        return u.dev->dictionary().write(0x6060, 0, od::AlState::PreOp, std::span<const uint8_t>(&m, 1));
    };
    EXPECT_EQ(write_mode(2), od::Status::InvalidValue);  // velocity mode
    EXPECT_EQ(write_mode(7), od::Status::Ok);            // interpolated position: 0x60C1 is there
    EXPECT_EQ(write_mode(4), od::Status::Ok);            // profile torque
}

namespace {

// The two-SM terminal's outputs (SM of 0x1600: 0x7000:01 Value, 0x7000:02 Output; SM of 0x1601: 0x7010:01
// Channel 2) in the session's image: outputs SM by SM in SM order.
void fill_two_sm(ProcessDataSession& pd) {
    auto o = pd.outputs();
    o[0] = 0x21;
    o[1] = 0x43;
    o[2] = 0x01;
    o[3] = 0x65;
    o[4] = 0x87;
}

// OP with the exact working counter, then the inputs of both inputs SMs: 0x6000:01 mirrors Value, 0x6000:03
// keeps 0x1234 (first SM), 0x6010:01 mirrors Channel 2, 0x6010:02 keeps 0x5A (second SM).
void expect_two_sm_exchange(ProcessDataSession& pd) {
    // Four FMMUs, one LRW: the ESC counts the datagram once per direction, 2 for the outputs written and 1
    // for the inputs read (ESC datasheet section I, working counter), not once per FMMU.
    EXPECT_EQ(pd.expected_wkc(), 3);
    ASSERT_NO_FATAL_FAILURE(session_to_op(
        pd, [&pd] { fill_two_sm(pd); }, 5));
    EXPECT_EQ(pd.last_wkc(), 3);
    const auto in = pd.inputs();
    EXPECT_EQ(u16(in, 0), 0x4321);
    EXPECT_EQ(u16(in, 3), 0x1234);
    EXPECT_EQ(u16(in, 5), 0x8765);
    EXPECT_EQ(in[7], 0x5A);
}

// A device without mailbox on an ESC of `fmmus` FMMUs, in Pre-Op, its layout read from its SII alone.
struct SiiUnitInPreOp : SiiUnit {
    SiiUnitInPreOp(std::shared_ptr<const od::Product> product, uint8_t fmmus)
        : SiiUnit(std::move(product), esc(fmmus)) {}
    static esc::EscConfig esc(uint8_t fmmus) {
        esc::EscConfig c;
        c.fmmu_count = fmmus;
        return c;
    }
    void discover() {
        ASSERT_NO_FATAL_FAILURE(preop_without_mailbox(m, a));
        ASSERT_EQ(pd.discover_sii(0), Error::Ok);
    }
};

}  // namespace

// A device with two outputs SMs (SM2, SM4) and two inputs SMs (SM3, SM5), PDOs assigned by 0x1C12..0x1C15
// (ETG.1000.6: 0x1C10 + n for SM n): the session sets up all four with an FMMU each, the outputs of both SMs
// reach the dictionary and the inputs of both come back, with the exact working counter.
TEST(ProductWithSeveralSms, EveryProcessDataSmIsMappedOverCoe) {
    CoeUnitInPreOp t(two_sm_terminal(true));
    ASSERT_NO_FATAL_FAILURE(t.to_preop());
    ProcessDataSession pd(t.m, t.a, t.sdo);
    ASSERT_EQ(pd.discover(), Error::Ok);
    const ProcessDataLayout& l = pd.layout();
    ASSERT_EQ(l.sms.size(), 4u);
    const uint8_t index[4] = {2, 3, 4, 5};
    const uint16_t length[4] = {3, 5, 2, 3};
    for (std::size_t k = 0; k < 4; ++k) {
        EXPECT_EQ(l.sms[k].index, index[k]);
        EXPECT_EQ(l.sms[k].outputs, k % 2 == 0);
        EXPECT_EQ(l.sms[k].length, length[k]);
    }
    EXPECT_EQ(l.pdos(true), (std::vector<uint16_t>{0x1600, 0x1601}));
    EXPECT_EQ(l.pdos(false), (std::vector<uint16_t>{0x1A00, 0x1A01}));
    ASSERT_EQ(pd.configure(), Error::Ok);
    ASSERT_EQ(pd.outputs().size(), 5u);
    ASSERT_EQ(pd.inputs().size(), 8u);
    ASSERT_NO_FATAL_FAILURE(expect_two_sm_exchange(pd));
    uint8_t b[4] = {};
    ASSERT_TRUE(t.sdo.upload(0x7000, 1, b).ok());
    EXPECT_EQ(u16(b, 0), 0x4321);
    ASSERT_TRUE(t.sdo.upload(0x7010, 1, b).ok());
    EXPECT_EQ(u16(b, 0), 0x8765);
    // SM4 and SM5 as the SII declares them, each read by its own FMMU (FMMU1: SM4, outputs after SM2's;
    // FMMU3: SM5, inputs after SM3's).
    uint8_t f[64] = {};
    ASSERT_EQ(t.m.read(t.a, reg::Fmmu0, f), Error::Ok);
    EXPECT_EQ(u16(f, 16 + 8), 0x1200);
    EXPECT_EQ(f[16 + 11], 0x02);
    EXPECT_EQ(f[48 + 8] | (f[48 + 9] << 8), 0x1280);
    EXPECT_EQ(f[48 + 11], 0x01);
}

// A device need not have the assignment object of an SM nothing is assigned to (abort "object does not
// exist"): that SM takes what the SII assigns to it, here nothing, and stays off; the others run.
TEST(ProductWithSeveralSms, AnSmWithoutAssignmentObjectTakesTheSiisPdos) {
    CoeUnitInPreOp t(two_sm_terminal(true, false));
    ASSERT_NO_FATAL_FAILURE(t.to_preop());
    ProcessDataSession pd(t.m, t.a, t.sdo);
    ASSERT_EQ(pd.discover(), Error::Ok);
    const ProcessDataLayout& l = pd.layout();
    ASSERT_EQ(l.sms.size(), 4u);
    EXPECT_EQ(l.sms[2].length, 0);
    EXPECT_EQ(l.sms[3].length, 0);
    ASSERT_EQ(pd.configure(), Error::Ok);
    ASSERT_EQ(pd.outputs().size(), 3u);
    ASSERT_EQ(pd.inputs().size(), 5u);
    const auto fill = [&pd] {
        pd.outputs()[0] = 0x21;
        pd.outputs()[1] = 0x43;
    };
    ASSERT_NO_FATAL_FAILURE(session_to_op(pd, fill, 5));
    EXPECT_EQ(pd.last_wkc(), 3);
    EXPECT_EQ(u16(pd.inputs(), 0), 0x4321);
}

// Without mailbox the layout comes from the SII alone: every SM of type 3/4 of the SyncM category with the
// PDOs the RxPDO/TxPDO categories assign to it, here outputs in SM0/SM2 and inputs in SM1/SM3.
TEST(ProductWithSeveralSms, EveryProcessDataSmIsMappedFromTheSiiAlone) {
    SiiUnitInPreOp t(two_sm_terminal(false), 8);
    ASSERT_NO_FATAL_FAILURE(t.discover());
    ProcessDataSession& pd = t.pd;
    const ProcessDataLayout& l = pd.layout(0);
    ASSERT_EQ(l.sms.size(), 4u);
    EXPECT_EQ(l.sms[2].index, 2);
    EXPECT_EQ(l.sms[3].index, 3);
    EXPECT_EQ(l.sms[3].start, 0x1200);
    EXPECT_EQ(l.sms[3].pdos, (std::vector<uint16_t>{0x1A01}));
    ASSERT_EQ(pd.configure(), Error::Ok);
    ASSERT_EQ(pd.outputs().size(), 5u);
    ASSERT_EQ(pd.inputs().size(), 8u);
    ASSERT_NO_FATAL_FAILURE(expect_two_sm_exchange(pd));
}

// A slave with fewer FMMUs (ESC 0x0004) than SMs carrying data cannot map its image: the session says so and
// configures nothing, rather than mapping part of it.
TEST(ProductWithSeveralSms, TooFewFmmusIsAnErrorAndNothingIsConfigured) {
    SiiUnitInPreOp t(two_sm_terminal(false), 3);
    ASSERT_NO_FATAL_FAILURE(t.discover());
    Master& m = t.m;
    const Address a = t.a;
    EXPECT_EQ(t.pd.configure(), Error::TooFewFmmus);
    EXPECT_NE(to_string(Error::TooFewFmmus).find("FMMU"), std::string::npos);
    for (uint8_t n = 0; n < 4; ++n)
        EXPECT_EQ(m.read_reg<uint8_t>(a, static_cast<uint16_t>(0x0806 + 8 * n)).value() & 0x01, 0)
            << "SM" << +n;
    for (uint8_t n = 0; n < 3; ++n)
        EXPECT_EQ(m.read_reg<uint8_t>(a, static_cast<uint16_t>(0x060C + 16 * n)).value() & 0x01, 0)
            << "FMMU" << +n;
}

// SMs one after the other in memory share one FMMU (one logical range onto one physical range, as SOEM and
// TwinCAT map them): the four one-byte outputs SMs on 0x0F00..0x0F03 fit the one FMMU of an ESC with one,
// and every byte reaches its SM.
TEST(ProductWithSeveralSms, AdjacentSmsShareOneFmmu) {
    SiiUnitInPreOp t(byte_outputs_terminal(), 1);
    ASSERT_NO_FATAL_FAILURE(t.discover());
    ProcessDataSession& pd = t.pd;
    ASSERT_EQ(pd.layout(0).sms.size(), 4u);
    const auto fmmus = pd.layout(0).fmmus();
    ASSERT_EQ(fmmus.size(), 1u);
    EXPECT_EQ(fmmus[0].physical, 0x0F00);
    EXPECT_EQ(fmmus[0].length, 4);
    ASSERT_EQ(pd.configure(), Error::Ok);
    ASSERT_EQ(pd.outputs().size(), 4u);
    EXPECT_EQ(pd.expected_wkc(), 2);
    const auto fill = [&pd] {
        for (uint8_t k = 0; k < 4; ++k)
            pd.outputs()[k] = static_cast<uint8_t>(0x11 * (k + 1));
    };
    ASSERT_NO_FATAL_FAILURE(session_to_op(pd, fill, 5));
    uint8_t out[4] = {};
    ASSERT_EQ(t.m.read(t.a, 0x0F00, out), Error::Ok);
    EXPECT_EQ(out[0], 0x11);
    EXPECT_EQ(out[3], 0x44);
}

// A vendor's ESI that declares 0x10F3 (ETG.1020 Diagnosis History) with :00..:05 only, no subindex for a
// message (Weidmueller's UR20 coupler, vendor round 7): the device starts and serves the object as the values
// it declares, without a history, and says so once (docs/decisions/device.md, "A 0x10F3 without messages").
TEST(ProductWithCoe, ADiagnosisHistoryWithoutRoomForMessagesIsServedAsDeclared) {
    const std::string sub =
        R"(<SubItem><SubIdx>%</SubIdx><Name>S%</Name><Type>USINT</Type><BitSize>8</BitSize>
<BitOffs>@</BitOffs><Flags><Access>ro</Access></Flags></SubItem>)";
    std::string items;
    for (int n = 0; n <= 5; ++n) {
        std::string s = sub;
        s.replace(s.find('%'), 1, std::to_string(n));
        s.replace(s.find('%'), 1, std::to_string(n));
        s.replace(s.find('@'), 1, std::to_string(n == 0 ? 0 : 8 + 8 * n));
        items += s;
    }
    const std::string xml = R"(<?xml version="1.0"?>
<EtherCATInfo><Vendor><Id>#x00000A5E</Id><Name>Example</Name></Vendor><Descriptions><Groups><Group>
<Type>G</Type><Name>G</Name></Group></Groups><Devices><Device Physics="YY">
<Type ProductCode="#x00000200" RevisionNo="#x00000001">DH1</Type><Name>DH1</Name><GroupType>G</GroupType>
<Profile><Dictionary><DataTypes><DataType><Name>USINT</Name><BitSize>8</BitSize></DataType>
<DataType><Name>DT10F3</Name><BitSize>56</BitSize>)" +
                            items + R"(</DataType></DataTypes><Objects>
<Object><Index>#x10F3</Index><Name>Diagnosis History</Name><Type>DT10F3</Type><BitSize>56</BitSize>
<Info><SubItem><Name>S0</Name><Info><DefaultData>05</DefaultData></Info></SubItem>
<SubItem><Name>S1</Name><Info><DefaultData>07</DefaultData></Info></SubItem></Info></Object>
</Objects></Dictionary></Profile>
<Sm DefaultSize="128" StartAddress="#x1000" ControlByte="#x26" Enable="1">MBoxOut</Sm>
<Sm DefaultSize="128" StartAddress="#x1080" ControlByte="#x22" Enable="1">MBoxIn</Sm>
<Mailbox><CoE SdoInfo="1"/></Mailbox></Device></Devices></Descriptions></EtherCATInfo>)";
    auto product = std::make_shared<od::Product>(esi::load_product(esi::read_esi_text(xml, "dh1.xml"), ""));
    Unit u(product);
    ASSERT_TRUE(u.dev->has_coe());
    const std::string log = u.log.str();
    const std::string w = "0x10F3 has no message subindex (:06 and after) (ETG.1020 Diagnosis History)";
    ASSERT_NE(log.find(w), std::string::npos) << log;
    EXPECT_EQ(log.find(w), log.rfind(w));
    EXPECT_EQ(u.dev->dictionary().get<uint8_t>(0x10F3, 1), 7u);  // the declared value, not a history's count
}

// A device whose 0x1C32:04 announces free run and DC but not the SM-synchronous mode (0x0005, Weidmueller's
// UR20 coupler, vendor round 7): it refuses PREOP -> SAFEOP in SM-synchronous mode (0x0028), so the master
// library's session asks for free run (0x1C32:01 = 0) and reaches Op (tools/lib/master session.cpp).
TEST(ProductWithDrive, AMasterSessionAsksFreeRunOfADeviceWithoutSmSynchronousMode) {
    std::ifstream in(SOFTECAT_ESI_EXAMPLES "/drive402.xml", std::ios::binary);
    std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string supported =
        "<Name>Sync modes supported</Name>\n\t\t\t\t\t\t\t\t\t\t<Info>\n\t\t\t\t\t\t\t\t\t\t\t"
        "<DefaultData>0700</DefaultData>";
    const std::size_t at = xml.find(supported);
    ASSERT_NE(at, std::string::npos);
    xml.replace(at + supported.size() - 18, 4, "0500");  // 0x0005: free run, DC SYNC0
    auto product =
        std::make_shared<od::Product>(esi::load_product(esi::read_esi_text(xml, "drive-0005.xml"), ""));
    CoeUnitInPreOp t(product);
    ASSERT_NO_FATAL_FAILURE(t.to_preop());
    uint8_t sup[2] = {};
    ASSERT_TRUE(t.sdo.upload(0x1C32, 4, sup).ok());
    ASSERT_EQ(sup[0], 0x05);
    ProcessDataSession pd(t.m, t.a, t.sdo);
    ASSERT_EQ(pd.discover(), Error::Ok);
    ASSERT_EQ(pd.configure(), Error::Ok);
    ASSERT_NO_FATAL_FAILURE(session_to_op(
        pd, [] {}, 3));
    uint8_t mode[2] = {0xFF, 0xFF};
    ASSERT_TRUE(t.sdo.upload(0x1C32, 1, mode).ok());
    EXPECT_EQ(mode[0], 0);  // free run
}
