// ecat-soak: the master side of the soak test (tests/integration/test_soak.py, issue 14). One process runs a
// DC-synchronous cyclic session with one slave and, beside it on the same wire, CoE mailbox traffic (SDO
// downloads and uploads between cycles), and replaces a share of the cycle frames with bad frames of known
// kinds. It reports what it saw as "name value" lines; the test compares them with the slave's statistics.
//
//   ecat-soak --iface IF [--cycles N] [--cycle-us US] [--bad-percent P] [--sdo-every N] [--seed S]
//
// Bad frames go out through their own raw socket with the source address 02:BA:D0:BA:D0:00 (kBadSource), so
// the test's loss filter can let them pass (every bad frame then reaches the slave and must be counted
// there). Each bad
// frame has a frame length error (ESC datasheet section I, Table 57), which the slave counts by reason and
// of which it executes nothing: a first datagram that runs past the end of the frame, or a NOP datagram
// followed by more than 64 bytes of padding. The EtherCAT header length is random (it is not evaluated).
// No frame is shorter than 60 bytes: the slave's link pads a runt as a wire would, so a frame without room
// for the EtherCAT header cannot reach it.
#include <net/if.h>
#include <netpacket/packet.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "esc/link.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"

namespace {

using master::Address;
using master::Error;
using Clock = std::chrono::steady_clock;

constexpr uint16_t kEtherTypeEcat = 0x88A4;

struct Options {
    std::string iface;
    uint64_t cycles = 100'000;
    unsigned cycle_us = 1000;
    double bad_percent = 1.0;
    unsigned sdo_every = 20;
    uint32_t seed = 1;
};

constexpr uint8_t kBadSource[6] = {0x02, 0xBA, 0xD0, 0xBA, 0xD0, 0x00};

[[noreturn]] void die(const std::string& what, Error e = Error::Ok) {
    std::fprintf(stderr, "ecat-soak: %s%s%s\n", what.c_str(), e == Error::Ok ? "" : ": ",
                 e == Error::Ok ? "" : std::string(master::to_string(e)).c_str());
    std::exit(1);
}

bool parse(int argc, char** argv, Options& o) {
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) return false;
        const char* v = argv[++i];
        if (a == "--iface")
            o.iface = v;
        else if (a == "--cycles")
            o.cycles = std::strtoull(v, nullptr, 0);
        else if (a == "--cycle-us")
            o.cycle_us = static_cast<unsigned>(std::strtoul(v, nullptr, 0));
        else if (a == "--bad-percent")
            o.bad_percent = std::strtod(v, nullptr);
        else if (a == "--sdo-every")
            o.sdo_every = static_cast<unsigned>(std::strtoul(v, nullptr, 0));
        else if (a == "--seed")
            o.seed = static_cast<uint32_t>(std::strtoul(v, nullptr, 0));
        else
            return false;
    }
    return !o.iface.empty() && o.cycle_us > 0 && o.sdo_every > 0;
}

// The raw socket the bad frames leave through.
class BadFrames {
  public:
    enum Kind : uint8_t { Length, Datagram, kKinds };
    static constexpr const char* kNames[kKinds] = {"length", "datagram"};

    BadFrames(const std::string& iface, uint32_t seed) : rng_(seed) {
        fd_ = ::socket(AF_PACKET, SOCK_RAW | SOCK_CLOEXEC, 0);  // protocol 0: send only
        if (fd_ < 0) die("raw socket for the bad frames: " + std::string(std::strerror(errno)));
        sockaddr_ll a{};
        a.sll_family = AF_PACKET;
        a.sll_ifindex = static_cast<int>(::if_nametoindex(iface.c_str()));
        if (a.sll_ifindex == 0) die("no interface " + iface);
        if (::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0)
            die("bind: " + std::string(std::strerror(errno)));
    }
    ~BadFrames() { ::close(fd_); }
    BadFrames(const BadFrames&) = delete;
    BadFrames& operator=(const BadFrames&) = delete;

    // Sends one bad frame of a random kind; false if the socket refused it.
    bool send(Kind& kind) {
        kind = static_cast<Kind>(rng_() % kKinds);
        std::array<uint8_t, 1514> f{};
        for (auto& b : f)
            b = static_cast<uint8_t>(rng_());
        std::fill_n(f.begin(), 6, 0xFF);  // broadcast
        std::copy_n(kBadSource, 6, f.begin() + 6);
        f[12] = kEtherTypeEcat >> 8;
        f[13] = kEtherTypeEcat & 0xFF;
        std::size_t size = 0;
        f[15] = static_cast<uint8_t>((f[15] & 0x07) | 0x10);  // type 1, a random length (not evaluated)
        switch (kind) {
            case Length: {  // a NOP datagram (no "more" bit) followed by more than 64 bytes of padding
                size = 16 + 12 + 65 + rng_() % 400;
                f[16] = 0;  // NOP
                put16(f.data() + 16 + 6, 0);
                break;
            }
            case Datagram: {  // the first datagram does not fit in the frame
                size = 60 + rng_() % 300;
                const std::size_t room = size - 16 - 12;  // data bytes the datagram could have
                const uint16_t dlen = static_cast<uint16_t>(room + 1 + rng_() % (0x7FF - room));
                put16(f.data() + 16 + 6, dlen);  // no "more datagrams" bit: this one is the last
                break;
            }
            case kKinds:
                break;
        }
        return ::send(fd_, f.data(), size, 0) == static_cast<ssize_t>(size);
    }

