// device::Device built from an od::Product made by hand (as the ESI reader makes them): a digital IO
// terminal without mailbox (process data in SM0/SM1, reaches Op with process data only, the IO model's
// mirror / counter / keep and `set`), and an analog terminal with CoE but no drive (SDO, no FoE, no drive;
// every mailbox protocol it does not serve answered with the mailbox error "unsupported protocol").
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "device/control.hpp"
#include "device/device.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "od/product.hpp"

#include "support/master_bring_up.hpp"
#include "support/temp_dir.hpp"
#include "support/wire_link.hpp"

using namespace master;

namespace {

od::Entry entry(uint8_t sub, std::string name, od::DataType type, uint16_t access, uint64_t value = 0) {
    od::Entry e;
    e.subindex = sub;
    e.name = std::move(name);
    e.type = type;
    e.access = access;
    e.default_value = value;
    return e;
}

od::Object var(uint16_t index, std::string name, od::DataType type, uint64_t value) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Var;
    o.name = name;
    o.type = type;
    o.entries.push_back(entry(0, std::move(name), type, od::access::RO, value));
    return o;
}

od::Object record(uint16_t index, std::string name, std::vector<od::Entry> entries) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Record;
    o.name = std::move(name);
    o.type = od::DataType::Identity;
    o.entries = std::move(entries);
    return o;
}

od::Object array(uint16_t index, std::string name, od::DataType type, const std::vector<uint64_t>& values) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Array;
    o.name = std::move(name);
    o.type = type;
    for (std::size_t i = 0; i < values.size(); ++i)
        o.entries.push_back(entry(static_cast<uint8_t>(i + 1), "SubIndex " + std::to_string(i + 1), type,
                                  od::access::RO, values[i]));
    return o;
}

void add_identity(od::Dictionary& d, const od::DeviceDescription& desc) {
    d.add(var(0x1000, "Device type", od::DataType::Unsigned32, 0x00001389));
    const od::Identity& id = desc.identity;
    d.add(record(0x1018, "Identity",
                 {entry(1, "Vendor ID", od::DataType::Unsigned32, od::access::RO, id.vendor_id),
                  entry(2, "Product code", od::DataType::Unsigned32, od::access::RO, id.product_code),
                  entry(3, "Revision", od::DataType::Unsigned32, od::access::RO, id.revision),
                  entry(4, "Serial number", od::DataType::Unsigned32, od::access::RO, id.serial_number)}));
}

constexpr uint16_t kRo = od::access::RO;
constexpr uint16_t kTx = od::access::RO | od::access::TxPdo;
constexpr uint16_t kRx = od::access::RO | od::access::WritePreOp | od::access::WriteSafeOp |
                         od::access::WriteOp | od::access::RxPdo;

// The PDOs of both products: RxPDO 0x1600 (0x7000:01 "Value" U16, 0x7000:02 "Output" BOOL, 7 bits
// padding: 3 bytes), TxPDO 0x1A00 (0x6000:01 "Value" U16 mirrors the output of that name, 0x6000:02
// "Cycle Counter" U8 counts, 0x6000:03 "Status" U16 keeps 0x1234: 5 bytes).
void add_io(od::Dictionary& d, uint16_t out_assign, uint16_t in_assign) {
    d.add(record(0x1600, "Outputs",
                 {entry(1, "SubIndex 001", od::DataType::Unsigned32, kRo, 0x70000110),
                  entry(2, "SubIndex 002", od::DataType::Unsigned32, kRo, 0x70000201),
                  entry(3, "SubIndex 003", od::DataType::Unsigned32, kRo, 0x00000007)}));
    d.add(record(0x1A00, "Inputs",
                 {entry(1, "SubIndex 001", od::DataType::Unsigned32, kRo, 0x60000110),
                  entry(2, "SubIndex 002", od::DataType::Unsigned32, kRo, 0x60000208),
                  entry(3, "SubIndex 003", od::DataType::Unsigned32, kRo, 0x60000310)}));
    d.add(array(out_assign, "RxPDO assign", od::DataType::Unsigned16, {0x1600}));
    d.add(array(in_assign, "TxPDO assign", od::DataType::Unsigned16, {0x1A00}));
    d.add(record(0x6000, "Inputs",
                 {entry(1, "Value", od::DataType::Unsigned16, kTx, 0),
                  entry(2, "Cycle Counter", od::DataType::Unsigned8, kTx, 250),
                  entry(3, "Status", od::DataType::Unsigned16, kTx, 0x1234)}));
    d.add(record(0x7000, "Outputs",
                 {entry(1, "Value", od::DataType::Unsigned16, kRx, 0),
                  entry(2, "Output", od::DataType::Boolean, kRx, 0)}));
}

