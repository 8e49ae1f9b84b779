// The slave runtime in segment mode (slave::Runtime over an esc::Segment) with a line of composed drives
// (device::Line) behind a LoopbackLink, and the master library on the other end: the devices found by the
// BRD working counter, addressed and taken to PRE-OP; faults through Line::apply(); a power cycle that
// brings a drive back in Init with its stored parameters; the hold queue of a delayed hop.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <thread>
#include <vector>

#include "device/line.hpp"
#include "device/products.hpp"
#include "esc/clock.hpp"
#include "esc/link_loopback.hpp"
#include "esc/wire/frame_builder.hpp"
#include "foe/image.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "slave/log.hpp"
#include "slave/runtime.hpp"
#include "slave/topology.hpp"
#include "support/temp_dir.hpp"

using master::Address;
using master::AlState;
using master::Error;

namespace {

std::vector<uint8_t> brd_type_frame() {
    return esc::wire::FrameBuilder().add_zero(esc::Command::BRD, 0x42, 0, 0x0000, 1).build(60);
}
constexpr std::size_t kWkcOffset = 16 + 10 + 1;

master::MasterOptions master_options() {
    master::MasterOptions o;
    o.timeout = std::chrono::milliseconds(100);  // the runtime runs in another thread on a shared machine
    o.al_timeout = std::chrono::milliseconds(2000);
    return o;
}

// N drives in a line, served by a runtime on the slave end of a loopback pair.
struct SegmentBus {
    explicit SegmentBus(int count, std::vector<std::shared_ptr<const od::Product>> products = {})
        : links(esc::LoopbackLink::make_pair(256)), log(log_text, slave::LogLevel::Debug) {
        device::LineOptions o;
        o.topology = slave::line_topology(count);
        o.products = std::move(products);
        o.base.state_dir = dir.path;
        o.base.log = &warnings;
        o.log = &log;
        line = std::make_unique<device::Line>(clock, std::move(o));
        runtime = std::make_unique<slave::Runtime>(*links.second, line->segment(), clock);
        runtime->set_firmware(line.get());
    }
    ~SegmentBus() { stop(); }

    void start() {
        thread = std::thread([this] { runtime->run(); });
    }
    // Stops the runtime thread: the test may then touch the Line (power, faults) without a race.
    void stop() {
        if (!thread.joinable()) return;
        runtime->request_stop();
        thread.join();
        runtime = std::make_unique<slave::Runtime>(*links.second, line->segment(), clock);
        runtime->set_firmware(line.get());
    }

    esc::LoopbackLink& master_end() { return *links.first; }

    test_support::TempDir dir{"segment-runtime-"};
    esc::SystemClock clock;
    std::pair<std::unique_ptr<esc::LoopbackLink>, std::unique_ptr<esc::LoopbackLink>> links;
    std::ostringstream log_text, warnings;
    slave::Log log;
    std::unique_ptr<device::Line> line;
    std::unique_ptr<slave::Runtime> runtime;
    std::thread thread;
};

void to_preop(master::Master& m, uint16_t station) {
    master::Mailbox mbx(m, Address::station(station));
    ASSERT_EQ(mbx.configure_from_sii(), Error::Ok) << std::hex << station;
    master::AlStatus st;
    ASSERT_EQ(m.request_state(Address::station(station), AlState::PreOp, &st), Error::Ok)
        << std::hex << station << " AL code 0x" << st.code;
}

TEST(SegmentRuntime, ThreeDrivesAreCountedAddressedAndTakenToPreOp) {
    SegmentBus bus(3);
    bus.start();
    master::Master m(bus.master_end(), master_options());
    ASSERT_EQ(m.count_slaves().value(), 3);
    ASSERT_EQ(m.assign_station_addresses(3), Error::Ok);
    for (uint16_t k = 0; k < 3; ++k) {
        const Address a = Address::station(static_cast<uint16_t>(0x1001 + k));
        EXPECT_EQ(m.read_reg<uint16_t>(a, 0x0010).value(), 0x1001 + k) << "station address of device " << k;
        EXPECT_EQ(m.sii_read_u32(a, master::sii::SerialNumber).value(), k + 1u)
            << "SII serial number of device " << k;
    }
    for (uint16_t k = 0; k < 3; ++k)
        ASSERT_NO_FATAL_FAILURE(to_preop(m, static_cast<uint16_t>(0x1001 + k)));
    // 0x1018:04 of each agrees with its SII.
    for (uint16_t k = 0; k < 3; ++k) {
        master::Mailbox mbx(m, Address::station(static_cast<uint16_t>(0x1001 + k)));
        ASSERT_EQ(mbx.adopt_current(), Error::Ok);
        master::SdoClient sdo(mbx);
        std::array<uint8_t, 4> serial{};
        ASSERT_TRUE(sdo.upload(0x1018, 4, serial).ok());
        uint32_t v = 0;
        std::memcpy(&v, serial.data(), 4);
        EXPECT_EQ(v, k + 1u);
    }
    bus.stop();
    for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(bus.line->device(k)->stack().state(), od::AlState::PreOp) << k;
        EXPECT_TRUE(std::filesystem::is_directory(bus.dir.path / ("drive" + std::to_string(k + 1)))) << k;
    }
    EXPECT_NE(bus.log_text.str().find("ecat-slave: drive2: AL state INIT -> PREOP"), std::string::npos)
        << bus.log_text.str();
}

