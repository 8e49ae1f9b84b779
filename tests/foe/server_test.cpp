#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <thread>

#include "foe/server.hpp"
#include "foe_test_support.hpp"

using namespace foe;
using foe_test::FakeSender;
using foe_test::kMaxpos;
using foe_test::le32;
using foe_test::TempDir;

namespace {

using Bytes = std::vector<uint8_t>;

Bytes request(Opcode op, uint32_t value, std::string_view tail = {}) {
    return foe_test::foe_packet(static_cast<uint8_t>(op), value,
                                {reinterpret_cast<const uint8_t*>(tail.data()), tail.size()});
}
Bytes data(uint32_t packet, std::span<const uint8_t> bytes) {
    Bytes m = request(Opcode::Data, packet);
    m.insert(m.end(), bytes.begin(), bytes.end());
    return m;
}

bool is_ack(const Bytes& m, uint32_t packet) {
    return m.size() == 6 && m[0] == 4 && le32(m, 2) == packet;
}
bool is_busy(const Bytes& m) {
    return m.size() == 6 && m[0] == 6;
}
uint32_t error_code(const Bytes& m) {
    return m.size() >= 6 && m[0] == 5 ? le32(m, 2) : 0;
}
std::string error_string(const Bytes& m) {
    return m.size() > 6 ? std::string(m.begin() + 6, m.end()) : "";
}

// Commit steps from poll() only: deterministic. The final DATA answered BUSY at once (busy_after_ns = 0),
// the path of a commit that outlasts ServerConfig::busy_after_ns; the default is tested on its own below.
ServerConfig stepped() {
    ServerConfig c;
    c.commit_in_thread = false;
    c.busy_after_ns = 0;
    return c;
}

struct Fixture : ::testing::Test {
    TempDir dir;
    FirmwareStore store{[&] {
        StoreConfig c;
        c.dir = dir.path;
        c.identity = kMaxpos;
        return c;
    }()};
    FoeServer server{store, stepped()};
    FakeSender out;  // 128-byte mailbox: 116 data bytes per packet
    uint64_t now = 1'000'000;
    static constexpr std::size_t kChunk = 128 - 12;

    void SetUp() override {
        ASSERT_TRUE(store.open());
        server.on_state_change(od::AlState::Init, od::AlState::Boot);
    }
    Bytes exchange(const Bytes& m) {
        server.handle(m, out);
        EXPECT_EQ(out.sent.size(), 1u) << "one reply per request";
        Bytes r = out.take();
        out.sent.clear();
        return r;
    }
    void poll(uint64_t advance_ns = 1'000'000) {
        now += advance_ns;
        server.poll(now, out);
        EXPECT_TRUE(out.sent.empty()) << "poll() never sends on its own";
    }
    // A complete download as SOEM/IgH do it: WRQ, DATA..., repeat the last DATA after BUSY until ACK.
    // Returns the final answer (ACK or ERR).
    Bytes download(const Bytes& image, std::string_view name = "MAXPOS", uint32_t password = 0) {
        Bytes r = exchange(request(Opcode::Write, password, name));
        if (!is_ack(r, 0)) return r;
        uint32_t packet = 1;
        std::size_t off = 0;
        for (;;) {
            const std::size_t n = std::min(kChunk, image.size() - off);
            const Bytes d = data(packet, {image.data() + off, n});
            r = exchange(d);
            off += n;
            if (n < kChunk) {
                for (int i = 0; i < 1000 && is_busy(r); ++i) {
                    poll();
                    r = exchange(d);
                }
                return r;
            }
            if (!is_ack(r, packet)) return r;
            ++packet;
        }
    }
    // A complete upload; returns the file, or the ERR message in *error.
    Bytes upload(std::string_view name, Bytes* error = nullptr, uint32_t password = 0) {
        Bytes file;
        Bytes r = exchange(request(Opcode::Read, password, name));
        for (uint32_t packet = 1;; ++packet) {
            if (r.empty() || r[0] != 3 || le32(r, 2) != packet) {
                if (error) *error = r;
                return {};
            }
            file.insert(file.end(), r.begin() + 6, r.end());
            const bool last = r.size() - 6 < kChunk;
            server.handle(request(Opcode::Ack, packet), out);
            if (last) {
                EXPECT_TRUE(out.sent.empty()) << "no answer to the last ACK";
                return file;
            }
            r = out.take();
        }
    }
    uint32_t active_version() const {
        return store.active_image() ? store.active_image()->header.version : 0;
    }
    // The clean server refuses the write request `taken` with the FoE error taken_code; a server with `fault`
    // set, in Bootstrap, takes it (ACK 0) and still refuses `refused` with refused_code.
    void expect_fault_takes(bool FoeFaults::*fault, const Bytes& taken, uint32_t taken_code,
                            const Bytes& refused, uint32_t refused_code) {
        EXPECT_EQ(error_code(exchange(taken)), taken_code);
        ServerConfig c = stepped();
        c.faults.*fault = true;
        FoeServer faulty(store, c);
        faulty.on_state_change(od::AlState::Init, od::AlState::Boot);
        faulty.handle(taken, out);
        ASSERT_EQ(out.sent.size(), 1u);
        EXPECT_TRUE(is_ack(out.take(), 0));
        faulty.abort_transfer();
        faulty.handle(refused, out);
        ASSERT_EQ(out.sent.size(), 1u);
        EXPECT_EQ(error_code(out.take()), refused_code);
    }
};

Bytes image_v(uint32_t version, std::size_t size = 1000) {
    return build_image(foe_test::payload_bytes(size, version), kMaxpos, version);
}

}  // namespace