od::SyncManagerDefault sm(od::SmKind kind, uint16_t start, uint16_t size, uint8_t control) {
    od::SyncManagerDefault s;
    s.kind = kind;
    s.start = start;
    s.default_size = size;
    s.control = control;
    return s;
}

od::Identity identity(uint32_t product) {
    od::Identity id;
    id.vendor_id = 0xE0000123;
    id.product_code = product;
    id.revision = 0x00010000;
    id.vendor_name = "Example";
    id.device_name = "IO terminal";
    id.order_code = "EX1234";
    id.group_type = "DigIO";
    return id;
}

// A digital IO terminal without mailbox: outputs in SM0 (0x0F00, 0x44), inputs in SM1 (0x1000, 0x00).
std::shared_ptr<const od::Product> io_terminal() {
    auto p = std::make_shared<od::Product>();
    p->source = "hand-built IO terminal";
    od::DeviceDescription& d = p->description;
    d.identity = identity(0x00001234);
    d.standard_mailbox = {0, 0, 0, 0};
    d.bootstrap_mailbox = {0, 0, 0, 0};
    d.mailbox_protocols = 0;
    d.coe_details = 0;
    d.sync_managers = {sm(od::SmKind::Outputs, 0x0F00, 3, 0x44), sm(od::SmKind::Inputs, 0x1000, 5, 0x00)};
    d.pdi_control = 0x04;  // digital IO
    d.esc_config = 0;
    p->make_dictionary = [](const od::DeviceDescription& desc) {
        od::Dictionary dict;
        add_identity(dict, desc);
        add_io(dict, 0x1C10, 0x1C11);
        return dict;
    };
    p->application = od::Application::None;
    p->warnings = {"Element 'Info/VendorSpecific' is not emulated"};
    return p;
}

// An analog terminal with CoE (SDO, SDO info) and no drive: standard mailbox, process data in SM2/SM3.
std::shared_ptr<const od::Product> coe_terminal() {
    auto p = std::make_shared<od::Product>();
    p->source = "hand-built CoE terminal";
    od::DeviceDescription& d = p->description;
    d.identity = identity(0x00005678);
    d.bootstrap_mailbox = {0, 0, 0, 0};
    d.mailbox_protocols = od::mailbox_protocol::CoE;
    d.coe_details = od::coe_details::Sdo | od::coe_details::SdoInfo;
    d.sync_managers = {sm(od::SmKind::MBoxOut, 0x1000, 128, 0x26), sm(od::SmKind::MBoxIn, 0x1080, 128, 0x22),
                       sm(od::SmKind::Outputs, 0x1100, 3, 0x64), sm(od::SmKind::Inputs, 0x1180, 5, 0x20)};
    p->make_dictionary = [](const od::DeviceDescription& desc) {
        od::Dictionary dict;
        add_identity(dict, desc);
        dict.add(array(0x1C00, "Sync manager type", od::DataType::Unsigned8, {1, 2, 3, 4}));
        // SM output/input parameters (ETG.1000.6): sync mode writable in Pre-Op, free run / SM-synchronous.
        constexpr uint16_t kRwPreOp = od::access::RO | od::access::WritePreOp;
        for (const uint16_t index : {uint16_t{0x1C32}, uint16_t{0x1C33}})
            dict.add(record(index, index == 0x1C32 ? "SM output parameter" : "SM input parameter",
                            {entry(1, "Sync mode", od::DataType::Unsigned16, kRwPreOp, 1),
                             entry(2, "Cycle time", od::DataType::Unsigned32, kRwPreOp, 0),
                             entry(4, "Sync modes supported", od::DataType::Unsigned16, kRo, 0x0003)}));
        add_io(dict, 0x1C12, 0x1C13);
        return dict;
    };
    return p;
}