// Line::next_deadline_ns() right after a pass is the earliest deadline of its devices, taken while the pass
// visits them (the runtime asks for it after every pass); the device's own answer agrees, pass after pass,
// as the devices' free-running drive cycles move their deadlines on, and after a device command.
TEST(SegmentRuntime, TheLinesDeadlineAfterAPassIsItsEarliestDevices) {
    SegmentBus bus(3);  // not started: the test runs the Line's passes itself
    device::Line& line = *bus.line;
    const auto earliest = [&line] {
        uint64_t d = UINT64_MAX;
        for (int k = 0; k < static_cast<int>(line.size()); ++k)
            d = std::min(d, line.device(k)->next_deadline_ns());
        return d;
    };
    uint64_t now = bus.clock.now_ns();
    for (int pass = 0; pass < 4; ++pass) {
        line.poll(now);
        const uint64_t seen = line.next_deadline_ns();
        EXPECT_NE(seen, UINT64_MAX) << pass;  // a drive outside Op runs its own cycle
        EXPECT_EQ(seen, earliest()) << pass;
        now = std::max(now, seen);
    }
    line.poll(now);
    EXPECT_EQ(line.apply("slave 1 input 1 on").rfind("ok", 0), 0u);
    EXPECT_EQ(line.next_deadline_ns(), earliest());
}

// A device whose ESC signalled nothing and whose own deadline is not due is not looked at: no PDI access (a
// PDI access leaves its ESC's due time unknown, 0), as a controller whose ESC keeps its interrupt line low
// sleeps. An AL control request written by a frame raises the line: that device alone is served, in the next
// pass; the runtime is told to come back at once if the frame came after the device's turn.
TEST(SegmentRuntime, ALineLooksOnlyAtDevicesWithSomethingToDo) {
    SegmentBus bus(3);  // not started: the test runs the passes and walks the frames itself
    device::Line& line = *bus.line;
    esc::Segment& segment = line.segment();
    const uint64_t now = bus.clock.now_ns();
    line.poll(now);
    for (int k = 0; k < 3; ++k)
        segment.esc(k).tick(now);  // settles what the first pass's PDI accesses left unknown
    std::array<uint64_t, 3> due{};
    for (std::size_t k = 0; k < 3; ++k) {
        due[k] = segment.signals()[k].due_ns;
        ASSERT_NE(due[k], 0u) << k;
    }
    line.poll(now);
    for (std::size_t k = 0; k < 3; ++k)
        EXPECT_EQ(segment.signals()[k].due_ns, due[k])
            << "device " << k << " was accessed with nothing to do";
    // Device 1 (auto-increment address -1): AL control = Pre-Op.
    const std::array<uint8_t, 2> preop{0x02, 0x00};
    std::vector<uint8_t> frame =
        esc::wire::FrameBuilder().add(esc::Command::APWR, 0x11, 0xFFFF, 0x0120, preop).build(60);
    ASSERT_EQ(segment.walk(frame, now).kind, esc::Segment::Result::Kind::Reply);
    EXPECT_EQ(frame[16 + 10 + preop.size()], 1) << "one device written";
    EXPECT_EQ(segment.signals()[1].wake, 1);
    EXPECT_EQ(line.next_deadline_ns(), 0u) << "an event after the pass: the runtime comes back at once";
    line.poll(now);
    // AL status of device 1 read by the master: Pre-Op, or Init with the error flag (no mailbox SyncManagers
    // were set up): the request was served either way.
    std::vector<uint8_t> read =
        esc::wire::FrameBuilder().add_zero(esc::Command::APRD, 0x12, 0xFFFF, 0x0130, 2).build(60);
    ASSERT_EQ(segment.walk(read, now).kind, esc::Segment::Result::Kind::Reply);
    EXPECT_NE(read[16 + 10] & 0x1F, 0x01) << "AL status still Init without error";
    EXPECT_EQ(segment.signals()[0].due_ns, due[0]) << "device 0 was not looked at";
    EXPECT_EQ(segment.signals()[2].due_ns, due[2]) << "device 2 was not looked at";
}

