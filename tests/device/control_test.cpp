// The soft drive's control socket: command parsing and the datagram socket itself.
#include <gtest/gtest.h>

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>

#include "device/control.hpp"
#include "device/device.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"

namespace {

struct Rig {
    std::filesystem::path dir;
    esc::ManualClock clock;
    std::unique_ptr<esc::Esc> esc;
    std::unique_ptr<device::Device> dev;
    Rig() {
        char pattern[] = "/tmp/softdrive-ctl-XXXXXX";
        dir = ::mkdtemp(pattern);
        clock.set(1'000'000'000);
        esc = std::make_unique<esc::Esc>(esc::EscConfig{}, clock);
        device::DeviceOptions o;
        o.state_dir = dir;
        dev = std::make_unique<device::Device>(*esc, o);
        dev->poll(clock.now_ns());
    }
    ~Rig() {
        dev.reset();
        std::error_code ec;
        std::filesystem::remove_all(dir, ec);
    }
    void run(int ms) {
        for (int i = 0; i < ms; ++i) {
            clock.advance(1'000'000);
            esc->tick();
            dev->poll(clock.now_ns());
        }
    }
};

using device::ControlSocket;

}  // namespace

TEST(ControlCommands, InputsAndSwitches) {
    Rig r;
    EXPECT_EQ(ControlSocket::apply(*r.dev, "input 4 on"), "ok input 4 on");
    EXPECT_EQ(ControlSocket::apply(*r.dev, "  input 4 off  # comment"), "ok input 4 off");
    EXPECT_EQ(ControlSocket::apply(*r.dev, "input 4 on"), "ok input 4 on");
    r.run(20);
    EXPECT_NE(r.dev->dictionary().get<uint16_t>(0x3141, 1) & 0x0008, 0);
    EXPECT_EQ(ControlSocket::apply(*r.dev, "limit-pos 5000"), "ok limit-pos");
    EXPECT_EQ(r.dev->environment().positive_limit, 5000);
    EXPECT_EQ(ControlSocket::apply(*r.dev, "limit-pos none"), "ok limit-pos");
    EXPECT_TRUE(std::isnan(r.dev->environment().positive_limit));
    EXPECT_EQ(ControlSocket::apply(*r.dev, "home -10 10"), "ok home");
    EXPECT_EQ(r.dev->environment().home_from, -10);
    EXPECT_EQ(r.dev->environment().home_to, 10);
    EXPECT_EQ(ControlSocket::apply(*r.dev, "stops -100000 100000"), "ok stops");
    EXPECT_EQ(ControlSocket::apply(*r.dev, "sto off"), "ok sto off");
    EXPECT_EQ(ControlSocket::apply(*r.dev, ""), "");
    EXPECT_EQ(ControlSocket::apply(*r.dev, "# only a comment"), "");
    EXPECT_EQ(ControlSocket::apply(*r.dev, "status").rfind("ok state INIT statusword 0x", 0), 0u)
        << ControlSocket::apply(*r.dev, "status");
}

TEST(ControlCommands, BadLinesAreRefusedWithoutEffect) {
    Rig r;
    for (const char* bad :
         {"input", "input 0 on", "input 7 on", "input 4 maybe", "input 4.5 on", "input x on",
          "input 4 on extra", "limit-neg", "limit-neg abc", "limit-neg 1e999", "home 10 -10", "home 1",
          "stops nan 5", "frobnicate", "status now", "sto", "sto 2"}) {
        const std::string answer = ControlSocket::apply(*r.dev, bad);
        EXPECT_EQ(answer.rfind("error: ", 0), 0u) << bad << " -> " << answer;
    }
    EXPECT_TRUE(std::isnan(r.dev->environment().negative_limit));
    EXPECT_TRUE(std::isnan(r.dev->environment().home_from));
    EXPECT_TRUE(std::isnan(r.dev->environment().stop_lo));
}

TEST(ControlSocket, DatagramsAreAppliedAndAnswered) {
    Rig r;
    const auto path = r.dir / "control.sock";
    ControlSocket ctl(path);
    ASSERT_GE(ctl.fd(), 0);
    // A client with an address of its own gets the answers.
    const int c = ::socket(AF_UNIX, SOCK_DGRAM, 0);
    ASSERT_GE(c, 0);
    sockaddr_un me{};
    me.sun_family = AF_UNIX;
    const std::string mine = (r.dir / "client.sock").string();
    std::strcpy(me.sun_path, mine.c_str());
    ASSERT_EQ(::bind(c, reinterpret_cast<sockaddr*>(&me), sizeof me), 0);
    sockaddr_un to{};
    to.sun_family = AF_UNIX;
    std::strcpy(to.sun_path, path.c_str());
    const std::string msg = "input 4 on\nlimit-neg -500\nbogus\n";
    ASSERT_EQ(::sendto(c, msg.data(), msg.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof to),
              static_cast<ssize_t>(msg.size()));
    ctl.service(*r.dev, r.clock.now_ns());
    char buf[512] = {};
    const ssize_t n = ::recv(c, buf, sizeof buf - 1, MSG_DONTWAIT);
    ASSERT_GT(n, 0);
    const std::string answer(buf, static_cast<std::size_t>(n));
    EXPECT_NE(answer.find("ok input 4 on\n"), std::string::npos) << answer;
    EXPECT_NE(answer.find("ok limit-neg\n"), std::string::npos) << answer;
    EXPECT_NE(answer.find("error: unknown command 'bogus'"), std::string::npos) << answer;
    EXPECT_EQ(r.dev->environment().negative_limit, -500);
    // Nothing waiting: service() returns at once.
    ctl.service(*r.dev, r.clock.now_ns());
    ::close(c);
}

TEST(ControlSocket, ReplacesAStaleSocketAndRemovesItsFile) {
    Rig r;
    const auto path = r.dir / "control.sock";
    { ControlSocket first(path); }
    EXPECT_FALSE(std::filesystem::exists(path));
    {
        ControlSocket a(path);
        // A crashed slave leaves the file behind: a new one replaces it.
        ::unlink(path.c_str());
        ControlSocket b(path);
        EXPECT_TRUE(std::filesystem::exists(path));
    }
    EXPECT_THROW(ControlSocket(r.dir / std::string(200, 'x')), std::runtime_error);
}

TEST(ControlCommands, RandomLinesNeverBreakTheDevice) {
    Rig r;
    uint32_t x = 12345;
    auto next = [&x] {
        x ^= x << 13, x ^= x >> 17, x ^= x << 5;
        return x;
    };
    const char* words[] = {"input", "sto",  "limit-neg", "limit-pos", "home", "stops", "status",
                           "on",    "off",  "none",      "1",         "-1",   "1e308", "nan",
                           "inf",   "0x10", "6",         "7",         "\t",   " "};
    for (int i = 0; i < 5000; ++i) {
        std::string line;
        const int n = static_cast<int>(next() % 5);
        for (int k = 0; k < n; ++k) {
            if (next() % 4 == 0) {
                line.push_back(static_cast<char>(next() & 0xFF));
            } else {
                line += words[next() % std::size(words)];
                line.push_back(' ');
            }
        }
        const std::string answer = ControlSocket::apply(*r.dev, line);
        EXPECT_TRUE(answer.empty() || answer.rfind("ok", 0) == 0 || answer.rfind("error: ", 0) == 0)
            << line << " -> " << answer;
        if (i % 100 == 0) r.run(1);
    }
    const auto& env = r.dev->environment();
    for (double v :
         {env.negative_limit, env.positive_limit, env.home_from, env.home_to, env.stop_lo, env.stop_hi})
        EXPECT_TRUE(std::isnan(v) || std::isfinite(v));
}
