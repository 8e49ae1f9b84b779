// FoE through the whole slave: a master (tools/lib/master) drives esc::Esc + ecat::Stack with the FoE server
// and the CoE server registered, on the drive's description: Init -> Bootstrap with the bootstrap mailbox,
// firmware download with BUSY handling as SOEM/IgH do it, Bootstrap -> Init restarts the device on the new
// image, then upload in Pre-Op and a refused write outside Bootstrap.
#include <gtest/gtest.h>

#include <chrono>
#include <deque>
#include <memory>
#include <vector>

#include "coe/sdo_server.hpp"
#include "ecat/application.hpp"
#include "ecat/stack.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "esi/sii.hpp"
#include "foe/firmware.hpp"
#include "foe_test_support.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "maxpos/maxpos.hpp"

#include "support/master_bring_up.hpp"
#include "support/wire_link.hpp"

namespace {

using Bytes = std::vector<uint8_t>;

// On Bootstrap -> Init the device "restarts": the store is reopened and the active image decides the
// revision, as the drive glue does before it rebuilds its dictionary.
struct RestartingApp final : ecat::Application {
    foe::FirmwareUpdate* fw = nullptr;
    od::Identity* identity = nullptr;
    int restarts = 0;
    void on_restart() override {
        ++restarts;
        fw->restart();
        fw->apply_to(*identity);
    }
};

struct Slave {
    esc::ManualClock clock;
    od::DeviceDescription desc;
    od::Dictionary dict;
    foe_test::TempDir dir;
    std::unique_ptr<foe::FirmwareUpdate> fw;
    foe::FirmwareStore* store = nullptr;
    std::unique_ptr<esc::Esc> esc;
    RestartingApp app;
    std::unique_ptr<ecat::Stack> stack;
    std::unique_ptr<coe::CoeServer> coe;

    Slave() {
        desc = maxpos::description();
        maxpos::place_sync_managers(desc);
        dict = maxpos::dictionary(desc);
        clock.set(1'000'000'000);
        fw = std::make_unique<foe::FirmwareUpdate>(dir.path, desc);
        EXPECT_TRUE(fw->ok());
        EXPECT_FALSE(fw->apply_to(desc.identity));  // nothing stored yet: the built-in identity stays
        store = &fw->store();
        app.fw = fw.get();
        app.identity = &desc.identity;
        esc = std::make_unique<esc::Esc>(esc::EscConfig{}, clock);
        esc->load_eeprom(esi::build_sii(desc, dict));
        stack = std::make_unique<ecat::Stack>(*esc, dict, desc, app);
        coe = std::make_unique<coe::CoeServer>(dict, [this] { return stack->state(); });
        stack->add_handler(*coe);
        stack->add_handler(fw->server());
        stack->poll(clock.now_ns());
    }
};

// The master's link to this slave: each frame through the ESC, then the firmware, as the runtime does.
struct SlaveLink final : test_support::WireLink {
    explicit SlaveLink(Slave& s)
        : WireLink([&s](std::vector<uint8_t>& f) {
              s.clock.advance(50'000);
              const bool back = s.esc->process_frame(f);
              s.esc->tick();
              s.stack->poll(s.clock.now_ns());
              return back;
          }) {}
};

using foe_test::foe_packet;
std::span<const uint8_t> text(std::string_view s) {
    return {reinterpret_cast<const uint8_t*>(s.data()), s.size()};
}

class FoeOverTheStack : public ::testing::Test {
  protected:
    FoeOverTheStack() : link(slave), m(link, options()), mbx(m, a) {}
    static master::MasterOptions options() { return test_support::in_process_master_options(); }
    void SetUp() override { ASSERT_NO_FATAL_FAILURE(test_support::one_slave_addressed(m)); }
    // Init -> Bootstrap with the bootstrap mailbox from the description (SII words 0x14-0x17).
    void enter_bootstrap() {
        const auto& b = slave.desc.bootstrap_mailbox;
        master::MailboxConfig c{b.out_start, b.out_size, b.in_start, b.in_size, 0};
        ASSERT_EQ(mbx.configure(c), master::Error::Ok);
        master::AlStatus st;
        ASSERT_EQ(m.request_state(a, master::AlState::Boot, &st), master::Error::Ok) << std::hex << st.code;
    }
    void enter_preop() {
        ASSERT_EQ(m.request_state(a, master::AlState::Init), master::Error::Ok);
        ASSERT_EQ(mbx.configure_from_sii(), master::Error::Ok);
        master::AlStatus st;
        ASSERT_EQ(m.request_state(a, master::AlState::PreOp, &st), master::Error::Ok) << std::hex << st.code;
    }
    Bytes exchange(const Bytes& request) {
        EXPECT_EQ(mbx.send(master::MailboxType::FoE, request), master::Error::Ok);
        master::MailboxMessage r;
        EXPECT_EQ(mbx.receive(r), master::Error::Ok);
        EXPECT_EQ(r.type, master::MailboxType::FoE);
        return Bytes(r.payload.begin(), r.payload.end());
    }
    // Returns the final answer: ACK or ERR.
    Bytes download(const Bytes& image, std::string_view name, unsigned* busy = nullptr) {
        const std::size_t chunk = mbx.max_out_payload() - 6;
        Bytes r = exchange(foe_packet(2, 0, text(name)));
        if (r.size() < 6 || r[0] != 4) return r;
        std::size_t off = 0;
        for (uint32_t packet = 1;; ++packet) {
            const std::size_t n = std::min(chunk, image.size() - off);
            const Bytes d = foe_packet(3, packet, {image.data() + off, n});
            off += n;
            r = exchange(d);
            // Storing runs on a worker thread and fsyncs: bound the wait by time, not by a count of polls
            // (a count ran out before a slow disk finished).
            const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
            while (r.size() >= 6 && r[0] == 6 && std::chrono::steady_clock::now() < give_up) {
                if (busy) ++*busy;
                r = exchange(d);  // SOEM / IgH: repeat the last DATA after BUSY
            }
            if (r.size() < 6 || r[0] != 4 || n < chunk) return r;
        }
    }
    Bytes upload(std::string_view name, Bytes* error) {
        const std::size_t chunk = mbx.max_in_payload() - 6;
        Bytes file;
        Bytes r = exchange(foe_packet(1, 0, text(name)));
        for (uint32_t packet = 1;; ++packet) {
            if (r.size() < 6 || r[0] != 3 || foe_test::le32(r, 2) != packet) {
                *error = r;
                return {};
            }
            file.insert(file.end(), r.begin() + 6, r.end());
            const bool last = r.size() - 6 < chunk;
            if (last) {
                EXPECT_EQ(mbx.send(master::MailboxType::FoE, foe_packet(4, packet)), master::Error::Ok);
                return file;
            }
            r = exchange(foe_packet(4, packet));
        }
    }