// A digital IO terminal without mailbox whose SMs have no PDI interrupt (control 0x44 and 0x00, as such
// ESIs declare them) cannot use the interrupt line: its stack reads the registers themselves. It is polled
// when a frame passed its ESC or a timer of it fired (EscSignals::activity), not on every pass of the line:
// a pass in between (another device's SYNC0, a control command's pass, the runtime's timer) would find the
// registers as its last poll left them. The process data still flows every cycle.
TEST(SegmentRuntime, ATerminalThatReadsItsRegistersIsPolledWhenItsEscChanged) {
    // With device emulation (ESC configuration bit 0, the ConfigData 0401 of such terminals): the ESC takes
    // Init -> Op as it comes.
    auto terminal = std::make_shared<od::Product>(*test_products::io_terminal());
    terminal->description.esc_config = 0x01;
    SegmentBus bus(2, {terminal, terminal});
    device::Line& line = *bus.line;
    bus.start();
    master::Master m(bus.master_end(), master_options());
    ASSERT_EQ(m.count_slaves().value(), 2);
    ASSERT_EQ(m.assign_station_addresses(2), Error::Ok);
    const std::array<Address, 2> slaves{Address::station(0x1001), Address::station(0x1002)};
    master::ProcessDataSession pd(m, slaves, {});
    for (std::size_t k = 0; k < 2; ++k)
        ASSERT_EQ(pd.discover_sii(k), Error::Ok) << k;
    ASSERT_EQ(pd.configure(), Error::Ok);
    for (const Address a : slaves)
        ASSERT_EQ(m.request_state(a, AlState::Op), Error::Ok);
    auto fill = [&pd] {
        pd.outputs()[0] = 0x21;
        pd.outputs()[3] = 0x43;
    };
    ASSERT_EQ(pd.run(5, std::chrono::microseconds(200), fill), Error::Ok);
    bus.stop();  // the test runs the passes and walks the frames itself
    ASSERT_EQ(line.device(0)->stack().state(), od::AlState::Op);
    ASSERT_EQ(line.device(0)->dictionary().get<uint16_t>(0x7000, 1), 0x0021) << "outputs taken";
    ASSERT_EQ(line.device(1)->dictionary().get<uint16_t>(0x7000, 1), 0x0043) << "outputs taken";

    uint64_t now = bus.clock.now_ns();
    line.poll(now);  // after line.device(): every device is asked once
    const uint64_t polls = line.stats().polls;
    for (int pass = 0; pass < 3; ++pass)
        line.poll(now);
    EXPECT_EQ(line.stats().polls, polls) << "passes with no frame and no timer event poll nobody";
    // A frame that passes both ESCs (a BRD of the type register): each is polled once in the next pass.
    std::vector<uint8_t> frame = brd_type_frame();
    ASSERT_EQ(line.segment().walk(frame, now).kind, esc::Segment::Result::Kind::Reply);
    line.poll(now);
    EXPECT_EQ(line.stats().polls, polls + 2);
    line.poll(now);
    EXPECT_EQ(line.stats().polls, polls + 2);
    // Process data written by a frame reaches the device in the pass after it.
    std::vector<uint8_t> lrw = esc::wire::FrameBuilder()
                                   .add(esc::Command::LWR, 0x43, 0x0000, 0x0001,
                                        std::array<uint8_t, 6>{0x65, 0x00, 0x00, 0x87, 0x00, 0x00})
                                   .build(60);
    ASSERT_EQ(line.segment().walk(lrw, now).kind, esc::Segment::Result::Kind::Reply);
    line.poll(now);
    EXPECT_EQ(line.device(0)->dictionary().get<uint16_t>(0x7000, 1), 0x0065);
    EXPECT_EQ(line.device(1)->dictionary().get<uint16_t>(0x7000, 1), 0x0087);
}