  private:
    static void put16(uint8_t* p, uint16_t v) {
        p[0] = static_cast<uint8_t>(v);
        p[1] = static_cast<uint8_t>(v >> 8);
    }
    int fd_ = -1;
    std::mt19937 rng_;
};

struct SdoCounts {
    uint64_t done = 0;                  // answered with success
    uint64_t aborted = 0;               // answered with an SDO abort (a code)
    uint64_t no_answer = 0;             // neither, also when tried again: timeout, mailbox or protocol error
    uint64_t retried = 0;               // without an answer the first time, tried once more
    uint64_t expected_abort_wrong = 0;  // a refused write aborted with another code than expected
    uint64_t mismatches = 0;            // a value read back is not the one written / the device's
    std::map<uint32_t, uint64_t> abort_codes;
};

}  // namespace

int main(int argc, char** argv) {
    Options o;
    if (!parse(argc, argv, o)) {
        std::fprintf(stderr,
                     "usage: ecat-soak --iface IF [--cycles N] [--cycle-us US] [--bad-percent P] "
                     "[--sdo-every N] [--seed S]\n");
        return 2;
    }
    std::unique_ptr<esc::Link> link;
    try {
        link = esc::open_link(o.iface);
    } catch (const esc::LinkError& e) {
        die(e.what());
    }
    master::MasterOptions mo;
    mo.timeout = std::chrono::milliseconds(5);  // a lost cycle frame costs this much, not 100 ms
    mo.retries = 3;
    master::Master m(*link, mo);

    // Set-up: station address, PREOP with the mailbox, the process-data layout, DC SYNC0, OP.
    auto n = m.count_slaves();
    if (!n || *n < 1) die("no slave", n ? Error::Timeout : n.error());
    if (Error e = m.assign_station_addresses(1); e != Error::Ok) die("station address", e);
    const Address a = Address::station(0x1001);
    if (Error e = m.request_state(a, master::AlState::Init); e != Error::Ok) die("INIT", e);
    master::Mailbox mbx(m, a);
    if (Error e = mbx.configure_from_sii(); e != Error::Ok) die("mailbox", e);
    if (Error e = m.request_state(a, master::AlState::PreOp); e != Error::Ok) die("PREOP", e);
    master::SdoClient sdo(mbx);
    std::vector<uint8_t> buf(512);
    auto upload_u32 = [&](uint16_t index, uint8_t sub) -> master::Result<uint32_t> {
        auto r = sdo.upload(index, sub, buf);
        if (!r) return r.error();
        uint32_t v = 0;
        for (std::size_t i = 0; i < std::min<std::size_t>(*r, 4); ++i)
            v |= static_cast<uint32_t>(buf[i]) << (8 * i);
        return v;
    };
    const auto vendor = upload_u32(0x1018, 1);
    if (!vendor) die("0x1018:01", vendor.error());
    auto name_len = sdo.upload(0x1008, 0, buf);
    if (!name_len) die("0x1008", name_len.error());
    const std::string device_name(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(*name_len));
    // Where the target position (0x607A) sits in the outputs, if the first RxPDO maps it.
    int target_at = -1;
    if (auto pdo = upload_u32(0x1C12, 1)) {
        if (auto count = upload_u32(static_cast<uint16_t>(*pdo), 0)) {
            unsigned bits = 0;
            for (uint8_t s = 1; s <= (*count & 0xFF); ++s) {
                auto entry = upload_u32(static_cast<uint16_t>(*pdo), s);
                if (!entry) break;
                if ((*entry >> 8) == 0x607A00 && (*entry & 0xFF) == 32 && bits % 8 == 0)
                    target_at = static_cast<int>(bits / 8);
                bits += *entry & 0xFF;
            }
        }
    }
    // The soak checks consistency, not timing: a long process-data watchdog (2 s at the default divider of
    // 100 us) so that a host that stalls the master now and then does not end OP.
    (void)m.write_reg<uint16_t>(a, 0x0420, 20'000);

    master::ProcessDataSession pd(m, a, sdo);
    if (Error e = pd.discover(); e != Error::Ok) die("process-data layout", e);
    master::DcConfig dc;
    dc.enable = true;
    dc.cycle_ns = o.cycle_us * 1000u;
    if (Error e = pd.configure(dc); e != Error::Ok) die("configure", e);
    const auto period = std::chrono::microseconds(o.cycle_us);
    uint32_t target = 0;
    std::deque<uint32_t> recent_targets;  // the last targets sent (a lost frame keeps an older one)
    auto fill = [&] {
        auto out = pd.outputs();
        std::fill(out.begin(), out.end(), 0);
        if (target_at >= 0 && static_cast<std::size_t>(target_at) + 4 <= out.size())
            for (int i = 0; i < 4; ++i)
                out[static_cast<std::size_t>(target_at + i)] = static_cast<uint8_t>(target >> (8 * i));
    };
    master::AlStatus final{};
    if (Error e = pd.request_state(master::AlState::SafeOp, period, &final, fill); e != Error::Ok)
        die("SAFEOP (AL status code " + std::to_string(final.code) + ")", e);
    if (Error e = pd.request_state(master::AlState::Op, period, &final, fill); e != Error::Ok)
        die("OP (AL status code " + std::to_string(final.code) + ")", e);

    // The soak.
    BadFrames bad(o.iface, o.seed);
    std::mt19937 rng(o.seed ^ 0x5A5A5A5Au);
    std::uniform_real_distribution<double> uni(0.0, 100.0);
    const master::CycleStats before = pd.stats();
    std::array<uint64_t, BadFrames::kKinds> bad_sent{};
    uint64_t bad_refused = 0, cycles_ok = 0, cycles_lost = 0, wkc_errors = 0, other_errors = 0, sdo_ops = 0;
    SdoCounts sdos;
    uint32_t window = 1000;     // 0x6065 following error window: the value last written
    bool window_known = false;  // its last download got an answer either way
    const auto started = Clock::now();
    auto next = Clock::now();
    for (uint64_t i = 0; i < o.cycles; ++i) {
        if (uni(rng) < o.bad_percent) {
            BadFrames::Kind kind{};
            if (bad.send(kind))
                ++bad_sent[kind];
            else
                ++bad_refused;
        } else {
            ++target;
            fill();
            recent_targets.push_back(target);
            if (recent_targets.size() > 64) recent_targets.pop_front();
            const Error e = pd.cycle();
            if (e == Error::Ok)
                ++cycles_ok;
            else if (e == Error::Timeout)
                ++cycles_lost;
            else if (e == Error::WorkingCounter)
                ++wkc_errors;
            else
                ++other_errors;
        }
        if (i % o.sdo_every == o.sdo_every - 1) {
            // One SDO operation of a rotating mix; every one must end done or aborted with a code. One that
            // got no answer in time (the soak loses frames on purpose, and a loaded host delays the slave) is
            // tried once more, as an application does; its late answer must not be taken for the retry's.
            auto attempt = [&](unsigned kind) -> Error {
                switch (kind) {
                    case 0: {  // download of a stored parameter, read back next time
                        const uint32_t v = 1000 + static_cast<uint32_t>(rng() % 100000);
                        uint8_t b[4] = {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8),
                                        static_cast<uint8_t>(v >> 16), static_cast<uint8_t>(v >> 24)};
                        const Error e = sdo.download(0x6065, 0, b);
                        window_known = e == Error::Ok;
                        if (e == Error::Ok) window = v;
                        return e;
                    }
                    case 1: {
                        auto r = upload_u32(0x6065, 0);
                        if (r && window_known && *r != window) {
                            ++sdos.mismatches;
                            std::fprintf(stderr, "ecat-soak: 0x6065 reads %u, %u was written\n", *r, window);
                        }
                        return r ? Error::Ok : r.error();
                    }
                    case 2: {
                        auto r = upload_u32(0x1018, 1);
                        if (r && *r != *vendor) ++sdos.mismatches;
                        return r ? Error::Ok : r.error();
                    }
                    case 3: {  // segmented upload
                        auto r = sdo.upload(0x1008, 0, buf);
                        if (r && std::string(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(*r)) !=
                                     device_name)
                            ++sdos.mismatches;
                        return r ? Error::Ok : r.error();
                    }
                    default: {  // a write the slave must refuse: read-only identity
                        const uint8_t b[4] = {1, 2, 3, 4};
                        const Error e = sdo.download(0x1018, 1, b);
                        if (e == Error::Ok || (e == Error::SdoAbort && sdo.last_abort() != 0x06010002))
                            ++sdos.expected_abort_wrong;
                        return e;
                    }
                }
            };
            const unsigned kind = static_cast<unsigned>(sdo_ops++ % 5);
            Error e = attempt(kind);
            if (e != Error::Ok && e != Error::SdoAbort) {
                ++sdos.retried;
                std::fprintf(stderr, "ecat-soak: cycle %llu: SDO without an answer, tried again: %s\n",
                             static_cast<unsigned long long>(i), std::string(master::to_string(e)).c_str());
                e = attempt(kind);
            }
            if (e == Error::Ok) {
                ++sdos.done;
            } else if (e == Error::SdoAbort) {
                ++sdos.aborted;
                ++sdos.abort_codes[sdo.last_abort()];
            } else {
                ++sdos.no_answer;
                std::fprintf(stderr, "ecat-soak: cycle %llu: SDO without an answer: %s\n",
                             static_cast<unsigned long long>(i), std::string(master::to_string(e)).c_str());
            }
        }
        // Absolute deadlines: after an SDO or a lost frame the next cycles follow without a pause until the
        // session is back on its schedule, so N cycles take N periods when the host keeps up.
        next += period;
        if (next > Clock::now()) std::this_thread::sleep_until(next);
    }
    const double seconds = std::chrono::duration<double>(Clock::now() - started).count();

    // After the soak: still OP without an error; the outputs the slave took are ones that were sent.
    auto st = m.al_status(a);
    int64_t target_seen = -1;
    bool target_recent = target_at < 0;
    // The final reads are retried: the soak loses frames on purpose, and on a loaded host a mailbox answer
    // may come after the client's timeout; what is checked is the value, not that one attempt got through.
    auto upload_final = [&](uint16_t index, uint8_t sub) {
        auto r = upload_u32(index, sub);
        for (int attempt = 1; attempt < 5 && !r; ++attempt) {
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
            r = upload_u32(index, sub);
        }
        return r;
    };
    if (target_at >= 0) {
        if (auto r = upload_final(0x607A, 0)) {
            target_seen = *r;
            target_recent =
                std::find(recent_targets.begin(), recent_targets.end(), *r) != recent_targets.end();
        }
    }
    auto window_now = upload_final(0x6065, 0);
    if (window_now && window_known && *window_now != window) ++sdos.mismatches;
    (void)m.request_state(a, master::AlState::PreOp);

    const auto& s = pd.stats();
    uint64_t bad_total = 0;
    for (uint64_t v : bad_sent)
        bad_total += v;
    std::printf("cycles %llu\n", static_cast<unsigned long long>(o.cycles));
    std::printf("seconds %.1f\n", seconds);
    std::printf("cycle_frames %llu\n", static_cast<unsigned long long>(s.cycles - before.cycles));
    std::printf("cycles_ok %llu\n", static_cast<unsigned long long>(cycles_ok));
    std::printf("cycles_lost %llu\n", static_cast<unsigned long long>(cycles_lost));
    std::printf("wkc_errors %llu\n", static_cast<unsigned long long>(wkc_errors));
    std::printf("other_errors %llu\n", static_cast<unsigned long long>(other_errors));
    std::printf("bad_frames %llu\n", static_cast<unsigned long long>(bad_total));
    for (int k = 0; k < BadFrames::kKinds; ++k)
        std::printf("bad_%s %llu\n", BadFrames::kNames[k], static_cast<unsigned long long>(bad_sent[k]));
    std::printf("bad_refused %llu\n", static_cast<unsigned long long>(bad_refused));
    std::printf("sdo_ops %llu\n", static_cast<unsigned long long>(sdo_ops));
    std::printf("sdo_done %llu\n", static_cast<unsigned long long>(sdos.done));
    std::printf("sdo_aborted %llu\n", static_cast<unsigned long long>(sdos.aborted));
    std::printf("sdo_no_answer %llu\n", static_cast<unsigned long long>(sdos.no_answer));
    std::printf("sdo_retried %llu\n", static_cast<unsigned long long>(sdos.retried));
    std::printf("sdo_stale_answers %llu\n", static_cast<unsigned long long>(sdo.stale_answers()));
    std::printf("sdo_wrong_abort %llu\n", static_cast<unsigned long long>(sdos.expected_abort_wrong));
    std::printf("sdo_mismatches %llu\n", static_cast<unsigned long long>(sdos.mismatches));
    for (const auto& [code, count] : sdos.abort_codes)
        std::printf("abort_0x%08x %llu\n", code, static_cast<unsigned long long>(count));
    std::printf("mailbox_repeats %llu\n", static_cast<unsigned long long>(mbx.repeats()));
    std::printf("master_timeouts %llu\n", static_cast<unsigned long long>(m.stats().timeouts));
    std::printf("final_state %u\n", st ? static_cast<unsigned>(st->state) : 0u);
    std::printf("final_error %u\n", st ? static_cast<unsigned>(st->error) : 1u);
    std::printf("target_mapped %d\n", target_at >= 0 ? 1 : 0);
    std::printf("target_seen %lld\n", static_cast<long long>(target_seen));
    std::printf("target_recent %d\n", target_recent ? 1 : 0);
    return 0;
}
