// The ecat-slave program: options, exit codes, and (as root) the veth pair it creates, serves and removes.
// The root test runs ecat-slave in a network namespace of its own (the child unshares before exec), so it
// never collides with interfaces on the host and everything vanishes with the process.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "device/faults.hpp"
#include "esc/link_packet.hpp"
#include "esc/wire/frame_builder.hpp"
#include "netns_util.hpp"
#include "pcap_records.hpp"
#include "slave/netif.hpp"

namespace {

struct Proc {
    pid_t pid = -1;
    int out = -1;  // stdout + stderr of the child
};

// A state directory of this test process for every privileged run, so no run writes the default
// /var/lib/softecat of the machine; removed when the test binary exits.
const std::string& state_dir() {
    struct Dir {
        std::string path;
        Dir() {
            char tmpl[] = "/tmp/ecat-slave-cli-XXXXXX";
            if (::mkdtemp(tmpl) != nullptr) path = tmpl;
        }
        ~Dir() {
            std::error_code ec;
            if (!path.empty()) std::filesystem::remove_all(path, ec);
        }
    };
    static Dir dir;
    return dir.path;
}

// Starts ecat-slave with args; with own_netns the child first enters a new network namespace and, with
// stale_pair, creates ecat0/ecat1 there as a killed earlier run would have left them.
// With unprivileged, the child drops to uid/gid 65534 (nobody) before exec, losing every capability.
Proc start(const std::vector<std::string>& args, bool own_netns = false, bool stale_pair = false,
           bool unprivileged = false) {
    std::string state_option = "--state-dir=" + state_dir();  // before fork: the parent owns the directory
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) return {};
    const pid_t parent = ::getpid();
    const pid_t pid = ::fork();
    if (pid == 0) {
        ::prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (::getppid() != parent) ::_exit(126);
        ::dup2(fds[1], 1);
        ::dup2(fds[1], 2);
        if (own_netns && ::unshare(CLONE_NEWNET) != 0) ::_exit(125);
        if (stale_pair) {
            try {
                slave::create_veth("ecat0", "ecat1");
            } catch (...) {
                ::_exit(124);
            }
        }
        if (unprivileged && (::setresgid(65534, 65534, 65534) != 0 || ::setresuid(65534, 65534, 65534) != 0))
            ::_exit(123);
        std::vector<char*> argv{const_cast<char*>(ECAT_SLAVE_PATH)};
        for (const auto& a : args)
            argv.push_back(const_cast<char*>(a.c_str()));
        if (!unprivileged && !state_dir().empty()) argv.push_back(state_option.data());
        argv.push_back(nullptr);
        ::execv(argv[0], argv.data());
        ::_exit(127);
    }
    ::close(fds[1]);
    return {pid, fds[0]};
}

// Reads the child's output until `needle` appears or the timeout passes.
std::string read_until(int fd, const std::string& needle, int timeout_ms) {
    std::string out;
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (out.find(needle) == std::string::npos && std::chrono::steady_clock::now() < end) {
        pollfd p{fd, POLLIN, 0};
        if (::poll(&p, 1, 50) <= 0) continue;
        char buf[512];
        const ssize_t n = ::read(fd, buf, sizeof buf);
        if (n <= 0) break;
        out.append(buf, static_cast<std::size_t>(n));
    }
    return out;
}

int wait_exit(pid_t pid, int timeout_ms) {
    for (int i = 0; i < timeout_ms / 10; ++i) {
        int status = 0;
        if (::waitpid(pid, &status, WNOHANG) == pid)
            return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ::kill(pid, SIGKILL);
    ::waitpid(pid, nullptr, 0);
    return -1;
}

struct RunResult {
    int code;
    std::string output;
};

RunResult run(const std::vector<std::string>& args, bool unprivileged = false) {
    Proc p = start(args, false, false, unprivileged);
    std::string out = read_until(p.out, "\x01never", 3000);
    const int code = wait_exit(p.pid, 3000);
    ::close(p.out);
    return {code, out};
}

TEST(EcatSlaveCli, VersionPrintsTheProjectVersion) {
    const RunResult r = run({"--version"});
    EXPECT_EQ(r.code, 0);
    EXPECT_NE(r.output.find("ecat-slave"), std::string::npos) << r.output;
}

TEST(EcatSlaveCli, MissingInterfaceExitsWith2AndSaysWhich) {
    const RunResult r = run({"--iface", "nosuchif0"});
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.output.find("nosuchif0"), std::string::npos) << r.output;
}