TEST(SegmentRuntime, APulledCableShortensTheLine) {
    SegmentBus bus(3);
    bus.start();
    master::Master m(bus.master_end(), master_options());
    ASSERT_EQ(m.count_slaves().value(), 3);
    bus.stop();
    EXPECT_EQ(bus.line->apply("link drive2 1 down"), "ok link drive2 1 down");
    EXPECT_EQ(bus.line->apply("link 1 3 down"), "error: drive2 has no port 3");
    EXPECT_EQ(bus.line->apply("link 9 1 down").rfind("error: no device '9'", 0), 0u);
    bus.start();
    EXPECT_EQ(m.count_slaves().value(), 2) << "drive2's port 1 loops back";
    bus.stop();
    EXPECT_EQ(bus.line->apply("link drive3 0 up"), "ok link drive3 0 up");
    bus.start();
    EXPECT_EQ(m.count_slaves().value(), 3);
    bus.stop();
    EXPECT_EQ(bus.line->stats().link_changes, 2u);
    EXPECT_NE(bus.log_text.str().find("link: cable at port 1 of drive2 pulled"), std::string::npos);
}

TEST(SegmentRuntime, APowerCycledDriveComesBackInInitWithItsStoredParameters) {
    SegmentBus bus(3);
    bus.start();
    master::Master m(bus.master_end(), master_options());
    ASSERT_EQ(m.count_slaves().value(), 3);
    ASSERT_EQ(m.assign_station_addresses(3), Error::Ok);
    for (uint16_t k = 0; k < 3; ++k)
        ASSERT_NO_FATAL_FAILURE(to_preop(m, static_cast<uint16_t>(0x1001 + k)));
    {
        master::Mailbox mbx(m, Address::station(0x1002));
        ASSERT_EQ(mbx.adopt_current(), Error::Ok);
        master::SdoClient sdo(mbx);
        const uint8_t v[4] = {0x34, 0x12, 0, 0};  // 0x6065 following error window, a stored parameter
        ASSERT_EQ(sdo.download(0x6065, 0, v), Error::Ok);
        const uint8_t save[4] = {'s', 'a', 'v', 'e'};
        ASSERT_EQ(sdo.download(0x1010, 1, save), Error::Ok);
        const uint8_t w[4] = {0x78, 0x56, 0, 0};  // not saved
        ASSERT_EQ(sdo.download(0x6065, 0, w), Error::Ok);
    }
    bus.stop();
    EXPECT_EQ(bus.line->apply("power drive2 off"), "ok power drive2 off");
    EXPECT_FALSE(bus.line->powered(1));
    EXPECT_EQ(bus.line->device(1), nullptr);
    EXPECT_EQ(bus.line->apply("slave drive2 status"), "error: drive2 is powered off");
    bus.start();
    EXPECT_EQ(m.count_slaves().value(), 1) << "a powered-off drive takes its neighbours' links";
    bus.stop();
    EXPECT_EQ(bus.line->apply("power 1 on"), "ok power drive2 on");
    EXPECT_EQ(bus.line->stats().power_cycles[1], 1u);
    bus.start();
    ASSERT_EQ(m.count_slaves().value(), 3);
    // The fresh ESC has no station address; the others kept theirs.
    EXPECT_EQ(m.read_reg<uint16_t>(Address::position(1), 0x0010).value(), 0u);
    EXPECT_EQ(m.read_reg<uint16_t>(Address::position(2), 0x0010).value(), 0x1003);
    EXPECT_EQ(m.al_status(Address::position(1)).value().state, static_cast<uint8_t>(AlState::Init));
    EXPECT_EQ(m.al_status(Address::station(0x1003)).value().state, static_cast<uint8_t>(AlState::PreOp));
    ASSERT_EQ(m.write_reg<uint16_t>(Address::position(1), 0x0010, 0x1002), Error::Ok);
    ASSERT_NO_FATAL_FAILURE(to_preop(m, 0x1002));
    {
        master::Mailbox mbx(m, Address::station(0x1002));
        ASSERT_EQ(mbx.adopt_current(), Error::Ok);
        master::SdoClient sdo(mbx);
        std::array<uint8_t, 4> v{};
        ASSERT_TRUE(sdo.upload(0x6065, 0, v).ok());
        EXPECT_EQ(v[0], 0x34);
        EXPECT_EQ(v[1], 0x12);
    }
    bus.stop();
    std::string seg = bus.line->apply("segment");
    EXPECT_EQ(
        seg.rfind("ok segment 3 devices\ndevice 0 drive1 power on state PREOP links 0:up 1:up 2:- 3:-", 0),
        0u)
        << seg;
    std::ostringstream report;
    bus.line->report(report);
    EXPECT_NE(report.str().find("segment.device1.power_cycles 1\n"), std::string::npos) << report.str();
    // Every device's own statistics, under its prefix: each of the three went through Init -> Pre-Op.
    for (int k = 0; k < 3; ++k)
        EXPECT_NE(report.str().find("segment.device" + std::to_string(k) + ".stack.transitions "),
                  std::string::npos)
            << k << report.str();
    EXPECT_EQ(report.str().find("segment.device1.stack.transitions 0\n"), std::string::npos) << report.str();
}