using FoeServerSession = Fixture;

TEST_F(FoeServerSession, FullWriteInBootstrapThenReadBack) {
    const auto image = image_v(0x01300000, 5000);
    const Bytes answer = download(image);
    EXPECT_TRUE(is_ack(answer, static_cast<uint32_t>(image.size() / kChunk + 1)));
    EXPECT_EQ(active_version(), 0x01300000u);
    EXPECT_TRUE(server.idle());
    EXPECT_EQ(server.stats().writes_completed, 1u);

    // Read back in Pre-Op: by the device name and by the firmware file name.
    server.on_state_change(od::AlState::Boot, od::AlState::Init);
    server.on_state_change(od::AlState::Init, od::AlState::PreOp);
    EXPECT_EQ(upload("MAXPOS"), image);
    EXPECT_EQ(upload("MAXPOS_0130h_3001h_0000h_0000h.bin"), image);
    EXPECT_EQ(upload("maxpos_0130H_3001h_0000h_0000h.BIN"), image);
}

TEST_F(FoeServerSession, PreviousImageStaysReadableByItsName) {
    ASSERT_TRUE(is_ack(download(image_v(0x01200000)), 9));
    ASSERT_TRUE(is_ack(download(image_v(0x01300000)), 9));
    EXPECT_EQ(upload("MAXPOS_0120h_3001h_0000h_0000h.bin"), image_v(0x01200000));
    EXPECT_EQ(upload("MAXPOS"), image_v(0x01300000));
}

TEST_F(FoeServerSession, ReadWithoutImageOrUnknownNameIsNotFound) {
    Bytes err;
    EXPECT_TRUE(upload("MAXPOS", &err).empty());
    EXPECT_EQ(error_code(err), 0x8001u);
    EXPECT_EQ(error_string(err).rfind("Not found", 0), 0u);
    ASSERT_TRUE(is_ack(download(image_v(0x01200000)), 9));
    EXPECT_TRUE(upload("EPOS4", &err).empty());
    EXPECT_EQ(error_code(err), 0x8001u);
}

TEST_F(FoeServerSession, WrongPasswordIsNoRights) {
    const Bytes r = exchange(request(Opcode::Write, 0x1234, "MAXPOS"));
    EXPECT_EQ(error_code(r), 0x800Au);
    EXPECT_EQ(error_string(r).rfind("No rights", 0), 0u);
    ASSERT_TRUE(is_ack(download(image_v(0x01200000)), 9));
    Bytes err;
    EXPECT_TRUE(upload("MAXPOS", &err, 7).empty());
    EXPECT_EQ(error_code(err), 0x800Au);
}

TEST_F(FoeServerSession, ConfiguredPasswordIsRequired) {
    ServerConfig c = stepped();
    c.password = 0x12345678;
    FoeServer s(store, c);
    s.set_state(od::AlState::Boot);
    s.handle(request(Opcode::Write, 0, "MAXPOS"), out);
    EXPECT_EQ(error_code(out.take()), 0x800Au);
    s.handle(request(Opcode::Write, 0x12345678, "MAXPOS"), out);
    EXPECT_TRUE(is_ack(out.take(), 0));
}