// One device "powered" on a manual clock; the master's frames go through its ESC, then the firmware.
struct Unit {
    esc::ManualClock clock;
    std::ostringstream log;
    std::unique_ptr<esc::Esc> esc;
    std::unique_ptr<device::Device> dev;
    std::filesystem::path dir;

    explicit Unit(std::shared_ptr<const od::Product> product)
        : dir(test_support::make_temp_dir("softecat-product-")) {
        clock.set(1'000'000'000);
        device::DeviceOptions o;
        o.product = std::move(product);
        o.state_dir = dir;
        o.log = &log;
        esc = std::make_unique<esc::Esc>(esc::EscConfig{}, clock);
        dev = std::make_unique<device::Device>(*esc, o);
        service();
    }
    ~Unit() {
        dev.reset();
        std::error_code ec;
        std::filesystem::remove_all(dir, ec);
    }
    void service() {
        esc->tick();
        dev->poll(clock.now_ns());
    }
};

struct UnitLink final : test_support::WireLink {
    explicit UnitLink(Unit& u)
        : WireLink([&u](std::vector<uint8_t>& f) {
              u.clock.advance(20'000);
              const bool back = u.esc->process_frame(f);
              u.service();
              return back;
          }) {}
};

uint16_t u16(std::span<const uint8_t> b, std::size_t at) {
    return static_cast<uint16_t>(b[at] | (b[at + 1] << 8));
}

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
    ASSERT_NO_FATAL_FAILURE(test_support::one_slave_addressed(m));
    AlStatus st;
    ASSERT_EQ(m.request_state(a, AlState::PreOp, &st), Error::Ok) << "AL code 0x" << std::hex << st.code;

    ProcessDataSession pd(m, std::span<const Address>(&a, 1));
    ASSERT_EQ(pd.discover_sii(0), Error::Ok);
    const ProcessDataLayout& l = pd.layout(0);
    EXPECT_EQ(l.out_sm, 0);
    EXPECT_EQ(l.in_sm, 1);
    EXPECT_EQ(l.sm2_start, 0x0F00);
    EXPECT_EQ(l.sm3_start, 0x1000);
    ASSERT_EQ(l.sm2_length, 3);
    ASSERT_EQ(l.sm3_length, 5);
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

TEST(ProductWithoutMailbox, InitToPreOpNeedsNoMailboxSmsAndStartsNone) {
    Unit u(io_terminal());
    UnitLink link(u);
    Master m(link, test_support::in_process_master_options());
    const Address a = Address::station(0x1001);
    ASSERT_NO_FATAL_FAILURE(test_support::one_slave_addressed(m));
    AlStatus st;
    ASSERT_EQ(m.request_state(a, AlState::PreOp, &st), Error::Ok) << "AL code 0x" << std::hex << st.code;
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
    EXPECT_EQ(pd.layout().sm2_length, 3);
    EXPECT_EQ(pd.layout().sm3_length, 5);
    ASSERT_EQ(pd.configure(), Error::Ok);
    auto fill = [&] {
        auto o = pd.outputs();
        o[0] = 0x21;
        o[1] = 0x43;
    };
    AlStatus st;
    ASSERT_EQ(pd.request_state(AlState::SafeOp, std::chrono::microseconds(100), &st, fill), Error::Ok)
        << "AL code 0x" << std::hex << st.code;
    ASSERT_EQ(pd.request_state(AlState::Op, std::chrono::microseconds(100), &st, fill), Error::Ok)
        << "AL code 0x" << std::hex << st.code;
    ASSERT_EQ(pd.run(3, std::chrono::microseconds(100), fill), Error::Ok);
    EXPECT_EQ(u16(pd.inputs(), 0), 0x4321);
}

// Every mailbox protocol the device does not serve (here all but CoE, FoE among them since it is not
// declared) is answered with the mailbox error reply "unsupported protocol" (ETG.1000.4, code 0x0002).
TEST(ProductWithCoe, EveryProtocolItDoesNotServeGetsTheUnsupportedProtocolError) {
    Unit u(coe_terminal());
    UnitLink link(u);
    Master m(link, test_support::in_process_master_options());
    const Address a = Address::station(0x1001);
    Mailbox mbx(m, a);
    ASSERT_NO_FATAL_FAILURE(test_support::one_slave_in_preop(m, mbx, a));
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