// A power cut in the middle of an FoE download or of the commit of a new image loses nothing stored: the
// store comes back with a complete image, the old or (once committed) the new one.
TEST(SegmentRuntime, APowerCutDuringAFirmwareDownloadLosesNothingStored) {
    SegmentBus bus(2);
    const od::Identity id = bus.line->device(1)->description().identity;
    auto store_image = [&](uint32_t version, std::size_t steps_before_cut, bool finish) {
        const std::vector<uint8_t> payload(3000, static_cast<uint8_t>(version));
        const auto image = foe::build_image(payload, foe::ImageIdentity::from(id), version);
        foe::FirmwareStore& store = bus.line->device(1)->firmware_store();
        foe::StoreError e;
        ASSERT_TRUE(store.begin_write(e)) << e.text;
        ASSERT_TRUE(store.append(std::span(image).first(image.size() / 2), e)) << e.text;
        if (!finish) return;  // the download is cut half-way
        ASSERT_TRUE(store.append(std::span(image).subspan(image.size() / 2), e)) << e.text;
        ASSERT_TRUE(store.finish(e)) << e.text;
        for (std::size_t i = 0; i < steps_before_cut; ++i)
            if (store.commit_step(e) == foe::FirmwareStore::Progress::Done) break;
    };
    const uint32_t v1 = 0x01300001, v2 = 0x01300002, v3 = 0x01300003;
    ASSERT_NO_FATAL_FAILURE(store_image(v1, 1000, true));  // committed
    ASSERT_EQ(bus.line->apply("power drive2 cycle"), "ok power drive2 cycle");
    EXPECT_EQ(bus.line->device(1)->description().identity.revision, v1);

    ASSERT_NO_FATAL_FAILURE(store_image(v2, 0, false));  // half a download
    ASSERT_EQ(bus.line->apply("power drive2 cycle"), "ok power drive2 cycle");
    EXPECT_EQ(bus.line->device(1)->description().identity.revision, v1) << "the stored image is kept";
    ASSERT_TRUE(bus.line->device(1)->firmware_store().active_image().has_value());

    ASSERT_NO_FATAL_FAILURE(store_image(v3, 1, true));  // cut one step into the commit
    ASSERT_EQ(bus.line->apply("power drive2 cycle"), "ok power drive2 cycle");
    const auto& active = bus.line->device(1)->firmware_store().active_image();
    ASSERT_TRUE(active.has_value());
    const uint32_t rev = bus.line->device(1)->description().identity.revision;
    EXPECT_TRUE(rev == v1 || rev == v3) << std::hex << rev;
    EXPECT_EQ(bus.line->stats().power_cycles[1], 3u);
}