    Slave slave;
    SlaveLink link;
    master::Master m;
    const master::Address a = master::Address::station(0x1001);
    master::Mailbox mbx;
};

}  // namespace

TEST_F(FoeOverTheStack, DownloadInBootstrapRestartOnNewImageUploadInPreOp) {
    const foe::ImageIdentity id = foe::ImageIdentity::from(slave.desc.identity);
    const Bytes image = foe::build_image(foe_test::payload_bytes(50'000, 9), id, 0x01300000);
    enter_bootstrap();
    EXPECT_EQ(mbx.max_out_payload(), 1024u - 6u);
    unsigned busy = 0;
    const Bytes answer = download(image, "MAXPOS", &busy);
    ASSERT_EQ(answer.size(), 6u);
    EXPECT_EQ(answer[0], 4) << "ERR 0x" << std::hex << foe_test::le32(answer, 2);
    // The final DATA is answered when the image is stored (BUSY only for a commit past busy_after_ns, which
    // a slow disk may reach): whatever came before, the answer is the ACK.
    (void)busy;
    ASSERT_TRUE(slave.store->active_image());
    EXPECT_EQ(slave.store->active_image()->header.version, 0x01300000u);

    // Bootstrap -> Init: the device restarts on the new image.
    ASSERT_EQ(m.request_state(a, master::AlState::Init), master::Error::Ok);
    EXPECT_EQ(slave.app.restarts, 1);
    EXPECT_EQ(slave.desc.identity.revision, 0x01300000u);
    EXPECT_EQ(slave.desc.identity.software_version, "0130h");

    enter_preop();
    Bytes error;
    EXPECT_EQ(upload("MAXPOS", &error), image);
    EXPECT_EQ(upload("MAXPOS_0130h_3001h_0000h_0000h.bin", &error), image);

    // Writing outside Bootstrap: "Bootstrap only".
    const Bytes refused = exchange(foe_packet(2, 0, text("MAXPOS")));
    ASSERT_GE(refused.size(), 6u);
    EXPECT_EQ(refused[0], 5);
    EXPECT_EQ(foe_test::le32(refused, 2), 0x8008u);
}

TEST_F(FoeOverTheStack, ImageForAnotherProductKeepsTheOldOne) {
    const foe::ImageIdentity id = foe::ImageIdentity::from(slave.desc.identity);
    enter_bootstrap();
    ASSERT_EQ(download(foe::build_image(foe_test::payload_bytes(3000, 1), id, 0x01200000), "MAXPOS")[0], 4);
    const Bytes other =
        foe::build_image(foe_test::payload_bytes(3000, 2), {id.vendor_id, 0x30990000}, 0x01300000);
    const Bytes r = download(other, "MAXPOS_0130h_3099h_0000h_0000h.bin");
    ASSERT_GE(r.size(), 6u);
    EXPECT_EQ(r[0], 5);
    EXPECT_EQ(foe_test::le32(r, 2), 0x800Du);
    ASSERT_EQ(m.request_state(a, master::AlState::Init), master::Error::Ok);
    EXPECT_EQ(slave.desc.identity.revision, 0x01200000u);
    EXPECT_EQ(slave.fw->active_version(), 0x01200000u);
}

TEST_F(FoeOverTheStack, LengthAMultipleOfTheBootstrapPacketSize) {
    const foe::ImageIdentity id = foe::ImageIdentity::from(slave.desc.identity);
    enter_bootstrap();
    const std::size_t chunk = mbx.max_out_payload() - 6;
    const Bytes image =
        foe::build_image(foe_test::payload_bytes(4 * chunk - foe::kImageHeaderSize, 3), id, 0x01400000);
    ASSERT_EQ(image.size() % chunk, 0u);
    const Bytes r = download(image, "MAXPOS");
    ASSERT_EQ(r.size(), 6u);
    EXPECT_EQ(r[0], 4);
    EXPECT_EQ(foe_test::le32(r, 2), 5u);  // 4 full packets and the empty one
    EXPECT_EQ(slave.store->active_image()->header.version, 0x01400000u);
}
