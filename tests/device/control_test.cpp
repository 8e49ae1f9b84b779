// The soft drive's control socket: command parsing and the datagram socket itself.
#include <gtest/gtest.h>

#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
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

// Issue 24, finding 4: numbers are parsed into their type with range checks, never cast first.
TEST(ControlCommands, NumbersAreCheckedBeforeAnyConversion) {
    Rig r;
    for (const char* bad :
         {"input 1e300 on", "input -1e300 on", "input 4.0 on", "input 0x4 on extra",
          "input 99999999999999999999 on", "limit-pos 1e400", "home -inf 5", "stops 1 nan"}) {
        const std::string answer = ControlSocket::apply(*r.dev, bad);
        EXPECT_EQ(answer.rfind("error: ", 0), 0u) << bad << " -> " << answer;
    }
    EXPECT_EQ(ControlSocket::apply(*r.dev, "input 0x4 on"), "ok input 4 on");  // the one lexer: hex too
    EXPECT_EQ(ControlSocket::apply(*r.dev, "input \"4\" off # quoted"), "ok input 4 off");
    EXPECT_EQ(ControlSocket::apply(*r.dev, "input \"4 on").rfind("error: unterminated string", 0), 0u);
}

// An answer is one line per command whatever the text in it: a name typed with the lexer's escapes (a line
// feed, a tab, a quote) comes back escaped, not as a second, forged answer line (found by issue 24's campaign
// run again: an ESI entry name "ud&#10;ok injected" answered "ok 0x6000:08 \"ud" and a line "ok injected").
TEST(ControlCommands, AnAnswerIsOneLineWhateverTheNamesInIt) {
    Rig r;
    for (const char* line :
         {"get \"a\\nok forged\"", "set \"x\\ty\\\"z\" 1", "\"bo\\ngus\"", "get \"\\\\\""}) {
        const std::string answer = ControlSocket::apply(*r.dev, line);
        EXPECT_EQ(answer.rfind("error: ", 0), 0u) << line << " -> " << answer;
        EXPECT_EQ(answer.find_first_of("\n\t"), std::string::npos) << line << " -> " << answer;
    }
    EXPECT_EQ(ControlSocket::apply(*r.dev, "get \"a\\nok forged\""), "error: no entry named 'a\\nok forged'");
}

namespace {

// A client socket bound to its own address (it gets the answers).
struct Client {
    int fd = -1;
    sockaddr_un to{};
    Client(const std::filesystem::path& dir, const std::filesystem::path& server,
           const char* name = "client.sock") {
        fd = ::socket(AF_UNIX, SOCK_DGRAM, 0);
        sockaddr_un me{};
        me.sun_family = AF_UNIX;
        std::strcpy(me.sun_path, (dir / name).c_str());
        if (::bind(fd, reinterpret_cast<sockaddr*>(&me), sizeof me) != 0) throw std::runtime_error("bind");
        to.sun_family = AF_UNIX;
        std::strcpy(to.sun_path, server.c_str());
    }
    ~Client() { ::close(fd); }
    bool send(const std::string& msg) const {
        return ::sendto(fd, msg.data(), msg.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to) ==
               static_cast<ssize_t>(msg.size());
    }
    std::string receive() const {
        std::string buf(65536, '\0');
        const ssize_t n = ::recv(fd, buf.data(), buf.size(), MSG_DONTWAIT);
        return n > 0 ? buf.substr(0, static_cast<std::size_t>(n)) : std::string{};
    }
};

bool readable(int fd) {
    pollfd p{fd, POLLIN, 0};
    return ::poll(&p, 1, 0) > 0;
}

}  // namespace

// Issue 24, finding 1: 4096 bytes of padding followed by a command was cut at 4096 bytes and the cut
// text executed. A datagram that does not fit is refused whole, with an error answer.
TEST(ControlSocket, ADatagramLongerThanTheBufferIsRefusedWhole) {
    Rig r;
    const auto path = r.dir / "control.sock";
    ControlSocket ctl(path);
    Client c(r.dir, path);
    // The padding is blanks: cut anywhere, the rest would be a valid command.
    ASSERT_TRUE(c.send(std::string(ControlSocket::kMaxDatagram, ' ') + "limit-neg -500\n"));
    const std::string fits = "limit-pos 500\n";
    ASSERT_TRUE(c.send(std::string(ControlSocket::kMaxDatagram - fits.size(), ' ') + fits));  // fits exactly
    ctl.service(*r.dev, r.clock.now_ns());
    const std::string first = c.receive();
    EXPECT_EQ(first.rfind("error: datagram longer than 4096 bytes: refused whole", 0), 0u) << first;
    EXPECT_TRUE(std::isnan(r.dev->environment().negative_limit));  // nothing of it executed
    ctl.service(*r.dev, r.clock.now_ns());
    EXPECT_EQ(c.receive(), "ok limit-pos\n");
    EXPECT_EQ(r.dev->environment().positive_limit, 500);
}