TEST_F(FoeServerSession, ImageForAnotherProductIsRefusedAtItsFirstPacket) {
    ASSERT_TRUE(is_ack(download(image_v(0x01200000)), 9));
    const auto other = build_image(foe_test::payload_bytes(3000, 5), {0xFB, 0x30020000}, 0x01300000);
    ASSERT_TRUE(is_ack(exchange(request(Opcode::Write, 0, "MAXPOS")), 0));
    const Bytes r = exchange(data(1, {other.data(), kChunk}));
    EXPECT_EQ(error_code(r), 0x800Du);
    EXPECT_NE(error_string(r).find("0x30020000"), std::string::npos) << error_string(r);
    EXPECT_TRUE(server.idle());
    EXPECT_EQ(active_version(), 0x01200000u);
    const auto vendor = build_image(foe_test::payload_bytes(300, 5), {0xAA, 0x30010000}, 0x01300000);
    EXPECT_EQ(error_code(download(vendor)), 0x800Du);
    EXPECT_EQ(active_version(), 0x01200000u);
}

TEST_F(FoeServerSession, CorruptedImageIsInvalidChecksum) {
    ASSERT_TRUE(is_ack(download(image_v(0x01200000)), 9));
    auto bad = image_v(0x01300000, 2000);
    bad[1500] ^= 0x10;
    const Bytes r = download(bad);
    EXPECT_EQ(error_code(r), 0x800Cu);
    EXPECT_EQ(error_string(r).rfind("Invalid checksum", 0), 0u);
    EXPECT_EQ(active_version(), 0x01200000u);
    // Not an image at all.
    EXPECT_EQ(error_code(download(Bytes(500, 0xAB))), 0x8010u);
    EXPECT_EQ(active_version(), 0x01200000u);
}

TEST_F(FoeServerSession, TransferCutOffThenNewRequestStartsClean) {
    ASSERT_TRUE(is_ack(download(image_v(0x01200000)), 9));
    const auto image = image_v(0x01300000, 4000);
    ASSERT_TRUE(is_ack(exchange(request(Opcode::Write, 0, "MAXPOS")), 0));
    for (uint32_t p = 1; p <= 10; ++p)
        ASSERT_TRUE(is_ack(exchange(data(p, {image.data() + (p - 1) * kChunk, kChunk})), p));
    // The master gives up and starts again.
    EXPECT_TRUE(is_ack(download(image), 35));
    EXPECT_EQ(active_version(), 0x01300000u);
    EXPECT_EQ(server.stats().cancelled, 1u);
    // A read request also cancels a write half-way.
    ASSERT_TRUE(is_ack(exchange(request(Opcode::Write, 0, "MAXPOS")), 0));
    ASSERT_TRUE(is_ack(exchange(data(1, {image.data(), kChunk})), 1));
    EXPECT_EQ(upload("MAXPOS"), image);
    EXPECT_EQ(error_code(exchange(data(2, {image.data() + kChunk, kChunk}))), 0x8004u);
    EXPECT_EQ(active_version(), 0x01300000u);
}