TEST(EcatSlaveCli, BadOptionsExitWith2) {
    EXPECT_EQ(run({"--backend", "dpdk", "--iface", "lo"}).code, 2);
    EXPECT_EQ(run({"--ram-kib", "0", "--iface", "lo"}).code, 2);
    EXPECT_EQ(run({"--no-such-option"}).code, 2);
    EXPECT_EQ(run({"--cpu", "100000", "--iface", "lo"}).code, 2);
    EXPECT_EQ(run({"--rt-priority", "100", "--iface", "lo"}).code, 2);
    EXPECT_EQ(run({"--eeprom", "/nonexistent/eeprom.bin", "--iface", "lo"}).code, 2);
    EXPECT_EQ(run({"--spin-us", "50", "--busy-poll", "--iface", "lo"}).code, 2);  // one way of waiting
    EXPECT_EQ(run({"--spin-us", "0", "--iface", "lo"}).code, 2);
}

TEST(EcatSlaveCli, FaultListPrintsEveryFaultWithItsDescriptionAndExits0) {
    const RunResult r = run({"--fault", "list"});
    EXPECT_EQ(r.code, 0) << r.output;
    std::size_t lines = 0;
    for (char c : r.output)
        lines += c == '\n';
    EXPECT_EQ(lines, device::kFaultCount) << r.output;
    for (const device::FaultInfo& f : device::fault_catalogue()) {
        const std::size_t at = r.output.find(std::string(f.name) + " ");
        ASSERT_NE(at, std::string::npos) << f.name << "\n" << r.output;
        const std::size_t eol = r.output.find('\n', at);
        EXPECT_NE(r.output.substr(at, eol - at).find(f.description), std::string::npos) << f.name;
    }
    EXPECT_GE(device::kFaultCount, 22u);
}

TEST(EcatSlaveCli, UnknownFaultIsAUsageError) {
    RunResult r = run({"--fault", "no-such-fault", "--iface", "lo"});
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.output.find("no-such-fault"), std::string::npos) << r.output;
    r = run({"--fault", "wkc-aprd,bogus", "--iface", "lo"});  // one bad name in a list
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.output.find("'bogus'"), std::string::npos) << r.output;
    r = run({"--fault", "wkc-aprd", "--fault", "", "--iface", "lo"});
    EXPECT_EQ(r.code, 2) << r.output;
}

TEST(EcatSlaveCli, MissingPrivilegesExitWith2AndNameTheCapability) {
    if (!linktest::is_root()) GTEST_SKIP() << "needs root to drop to an unprivileged user";
    if (::access(ECAT_SLAVE_PATH, X_OK) != 0) GTEST_SKIP() << "binary not reachable";
    for (const char* backend : {"pcap", "packet"}) {
        const RunResult r = run({"--iface", "lo", "--backend", backend}, /*unprivileged=*/true);
        if (r.code == 127) GTEST_SKIP() << "the build directory is not accessible to user nobody";
        EXPECT_EQ(r.code, 2) << backend << ": " << r.output;
        EXPECT_NE(r.output.find("CAP_NET_RAW"), std::string::npos) << backend << ": " << r.output;
    }
    const RunResult r = run({"--veth-name", "nopriv0"}, /*unprivileged=*/true);
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("CAP_NET_ADMIN"), std::string::npos) << r.output;
    EXPECT_FALSE(slave::interface_exists("nopriv0"));
}

// Joins the network namespace of pid on a helper thread, runs fn there.
template <typename F>
void in_netns_of(pid_t pid, F&& fn) {
    std::exception_ptr error;
    std::thread t([&] {
        try {
            const std::string path = "/proc/" + std::to_string(pid) + "/ns/net";
            const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
            if (fd < 0 || ::setns(fd, CLONE_NEWNET) != 0) throw std::runtime_error("setns " + path);
            ::close(fd);
            fn();
        } catch (...) {
            error = std::current_exception();
        }
    });
    t.join();
    if (error) std::rethrow_exception(error);
}