TEST(SegmentRuntime, ADelayedHopHoldsTheReply) {
    SegmentBus bus(3);
    EXPECT_EQ(bus.line->apply("delay 2 1000000000"), "ok delay hop 2 1000000000");  // one second
    const auto f = brd_type_frame();
    ASSERT_TRUE(bus.master_end().send(f));
    ASSERT_TRUE(bus.runtime->run_once(100));
    EXPECT_EQ(bus.runtime->held(), 1u) << "the reply waits in the hold queue";
    EXPECT_EQ(bus.master_end().pending(), 0u);
    EXPECT_EQ(bus.runtime->stats().frames_held, 1u);
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    // run_once() also returns for the drives' own 10 ms cycles: wait by the clock, not by passes.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (bus.master_end().pending() == 0 && std::chrono::steady_clock::now() < deadline)
        ASSERT_TRUE(bus.runtime->run_once(100));
    ASSERT_EQ(bus.master_end().receive(buf), f.size());
    EXPECT_EQ(buf[kWkcOffset], 3) << "BRD through three ESCs";
    EXPECT_EQ(bus.runtime->held(), 0u);

    EXPECT_EQ(bus.line->apply("clear"), "ok clear");
    ASSERT_TRUE(bus.master_end().send(f));
    ASSERT_TRUE(bus.runtime->run_once(100));
    EXPECT_EQ(bus.master_end().pending(), 1u) << "no hold without a delay";
    EXPECT_EQ(bus.runtime->stats().frames_held, 1u);
}

// Frames that come in one burst are walked one after the other and their replies leave together, in the
// order of the frames, once the burst is done: a master that sent several frames is woken once for them.
TEST(SegmentRuntime, TheRepliesOfABurstLeaveTogetherInOrder) {
    SegmentBus bus(3);
    std::vector<std::vector<uint8_t>> sent;
    for (uint8_t index = 0x10; index < 0x15; ++index) {
        sent.push_back(esc::wire::FrameBuilder().add_zero(esc::Command::BRD, index, 0, 0x0000, 1).build(60));
        ASSERT_TRUE(bus.master_end().send(sent.back()));
    }
    const uint64_t batches = bus.runtime->stats().reply_batches;
    ASSERT_TRUE(bus.runtime->run_once(100));
    EXPECT_EQ(bus.runtime->stats().frames_received, 5u);
    EXPECT_EQ(bus.runtime->stats().frames_sent, 5u);
    EXPECT_EQ(bus.runtime->stats().reply_batches, batches + 1) << "one batch for the burst";
    ASSERT_EQ(bus.master_end().pending(), 5u);
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    for (const auto& f : sent) {
        ASSERT_EQ(bus.master_end().receive(buf), f.size());
        EXPECT_EQ(buf[16 + 1], f[16 + 1]) << "the replies in the order of the frames";
        EXPECT_EQ(buf[kWkcOffset], 3);
    }
}