TEST_F(FoeServerSession, StaleTransferTimesOut) {
    const auto image = image_v(0x01300000, 4000);
    ASSERT_TRUE(is_ack(exchange(request(Opcode::Write, 0, "MAXPOS")), 0));
    ASSERT_TRUE(is_ack(exchange(data(1, {image.data(), kChunk})), 1));
    poll(5'000'000'000ull);
    EXPECT_FALSE(server.idle());
    poll(6'000'000'000ull);
    EXPECT_TRUE(server.idle());
    EXPECT_EQ(server.stats().timeouts, 1u);
    EXPECT_EQ(error_code(exchange(data(2, {image.data() + kChunk, kChunk}))), 0x8004u);
    EXPECT_FALSE(store.active_image());
}

TEST_F(FoeServerSession, PathLikeAndMalformedNamesAreRefused) {
    for (std::string name :
         {std::string("../MAXPOS"), std::string("/MAXPOS"), std::string("a/b"), std::string("a\\b"),
          std::string("C:MAXPOS"), std::string(".."), std::string("MAX\0POS", 7), std::string("MAX\x01POS"),
          std::string("MAX\x7fPOS"), std::string("MAX\xc3\xa9POS"), std::string(65, 'A')}) {
        SCOPED_TRACE(name);
        for (Opcode op : {Opcode::Write, Opcode::Read}) {
            const Bytes r = exchange(request(op, 0, name));
            EXPECT_EQ(error_code(r), 0x8002u);
            EXPECT_EQ(error_string(r).rfind("Access denied", 0), 0u);
        }
    }
    EXPECT_EQ(error_code(exchange(request(Opcode::Write, 0, ""))), 0x8001u);
    EXPECT_EQ(error_code(exchange(request(Opcode::Write, 0, "OTHER"))), 0x8001u);
    // A C-string terminator is not part of the name.
    EXPECT_TRUE(is_ack(exchange(request(Opcode::Write, 0, std::string("MAXPOS\0\0", 8))), 0));
    EXPECT_TRUE(is_ack(exchange(request(Opcode::Write, 0, "MAXPOS_0130h_3001h_0000h_0000h.bin")), 0));
    EXPECT_EQ(error_code(exchange(request(Opcode::Write, 0, "MAXPOS_0130h_3001h_0000h.bin"))), 0x8001u);
}

TEST_F(FoeServerSession, WriteOutsideBootstrapIsBootstrapOnly) {
    for (od::AlState s : {od::AlState::PreOp, od::AlState::SafeOp, od::AlState::Op}) {
        server.on_state_change(od::AlState::Init, s);
        const Bytes r = exchange(request(Opcode::Write, 0, "MAXPOS"));
        EXPECT_EQ(error_code(r), 0x8008u);
        EXPECT_EQ(error_string(r).rfind("Bootstrap only", 0), 0u);
    }
    EXPECT_FALSE(server.available(od::AlState::Init));
    EXPECT_TRUE(server.available(od::AlState::Boot));
    EXPECT_TRUE(server.available(od::AlState::PreOp));
}

TEST_F(FoeServerSession, LeavingBootstrapDropsTheDownload) {
    const auto image = image_v(0x01300000, 4000);
    ASSERT_TRUE(is_ack(exchange(request(Opcode::Write, 0, "MAXPOS")), 0));
    ASSERT_TRUE(is_ack(exchange(data(1, {image.data(), kChunk})), 1));
    server.on_state_change(od::AlState::Boot, od::AlState::Init);
    EXPECT_TRUE(server.idle());
    EXPECT_FALSE(store.writing());
}

TEST_F(FoeServerSession, PacketNumberWrong) {
    const auto image = image_v(0x01300000, 4000);
    ASSERT_TRUE(is_ack(exchange(request(Opcode::Write, 0, "MAXPOS")), 0));
    ASSERT_TRUE(is_ack(exchange(data(1, {image.data(), kChunk})), 1));
    // A repeated packet (lost ACK) is acknowledged again, not stored twice.
    ASSERT_TRUE(is_ack(exchange(data(1, {image.data(), kChunk})), 1));
    EXPECT_EQ(store.received(), kChunk);
    const Bytes r = exchange(data(3, {image.data() + kChunk, kChunk}));
    EXPECT_EQ(error_code(r), 0x8005u);
    EXPECT_EQ(error_string(r).rfind("Packet number wrong", 0), 0u);
    EXPECT_TRUE(server.idle());
    // On a read: an ACK for another packet.
    ASSERT_TRUE(is_ack(download(image), 35));
    const Bytes d = exchange(request(Opcode::Read, 0, "MAXPOS"));
    ASSERT_EQ(d[0], 3);
    EXPECT_EQ(error_code(exchange(request(Opcode::Ack, 2))), 0x8005u);
}

TEST_F(FoeServerSession, BusyWhileStoring) {
    const auto image = image_v(0x01300000, 500'000);  // several read-back steps
    ASSERT_TRUE(is_ack(exchange(request(Opcode::Write, 0, "MAXPOS")), 0));
    uint32_t packet = 1;
    std::size_t off = 0;
    for (; image.size() - off >= kChunk; off += kChunk, ++packet)
        ASSERT_TRUE(is_ack(exchange(data(packet, {image.data() + off, kChunk})), packet));
    const Bytes last = data(packet, {image.data() + off, image.size() - off});
    Bytes r = exchange(last);
    ASSERT_TRUE(is_busy(r));
    EXPECT_EQ(r[4] | r[5] << 8, 100);  // entire
    EXPECT_TRUE(server.storing());
    // Without poll() nothing moves: the repeated DATA gets BUSY again.
    EXPECT_TRUE(is_busy(exchange(last)));
    EXPECT_EQ(active_version(), 0u);
    unsigned busy = 2, previous_done = 0;
    while (is_busy(r)) {
        const unsigned done = r[2] | r[3] << 8;
        EXPECT_GE(done, previous_done);
        EXPECT_LE(done, 100u);
        previous_done = done;
        poll();
        r = exchange(last);
        if (is_busy(r)) ++busy;
        ASSERT_LT(busy, 100u);
    }
    EXPECT_TRUE(is_ack(r, packet));
    EXPECT_GE(busy, 5u);
    EXPECT_EQ(active_version(), 0x01300000u);
    EXPECT_TRUE(server.idle());
}

TEST_F(FoeServerSession, FileLengthMultipleOfThePacketSize) {
    // 3 full packets exactly: the master ends with an empty DATA.
    const auto image = image_v(0x01300000, 3 * kChunk - kImageHeaderSize);
    ASSERT_EQ(image.size(), 3 * kChunk);
    ASSERT_TRUE(is_ack(exchange(request(Opcode::Write, 0, "MAXPOS")), 0));
    for (uint32_t p = 1; p <= 3; ++p)
        ASSERT_TRUE(is_ack(exchange(data(p, {image.data() + (p - 1) * kChunk, kChunk})), p));
    EXPECT_EQ(active_version(), 0u);
    EXPECT_FALSE(server.storing());
    Bytes r = exchange(data(4, {}));
    ASSERT_TRUE(is_busy(r));
    while (is_busy(r)) {
        poll();
        r = exchange(data(4, {}));
    }
    EXPECT_TRUE(is_ack(r, 4));
    EXPECT_EQ(active_version(), 0x01300000u);

    // Reading it back ends with an empty DATA 4.
    ASSERT_EQ(exchange(request(Opcode::Read, 0, "MAXPOS")).size(), 6 + kChunk);
    ASSERT_EQ(exchange(request(Opcode::Ack, 1)).size(), 6 + kChunk);
    ASSERT_EQ(exchange(request(Opcode::Ack, 2)).size(), 6 + kChunk);
    const Bytes empty = exchange(request(Opcode::Ack, 3));
    EXPECT_EQ(empty, request(Opcode::Data, 4));
    server.handle(request(Opcode::Ack, 4), out);
    EXPECT_TRUE(out.sent.empty());
    EXPECT_TRUE(server.idle());
}

TEST_F(FoeServerSession, ConfiguredSm0SizeDecidesTheEndOfFile) {
    // The master's mailbox (SM0) is larger than the reply mailbox: packets of 500 bytes are full ones.
    ServerConfig c = stepped();
    c.bootstrap_data_size = 500;
    FoeServer s(store, c);
    s.set_state(od::AlState::Boot);
    const auto image = image_v(0x01300000, 1200 - kImageHeaderSize);
    s.handle(request(Opcode::Write, 0, "MAXPOS"), out);
    ASSERT_TRUE(is_ack(out.take(), 0));
    s.handle(data(1, {image.data(), 500}), out);
    ASSERT_TRUE(is_ack(out.take(), 1));
    s.handle(data(2, {image.data() + 500, 500}), out);
    ASSERT_TRUE(is_ack(out.take(), 2));
    s.handle(data(3, {image.data() + 1000, 200}), out);
    ASSERT_TRUE(is_busy(out.take()));
    od::DeviceDescription d;
    EXPECT_EQ(ServerConfig::from(d).bootstrap_data_size, 1024u - 12u);
    EXPECT_EQ(ServerConfig::from(d).standard_data_size, 128u - 12u);
    EXPECT_EQ(ServerConfig::from(d).device_name, "MAXPOS");
}

TEST_F(FoeServerSession, UnexpectedPacketsAreIllegal) {
    Bytes r = exchange(Bytes{0x09, 0, 0, 0, 0, 0});
    EXPECT_EQ(error_code(r), 0x8004u);
    EXPECT_EQ(error_string(r).rfind("Illegal", 0), 0u);
    EXPECT_EQ(error_code(exchange(Bytes{0x02, 0})), 0x8004u);
    EXPECT_EQ(error_code(exchange(request(Opcode::Ack, 1))), 0x8004u);
    EXPECT_EQ(error_code(exchange(request(Opcode::Data, 1))), 0x8004u);
    EXPECT_EQ(error_code(exchange(request(Opcode::Busy, 0))), 0x8004u);
    // ERR from the master aborts without an answer.
    ASSERT_TRUE(is_ack(exchange(request(Opcode::Write, 0, "MAXPOS")), 0));
    server.handle(request(Opcode::Error, 0x8000), out);
    EXPECT_TRUE(out.sent.empty());
    EXPECT_TRUE(server.idle());
    EXPECT_FALSE(store.writing());
}

TEST_F(FoeServerSession, ErrorTextIsCutToTheMailbox) {
    out.max = 14;
    const Bytes r = exchange(request(Opcode::Write, 0, "../x"));
    EXPECT_EQ(r.size(), 14u);
    EXPECT_EQ(error_code(r), 0x8002u);
    EXPECT_EQ(error_string(r), "Access d");
}

TEST_F(FoeServerSession, RandomPacketsNeverCrash) {
    ASSERT_TRUE(is_ack(download(image_v(0x01200000)), 9));
    uint32_t x = 12345;
    auto next = [&] {
        x = x * 1103515245u + 12345u;
        return x >> 16;
    };
    for (int i = 0; i < 20000; ++i) {
        Bytes m(next() % 40);
        for (auto& b : m)
            b = static_cast<uint8_t>(next());
        if (!m.empty()) m[0] = static_cast<uint8_t>(next() % 8);
        server.handle(m, out);
        EXPECT_LE(out.sent.size(), 1u);
        out.sent.clear();
        if (i % 100 == 0) poll();
    }
    EXPECT_EQ(active_version(), 0x01200000u);
}

TEST_F(FoeServerSession, CommitOnAWorkerThread) {
    ServerConfig c;
    ASSERT_TRUE(c.commit_in_thread);
    c.busy_after_ns = 0;
    FoeServer s(store, c);
    s.set_state(od::AlState::Boot);
    const auto image = image_v(0x01300000, 2'000'000);
    s.handle(request(Opcode::Write, 0, "MAXPOS"), out);
    ASSERT_TRUE(is_ack(out.take(), 0));
    uint32_t packet = 1;
    std::size_t off = 0;
    for (; image.size() - off >= kChunk; off += kChunk, ++packet) {
        s.handle(data(packet, {image.data() + off, kChunk}), out);
        ASSERT_TRUE(is_ack(out.take(), packet));
    }
    const Bytes last = data(packet, {image.data() + off, image.size() - off});
    s.handle(last, out);
    Bytes r = out.take();
    unsigned busy = 0;
    // No poll(): the worker stores on its own; the repeated DATA sees BUSY, then the ACK.
    for (int i = 0; i < 20000 && is_busy(r); ++i, ++busy) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        s.handle(last, out);
        r = out.take();
    }
    EXPECT_TRUE(is_ack(r, packet));
    EXPECT_GE(busy, 1u);
    EXPECT_EQ(active_version(), 0x01300000u);
    EXPECT_EQ(s.stats().writes_completed, 1u);
}

TEST_F(FoeServerSession, NewRequestStopsAWorkerCommit) {
    ASSERT_TRUE(is_ack(download(image_v(0x01200000)), 9));
    ServerConfig c;
    c.busy_after_ns = 0;
    FoeServer s(store, c);
    s.set_state(od::AlState::Boot);
    const auto image = image_v(0x01300000, 1000);
    s.handle(request(Opcode::Write, 0, "MAXPOS"), out);
    ASSERT_TRUE(is_ack(out.take(), 0));
    for (uint32_t p = 1; p <= 8; ++p) {
        s.handle(data(p, {image.data() + (p - 1) * kChunk, kChunk}), out);
        ASSERT_TRUE(is_ack(out.take(), p));
    }
    s.handle(data(9, {image.data() + 8 * kChunk, image.size() - 8 * kChunk}), out);
    ASSERT_TRUE(is_busy(out.take()));
    s.handle(request(Opcode::Read, 0, "MAXPOS"), out);  // joins the worker, then reads
    const Bytes d = out.take();
    ASSERT_EQ(d[0], 3);
    // Whichever image the commit had reached, it is a complete one and it is what is read.
    const uint32_t v = active_version();
    EXPECT_TRUE(v == 0x01200000u || v == 0x01300000u);
    EXPECT_TRUE(std::equal(d.begin() + 6, d.end(), image_v(v).begin()));
    for (const auto& f : std::filesystem::directory_iterator(dir.path))
        EXPECT_NE(f.path().extension(), ".tmp");
}

// Downloads disturbed at random (wrong packet numbers, short packets, bit flips, aborts, new requests,
// state changes, timeouts): one answer per request at most, and whatever happened, the store reopens with
// one of the complete images active.
TEST_F(FoeServerSession, DisturbedDownloadsNeverLeaveAHalfImage) {
    const Bytes v1 = image_v(0x01200000, 600), v2 = image_v(0x01300000, 900);
    ASSERT_TRUE(is_ack(download(v1), 6));
    uint32_t x = 777;
    auto next = [&] {
        x = x * 1103515245u + 12345u;
        return x >> 16;
    };
    for (int round = 0; round < 300; ++round) {
        const Bytes& img = (next() & 1) ? v1 : v2;
        server.handle(request(Opcode::Write, 0, "MAXPOS"), out);
        out.sent.clear();
        uint32_t packet = 1;
        for (std::size_t off = 0; off <= img.size();) {
            std::size_t n = std::min(kChunk, img.size() - off);
            Bytes d = data(packet, {img.data() + off, n});
            switch (next() % 16) {
                case 0:
                    d[2] = static_cast<uint8_t>(d[2] + 1 + next() % 3);  // wrong number
                    break;
                case 1:
                    if (d.size() > 6)
                        d[6 + next() % (d.size() - 6)] ^= static_cast<uint8_t>(1 + next() % 255);
                    break;
                case 2:
                    d.resize(6 + next() % (n + 1));  // cut short
                    break;
                case 3:
                    d = request(Opcode::Error, 0x8000);
                    break;
                case 4:
                    server.on_state_change(od::AlState::Boot, od::AlState::Init);
                    server.on_state_change(od::AlState::Init, od::AlState::Boot);
                    break;
                case 5:
                    poll(11'000'000'000ull);
                    break;
                default:
                    break;
            }
            server.handle(d, out);
            EXPECT_LE(out.sent.size(), 1u);
            const Bytes r = out.take();
            out.sent.clear();
            for (int i = 0; i < 50 && is_busy(r) && !server.idle(); ++i) {
                poll();
                server.handle(d, out);
                out.sent.clear();
            }
            if (!is_ack(r, packet) || n < kChunk) break;
            off += n;
            ++packet;
        }
    }
    EXPECT_GT(server.stats().writes_completed, 5u);  // both outcomes were exercised
    EXPECT_GT(server.stats().errors_sent, 20u);
    server.abort_transfer();
    FirmwareStore again([&] {
        StoreConfig c;
        c.dir = dir.path;
        c.identity = kMaxpos;
        return c;
    }());
    ASSERT_TRUE(again.open());
    ASSERT_TRUE(again.active_image());
    const uint32_t v = again.active_image()->header.version;
    EXPECT_TRUE(v == 0x01200000u || v == 0x01300000u);
    for (const auto& f : std::filesystem::directory_iterator(dir.path))
        EXPECT_NE(f.path().extension(), ".tmp");
}

// The end of every file write goes to the event sink once: stored (error 0) or the FoE error and its text.
struct FoeEvents : ecat::EventSink {
    struct Call {
        std::string name;
        uint64_t bytes;
        uint32_t code;
        std::string text;
    };
    std::vector<Call> calls;
    void foe_write(std::string_view name, uint64_t bytes, uint32_t code, std::string_view text) override {
        calls.push_back({std::string(name), bytes, code, std::string(text)});
    }
};

TEST_F(FoeServerSession, EveryWriteEndIsReportedOnceWithNameSizeAndResult) {
    FoeEvents events;
    server.set_event_sink(&events);
    const auto image = image_v(0x01300000, 3000);
    ASSERT_TRUE(is_ack(download(image), static_cast<uint32_t>(image.size() / kChunk + 1)));
    ASSERT_EQ(events.calls.size(), 1u);
    EXPECT_EQ(events.calls[0].name, "MAXPOS");
    EXPECT_EQ(events.calls[0].bytes, image.size());
    EXPECT_EQ(events.calls[0].code, 0u);

    // A name the device does not take: refused at the request.
    EXPECT_EQ(error_code(exchange(request(Opcode::Write, 0, "other.bin"))), 0x8001u);
    ASSERT_EQ(events.calls.size(), 2u);
    EXPECT_EQ(events.calls[1].name, "other.bin");
    EXPECT_EQ(events.calls[1].code, 0x8001u);
    EXPECT_EQ(events.calls[1].bytes, 0u);

    // Abandoned half-way by leaving Bootstrap.
    ASSERT_TRUE(is_ack(exchange(request(Opcode::Write, 0, "MAXPOS")), 0));
    ASSERT_TRUE(is_ack(exchange(data(1, {image.data(), kChunk})), 1));
    server.on_state_change(od::AlState::Boot, od::AlState::Init);
    ASSERT_EQ(events.calls.size(), 3u);
    EXPECT_EQ(events.calls[2].bytes, kChunk);
    EXPECT_NE(events.calls[2].code, 0u);
    EXPECT_NE(events.calls[2].text.find("Bootstrap"), std::string::npos);

    // Reads are not writes: nothing reported.
    server.on_state_change(od::AlState::Init, od::AlState::PreOp);
    EXPECT_EQ(upload("MAXPOS"), image);
    EXPECT_EQ(events.calls.size(), 3u);
}

// ---- Deliberate faults (foe/faults.hpp, `ecat-slave --fault`) ----------------------------------------

// The two faults mirror each other: each takes the write it is about and still refuses the other one.
TEST_F(FoeServerSession, FaultPasswordIgnoredAcceptsAWrongPassword) {
    expect_fault_takes(&FoeFaults::password_ignored, request(Opcode::Write, 0x1234, "MAXPOS"), 0x800Au,
                       request(Opcode::Write, 0, "NOSUCHFILE"), 0x8001u);
}

TEST_F(FoeServerSession, FaultAnyFileNameAcceptsAnUnknownFile) {
    expect_fault_takes(&FoeFaults::any_file_name, request(Opcode::Write, 0, "NOSUCHFILE"), 0x8001u,
                       request(Opcode::Write, 0x1234, "MAXPOS"), 0x800Au);
}

namespace {

// The default (ServerConfig::busy_after_ns): the final DATA is answered once the image is stored, ACK only
// when it is active; poll() sends that one answer. A master without BUSY (libethercat) sees only ACK.
struct AnswerWhenStored : Fixture {
    ServerConfig c = [] {
        ServerConfig k;
        k.commit_in_thread = false;
        return k;
    }();
    FoeServer s{store, c};
    void SetUp() override {
        Fixture::SetUp();
        s.on_state_change(od::AlState::Init, od::AlState::Boot);
    }
    // Sends everything but the final DATA; returns it.
    Bytes send_all_but_last(const Bytes& image, uint32_t& packet) {
        s.handle(request(Opcode::Write, 0, "MAXPOS"), out);
        EXPECT_TRUE(is_ack(out.take(), 0));
        packet = 1;
        std::size_t off = 0;
        for (; image.size() - off >= kChunk; off += kChunk, ++packet) {
            s.handle(data(packet, {image.data() + off, kChunk}), out);
            EXPECT_TRUE(is_ack(out.take(), packet));
        }
        return data(packet, {image.data() + off, image.size() - off});
    }
};

TEST_F(AnswerWhenStored, FinalDataIsAcknowledgedOnlyOnceTheImageIsActive) {
    ASSERT_GT(c.busy_after_ns, 0u);
    uint32_t packet = 0;
    const Bytes last = send_all_but_last(image_v(0x01400000, 3000), packet);
    s.handle(last, out);
    EXPECT_TRUE(out.sent.empty()) << "no answer before the image is stored";
    Bytes r;
    int polls = 0;  // each poll() runs one commit step: the answer waits for the last one
    for (; polls < 1000 && out.sent.empty(); ++polls) {
        now += 1'000'000;
        s.poll(now, out);
    }
    EXPECT_GT(polls, 1);
    ASSERT_EQ(out.sent.size(), 1u);
    r = out.take();
    EXPECT_TRUE(is_ack(r, packet));
    EXPECT_EQ(active_version(), 0x01400000u);
    EXPECT_EQ(s.stats().busy_sent, 0u);
    EXPECT_TRUE(s.idle());
    now += 1'000'000;
    s.poll(now, out);
    EXPECT_TRUE(out.sent.empty()) << "one answer only";
}

TEST_F(AnswerWhenStored, ABadImageIsRefusedNotAcknowledged) {
    auto image = image_v(0x01400000, 3000);
    image[image.size() / 2] ^= 0x5A;  // the payload no longer matches its CRC
    uint32_t packet = 0;
    const Bytes last = send_all_but_last(image, packet);
    s.handle(last, out);
    for (int i = 0; i < 1000 && out.sent.empty(); ++i) {
        now += 1'000'000;
        s.poll(now, out);
    }
    ASSERT_EQ(out.sent.size(), 1u);
    const Bytes r = out.take();
    ASSERT_FALSE(r.empty());
    EXPECT_EQ(r[0], 5);  // ERR
    EXPECT_NE(active_version(), 0x01400000u);
}

// A commit still running at busy_after_ns is answered BUSY; the master repeats the DATA and gets the ACK.
TEST_F(AnswerWhenStored, BusyOnlyAfterTheBound) {
    uint32_t packet = 0;
    const Bytes last = send_all_but_last(image_v(0x01400000, 500'000), packet);
    s.handle(last, out);
    EXPECT_TRUE(out.sent.empty());
    now += c.busy_after_ns;  // the first poll() comes after the bound: one commit step, then BUSY
    s.poll(now, out);
    ASSERT_EQ(out.sent.size(), 1u);
    Bytes r = out.take();
    if (!is_ack(r, packet)) {
        EXPECT_TRUE(is_busy(r));
        for (int i = 0; i < 1000 && is_busy(r); ++i) {
            now += 1'000'000;
            s.poll(now, out);
            EXPECT_TRUE(out.sent.empty()) << "after BUSY the answer waits for the repeated DATA";
            s.handle(last, out);
            r = out.take();
        }
    }
    EXPECT_TRUE(is_ack(r, packet));
    EXPECT_EQ(active_version(), 0x01400000u);
}

}  // namespace