// Sends a BRD of the ESC type register from ecat1 in the namespace of `pid` and expects the slave's answer:
// working counter 1 and the source MAC bit set (first source byte 0x03; 0x01 with --fault
// source-mac-unchanged).
void expect_brd_answer(pid_t pid, uint8_t source_byte = 0x03) {
    std::unique_ptr<esc::PacketLink> master;
    in_netns_of(pid, [&] { master = std::make_unique<esc::PacketLink>("ecat1"); });
    // BRD of the ESC type register: the slave answers with WKC 1 and the source MAC bit set.
    const auto f = esc::wire::FrameBuilder().add_zero(esc::Command::BRD, 0, 0, 0x0000, 1).build();
    ASSERT_TRUE(master->send(f));
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    std::size_t n = 0;
    for (int i = 0; i < 100 && n == 0; ++i) {
        pollfd pf{master->fd(), POLLIN, 0};
        ::poll(&pf, 1, 20);
        n = master->receive(buf);
    }
    ASSERT_EQ(n, 60u);
    EXPECT_EQ(buf[6], source_byte);
    EXPECT_EQ(buf[27], 1) << "working counter";
}

TEST(EcatSlaveVeth, CreatesThePairAnswersOnItAndRemovesItOnSigterm) {
    if (!linktest::is_root()) GTEST_SKIP() << "needs root (CAP_NET_ADMIN, CAP_NET_RAW)";
    const std::string capture = "/tmp/ecat-slave-test-" + std::to_string(::getpid()) + ".pcap";
    Proc p = start({"--capture", capture, "--verbose"}, /*own_netns=*/true, /*stale_pair=*/true);
    ASSERT_GT(p.pid, 0);
    const std::string out = read_until(p.out, "running on", 5000);
    ASSERT_NE(out.find("master interface: ecat1"), std::string::npos) << out;

    expect_brd_answer(p.pid);

    bool exists_before = false, exists_after = true;
    in_netns_of(p.pid, [&] { exists_before = slave::interface_exists("ecat0"); });
    // Keep a handle on the namespace so it outlives the slave and we can look inside afterwards.
    const int ns = ::open(("/proc/" + std::to_string(p.pid) + "/ns/net").c_str(), O_RDONLY | O_CLOEXEC);
    ASSERT_GE(ns, 0);
    ::kill(p.pid, SIGTERM);
    EXPECT_EQ(wait_exit(p.pid, 5000), 0);
    std::thread t([&] {
        if (::setns(ns, CLONE_NEWNET) == 0)
            exists_after = slave::interface_exists("ecat0") || slave::interface_exists("ecat1");
    });
    t.join();
    ::close(ns);
    ::close(p.out);
    EXPECT_TRUE(exists_before);
    EXPECT_FALSE(exists_after) << "the veth pair must be gone after SIGTERM";

    // The capture holds the frame as received and the reply.
    const auto cap = linktest::read_pcap(capture);
    ASSERT_TRUE(cap.opened) << cap.error;
    ASSERT_GE(cap.records.size(), 2u);
    EXPECT_EQ(cap.records[0].size(), 60u);
    EXPECT_EQ(cap.records[0][6], 0x01);
    EXPECT_EQ(cap.records[1][6], 0x03);
    EXPECT_EQ(cap.records[1][27], 1);
    std::remove(capture.c_str());
}

// A fault given on the command line reaches the ESC: the slave answers, but with the source MAC unchanged.
TEST(EcatSlaveVeth, FaultFromTheCommandLineReachesTheEsc) {
    if (!linktest::is_root()) GTEST_SKIP() << "needs root (CAP_NET_ADMIN, CAP_NET_RAW)";
    Proc p = start({"--fault", "source-mac-unchanged"}, /*own_netns=*/true);
    ASSERT_GT(p.pid, 0);
    const std::string out = read_until(p.out, "running on", 5000);
    ASSERT_NE(out.find("master interface: ecat1"), std::string::npos) << out;
    EXPECT_NE(out.find("deliberate faults (testing aid): source-mac-unchanged"), std::string::npos) << out;
    expect_brd_answer(p.pid, 0x01);
    ::kill(p.pid, SIGTERM);
    EXPECT_EQ(wait_exit(p.pid, 5000), 0);
    ::close(p.out);
}

// The ways of waiting (--spin-us, --busy-poll) answer frames on a real veth pair like the default and end on
// SIGTERM, the busy loop included.
TEST(EcatSlaveVeth, SpinAndBusyPollAnswerAndStopOnSigterm) {
    if (!linktest::is_root()) GTEST_SKIP() << "needs root (CAP_NET_ADMIN, CAP_NET_RAW)";
    for (const std::vector<std::string>& waiting :
         {std::vector<std::string>{"--spin-us", "200"}, std::vector<std::string>{"--busy-poll"}}) {
        std::vector<std::string> args = waiting;
        args.push_back("--verbose");
        Proc p = start(args, /*own_netns=*/true, /*stale_pair=*/false);
        ASSERT_GT(p.pid, 0);
        const std::string out = read_until(p.out, "running on", 5000);
        ASSERT_NE(out.find("running on"), std::string::npos) << waiting[0] << ": " << out;
        expect_brd_answer(p.pid);
        ::kill(p.pid, SIGTERM);
        EXPECT_EQ(wait_exit(p.pid, 5000), 0) << waiting[0];
    }
}

}  // namespace