TEST(SegmentRuntime, DropAndCorruptAreCountedPerHop) {
    SegmentBus bus(3);
    EXPECT_EQ(bus.line->apply("drop 1 1"), "ok drop hop 1 1");
    const auto f = brd_type_frame();
    ASSERT_TRUE(bus.master_end().send(f));
    ASSERT_TRUE(bus.runtime->run_once(100));
    EXPECT_EQ(bus.master_end().pending(), 0u) << "the frame is lost on hop 1";
    EXPECT_EQ(bus.line->segment().hop_stats(1).dropped, 1u);
    EXPECT_EQ(bus.line->apply("drop 1 0"), "ok drop hop 1 0");
    EXPECT_EQ(bus.line->apply("corrupt 2 1"), "ok corrupt hop 2 1");
    ASSERT_TRUE(bus.master_end().send(f));
    ASSERT_TRUE(bus.runtime->run_once(100));
    EXPECT_EQ(bus.line->segment().hop_stats(2).corrupted, 1u);
    EXPECT_EQ(bus.line->segment().hop_stats(1).corrupted, 0u);
    EXPECT_EQ(bus.line->apply("drop 3 0.5").rfind("error: usage: drop <hop 0-2>", 0), 0u);
    EXPECT_EQ(bus.line->apply("corrupt 0 1.5"), "error: usage: corrupt <hop> <fraction 0-1>");
    EXPECT_EQ(bus.line->apply("power drive9 off").rfind("error: no device 'drive9'", 0), 0u);
    EXPECT_EQ(bus.line->apply("status").rfind("ok state INIT", 0), 0u)
        << "device 0's commands without prefix";
    EXPECT_EQ(bus.line->apply("slave 2 status").rfind("ok state INIT", 0), 0u);
    EXPECT_NE(bus.line->apply("bogus").find("power, clear, segment)"), std::string::npos);
    std::ostringstream report;
    bus.line->report(report);
    EXPECT_NE(report.str().find("segment.hop1.dropped 1\n"), std::string::npos) << report.str();
    EXPECT_NE(report.str().find("segment.hop2.corrupted 1\n"), std::string::npos) << report.str();
    EXPECT_NE(bus.log_text.str().find("fault: drop 1 of the frames on hop 1 (the cable into drive2)"),
              std::string::npos)
        << bus.log_text.str();
}

}  // namespace

namespace {

// The line continues on an out link (--out-iface): a second, lone ESC behind it answers as the next process
// or a hardware device would; the master counts both. Without a carrier the external port loops back.
TEST(SegmentRuntime, TheLineContinuesOnTheOutLink) {
    test_support::TempDir dir("segment-out-");
    esc::SystemClock clock;
    auto in = esc::LoopbackLink::make_pair(64);
    auto out = esc::LoopbackLink::make_pair(64);
    device::LineOptions o;
    o.topology = slave::line_topology(2);
    o.base.state_dir = dir.path;
    std::ostringstream warnings, log_text;
    o.base.log = &warnings;
    slave::Log log(log_text);
    o.log = &log;
    esc::LoopbackLink& out_end = *out.first;
    device::Line line(clock, std::move(o), [&out_end](std::span<const uint8_t> f) { (void)out_end.send(f); });
    slave::Runtime runtime(*in.second, line.segment(), clock, out.first.get());
    runtime.set_firmware(&line);
    bool carrier = true;
    runtime.set_carrier_check([&carrier] { return carrier; }, &log, "out0");
    esc::Esc next(esc::EscConfig{}, clock);  // the device behind the out link

    auto brd_wkc = [&]() -> int {
        const auto f = brd_type_frame();
        EXPECT_TRUE(in.first->send(f));
        std::array<uint8_t, esc::kMaxFrameSize> buf{};
        for (int i = 0; i < 200; ++i) {
            EXPECT_TRUE(runtime.run_once(10));
            // The far side: what came out of OUT goes through the next ESC and back.
            std::array<uint8_t, esc::kMaxFrameSize> far{};
            while (const std::size_t n = out.second->receive(far)) {
                std::span<uint8_t> frame(far.data(), n);
                if (next.process_frame(frame)) (void)out.second->send(frame);
            }
            if (const std::size_t n = in.first->receive(buf); n > 0) return buf[kWkcOffset];
        }
        return -1;
    };
    EXPECT_EQ(brd_wkc(), 3) << "two ESCs here and one behind the out link";
    EXPECT_GT(runtime.stats().frames_external, 0u);
    EXPECT_GT(runtime.stats().frames_resumed, 0u);

    carrier = false;  // the peer went away: polled within kCarrierPollNs
    for (auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
         runtime.stats().carrier_changes == 0 && std::chrono::steady_clock::now() < until;)
        ASSERT_TRUE(runtime.run_once(10));
    ASSERT_EQ(runtime.stats().carrier_changes, 1u);
    EXPECT_EQ(brd_wkc(), 2) << "no carrier: the last device's port 1 loops back";
    EXPECT_NE(log_text.str().find("out link out0: no carrier"), std::string::npos) << log_text.str();
    carrier = true;
    for (auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
         runtime.stats().carrier_changes == 1 && std::chrono::steady_clock::now() < until;)
        ASSERT_TRUE(runtime.run_once(10));
    EXPECT_EQ(brd_wkc(), 3);
}

}  // namespace