// Issue 24, finding 2: the control work of one call is bounded in time; what is left waits, and the
// descriptor the runtime watches stays readable until it is done.
TEST(ControlSocket, WorkPerCallIsBoundedAndTheRestWaits) {
    Rig r;
    const auto path = r.dir / "control.sock";
    ControlSocket ctl(path);
    Client c(r.dir, path);
    std::string many;
    for (int i = 0; i < 200; ++i)
        many += "status\n";
    ASSERT_TRUE(c.send(many));
    ASSERT_TRUE(c.send("input 4 on\n"));
    int lines = 0, calls = 0;
    const auto count = [&](std::string_view line) {
        ++lines;
        return ControlSocket::apply(*r.dev, line);
    };
    ASSERT_TRUE(readable(ctl.fd()));
    ctl.service(count, 0);  // no time at all: one line
    ++calls;
    EXPECT_EQ(lines, 1);
    EXPECT_TRUE(ctl.busy());
    EXPECT_TRUE(readable(ctl.fd()));  // the rest of the datagram: the runtime comes back
    EXPECT_EQ(c.receive(), "");       // nothing answered before the whole datagram is done
    while (readable(ctl.fd()) && calls < 1000) {
        ctl.service(count, 0);
        ++calls;
    }
    EXPECT_EQ(lines, 201);
    EXPECT_FALSE(readable(ctl.fd()));
    EXPECT_FALSE(ctl.busy());
    const std::string answer = c.receive();
    EXPECT_EQ(std::count(answer.begin(), answer.end(), '\n'), 200) << answer.substr(0, 200);
    EXPECT_EQ(c.receive(), "ok input 4 on\n");
}

// Issue 24, finding 3: the socket's mode did not depend on the umask, any path was unlinked, and the path
// was deleted at exit whatever it then was.
TEST(ControlSocket, IsTheOwnersOnlyWhateverTheUmask) {
    Rig r;
    const auto path = r.dir / "control.sock";
    const mode_t old = ::umask(0);
    {
        ControlSocket ctl(path);
        struct stat st {};
        ASSERT_EQ(::lstat(path.c_str(), &st), 0);
        EXPECT_EQ(st.st_mode & 0777, 0600u);
    }
    {
        ControlSocket ctl(path, ::getegid());
        struct stat st {};
        ASSERT_EQ(::lstat(path.c_str(), &st), 0);
        EXPECT_EQ(st.st_mode & 0777, 0660u);
        EXPECT_EQ(st.st_gid, ::getegid());
    }
    ::umask(old);
}

TEST(ControlSocket, NeverReplacesOrRemovesWhatItDidNotCreate) {
    Rig r;
    const auto path = r.dir / "control.sock";
    // A live socket of another program: refused, left alone.
    {
        const int other = ::socket(AF_UNIX, SOCK_DGRAM, 0);
        sockaddr_un a{};
        a.sun_family = AF_UNIX;
        std::strcpy(a.sun_path, path.c_str());
        ASSERT_EQ(::bind(other, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
        EXPECT_THROW(ControlSocket{path}, std::runtime_error);
        EXPECT_TRUE(std::filesystem::is_socket(path));
        ::close(other);  // now stale: replaced
        ControlSocket ctl(path);
        EXPECT_TRUE(std::filesystem::is_socket(path));
        // Another control socket on the same path (of this process) is refused too.
        EXPECT_THROW(ControlSocket{path}, std::runtime_error);
    }
    EXPECT_FALSE(std::filesystem::exists(path));
    // A regular file: refused, left alone.
    std::ofstream(path) << "data";
    EXPECT_THROW(ControlSocket{path}, std::runtime_error);
    EXPECT_TRUE(std::filesystem::is_regular_file(path));
    std::filesystem::remove(path);
    // Replaced while it runs: what is at the path at the end is not removed.
    {
        ControlSocket ctl(path);
        ::unlink(path.c_str());
        std::ofstream(path) << "someone else's";
    }
    EXPECT_TRUE(std::filesystem::is_regular_file(path));
}

TEST(ControlSocket, ASenderOfAnotherUserIsRefused) {
    Rig r;
    const auto path = r.dir / "control.sock";
    ControlSocket ctl(path);
    EXPECT_EQ(ctl.refuse(::geteuid(), ::getegid()), "");
    EXPECT_EQ(ctl.refuse(0, 0), "");
    EXPECT_NE(ctl.refuse(::geteuid() + 4242, 4242), "");
    ControlSocket grouped(r.dir / "grouped.sock", 4242);
    EXPECT_EQ(grouped.refuse(::geteuid() + 4242, 4242), "");  // a member of the control group
    if (::geteuid() != 0) GTEST_SKIP() << "sending as another user needs root";
    // Over the socket: a child that became nobody sends; the mode stops it first, so open the mode.
    ASSERT_EQ(::chmod(path.c_str(), 0666), 0);
    ASSERT_EQ(::chmod(r.dir.c_str(), 0755), 0);
    const pid_t child = ::fork();
    if (child == 0) {
        if (::setgid(65534) != 0 || ::setuid(65534) != 0) ::_exit(3);
        const int fd = ::socket(AF_UNIX, SOCK_DGRAM, 0);
        sockaddr_un to{};
        to.sun_family = AF_UNIX;
        std::strcpy(to.sun_path, path.c_str());
        const std::string msg = "input 4 on\n";
        ::_exit(::sendto(fd, msg.data(), msg.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof to) ==
                        static_cast<ssize_t>(msg.size())
                    ? 0
                    : 4);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status));
    ASSERT_EQ(WEXITSTATUS(status), 0);
    int lines = 0;
    ctl.service(
        [&](std::string_view) {
            ++lines;
            return std::string("ok");
        },
        ControlSocket::kBudgetNs);
    EXPECT_EQ(lines, 0);  // received and refused: nothing applied
}