// ---- usage errors that name the file and the line, and output files
// ----------------------------------------

namespace {

std::string temp_file(const std::string& name, const std::string& content) {
    const std::string path = state_dir() + "/" + name;
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f != nullptr) {
        std::fwrite(content.data(), 1, content.size(), f);
        std::fclose(f);
    }
    return path;
}

bool has(const RunResult& r, const std::string& text) {
    return r.output.find(text) != std::string::npos;
}

}  // namespace

TEST(EcatSlaveCli, ABadEepromImageIsAUsageError) {
    // Exists, but is no SII image: refused before any network set-up, exit 2 like every bad option.
    const std::string odd = temp_file("odd.bin", "abc");
    const RunResult r = run({"--eeprom", odd, "--iface", "lo"});
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_TRUE(has(r, "--eeprom")) << r.output;
    EXPECT_TRUE(has(r, "3 bytes")) << r.output;
    EXPECT_EQ(run({"--eeprom", temp_file("empty.bin", ""), "--iface", "lo"}).code, 2);
}

TEST(EcatSlaveCli, ConfigurationErrorsNameTheFileAndTheLine) {
    struct Case {
        std::string content, expect;
    };
    const std::vector<Case> cases = {
        {"state-dir = /tmp/x\n[identity\nvendor_id = 1\n", ":2: section header '[identity' without ']'"},
        {"# options\nfrobnicate = 1\n", ":2: unknown option 'frobnicate'"},
        {"[identity]\nvendor_idx = 3\n", ":2: unknown key 'vendor_idx' in [identity]"},
        {"[identity]\n[nonsense]\nx = 1\n", ":2: unknown section [nonsense]"},
        {"limit-neg = -5\n\x7f\x45LF\x02\x01\x01\x00\x00\x00\n",
         ":2: control character 0x7F at column 1 (not text)"},
    };
    int n = 0;
    for (const Case& c : cases) {
        const std::string path = temp_file("bad" + std::to_string(n++) + ".conf", c.content);
        const RunResult r = run({"--config", path, "--write-sii", state_dir() + "/out.sii"});
        EXPECT_EQ(r.code, 2) << r.output;
        EXPECT_TRUE(has(r, path + c.expect)) << "expected '" << path + c.expect << "' in: " << r.output;
        EXPECT_FALSE(has(r, "ELF")) << "the binary content is echoed: " << r.output;
    }
    const RunResult missing =
        run({"--config", state_dir() + "/none.conf", "--write-sii", state_dir() + "/o"});
    EXPECT_EQ(missing.code, 2) << missing.output;
    EXPECT_TRUE(has(missing, "none.conf: cannot open the configuration file: No such file or directory"))
        << missing.output;
    // The example configurations are accepted as they are.
    EXPECT_EQ(run({"--config", std::string(SOFTECAT_SOURCE_DIR) + "/tools/ecat-slave/drive.conf",
                   "--write-sii", state_dir() + "/ok.sii"})
                  .code,
              0);
}

TEST(EcatSlaveCli, OutputFilesTakeDashForStandardOutputAndSayWhyAWriteFails) {
    const RunResult esi = run({"--write-esi", "-"});
    EXPECT_EQ(esi.code, 0) << esi.output;
    EXPECT_TRUE(has(esi, "<EtherCATInfo")) << esi.output.substr(0, 200);
    EXPECT_FALSE(std::filesystem::exists("-"));
    const RunResult sii = run({"--write-sii", "-"});
    EXPECT_EQ(sii.code, 0);
    EXPECT_GE(sii.output.size(), 128u);  // the binary image on stdout
    const RunResult bad = run({"--write-esi", "/nonexistent-dir/device.xml"});
    EXPECT_EQ(bad.code, 1) << bad.output;
    EXPECT_TRUE(has(bad, "cannot write /nonexistent-dir/device.xml: No such file or directory"))
        << bad.output;
}
