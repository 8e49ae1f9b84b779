// ecat-conform: runs the conformance catalogue against one slave on a Linux interface and reports, test by
// test, where the slave differs from what the standards and its ESI file promise.
#include <fnmatch.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <cmath>
#include <csignal>
#include <cstring>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include "conform.hpp"
#include "esc/link.hpp"
#include "esi/esi_reader.hpp"
#include "report.hpp"
#include "sdo_util.hpp"
#include "util/input_file.hpp"
#include "util/strfmt.hpp"

namespace {

using conform::Status;

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string x;
    while (std::getline(ss, x, ','))
        if (!x.empty()) out.push_back(x);
    return out;
}

bool selected(const conform::TestCase& t, const std::set<std::string>& groups, const std::string& filter) {
    if (!groups.empty() && !groups.count(t.group)) return false;
    if (!filter.empty()) {
        bool any = false;
        for (const auto& f : split(filter))
            any = any || fnmatch(f.c_str(), t.id.c_str(), 0) == 0;
        if (!any) return false;
    }
    return true;
}

// Stopped from outside (SIGTERM, SIGINT) or by --deadline (SIGALRM): the JUnit and JSON files on disk already
// hold every finished test and the running one marked as interrupted (written before it started); the
// handler only ends the text report with a prepared line and exits.
constexpr int kExitStopped = 3;
// A pause of the tool's own process-data cycles beyond which a slave may rightly have seen a communication
// loss (ten cycles of the tool's 1 ms cycle: a DC slave's SM-event and sync error counters count far
// fewer; an SM watchdog is 100 ms by default). A test that failed after such a pause runs once more.
constexpr std::chrono::milliseconds kOwnPauseLimit{10};
char g_stop_line[512] = "\nstopped\n";
volatile std::sig_atomic_t g_stop_len = 9;

extern "C" void on_stop(int sig) {
    const char* why = sig == SIGALRM ? "\nstopped: --deadline reached while running "
                                     : "\nstopped by a signal while running ";
    (void)!write(STDOUT_FILENO, why, std::strlen(why));
    (void)!write(STDOUT_FILENO, g_stop_line, static_cast<std::size_t>(g_stop_len));
    _exit(kExitStopped);
}

void prepare_stop_line(const std::string& id) {
    const std::string line = id + " (reports hold the tests before it)\n";
    const std::size_t n = std::min(line.size(), sizeof g_stop_line);
    std::memcpy(g_stop_line, line.data(), n);
    g_stop_len = static_cast<std::sig_atomic_t>(n);
}

// The stop signals held back while the reports on disk and the prepared stop line change: the two report
// files are renamed one after the other, and a stop between the renames would leave JUnit and JSON holding
// different sets of tests. A signal that arrives meanwhile is delivered when the guard ends.
class StopSignalsHeld {
  public:
    StopSignalsHeld() {
        sigset_t s;
        sigemptyset(&s);
        sigaddset(&s, SIGTERM);
        sigaddset(&s, SIGINT);
        sigaddset(&s, SIGALRM);
        pthread_sigmask(SIG_BLOCK, &s, &old_);
    }
    ~StopSignalsHeld() { pthread_sigmask(SIG_SETMASK, &old_, nullptr); }
    StopSignalsHeld(const StopSignalsHeld&) = delete;
    StopSignalsHeld& operator=(const StopSignalsHeld&) = delete;

  private:
    sigset_t old_{};
};

// Written to FILE.tmp and renamed: a reader (or a kill) never sees half a file.
template <typename Writer>
void save_atomically(const std::string& path, Writer w) {
    if (path.empty()) return;
    const std::string tmp = path + ".tmp";
    {
        std::ofstream f(tmp);
        w(f);
        if (!f) {
            std::fprintf(stderr, "ecat-conform: cannot write %s\n", tmp.c_str());
            return;
        }
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0)
        std::fprintf(stderr, "ecat-conform: cannot write %s\n", path.c_str());
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "ecat-conform: EtherCAT slave conformance tests (ETG.1000, ETG.2000, ETG.1020, ETG.5001, CiA 402)"};
    app.set_version_flag("--version", std::string("ecat-conform ") + SOFTECAT_VERSION);
    conform::Options o;
    std::string groups_arg, filter, junit, json, backend;
    bool list = false, markdown = false;
    app.add_option("--iface,-i", o.iface, "Interface the slave is on");
    std::string slave_arg = "0";
    app.add_option(
        "--slave", slave_arg,
        "Position of the slave under test (0 = first); a list (0,2) or 'all': each in turn, one report");
    app.add_option(
        "--esi-dir", o.esi_dir,
        "Without --esi: a directory of ESI files; each slave is tested against the file whose device "
        "matches its SII identity");
    app.add_option("--esi", o.esi_path,
                   "ESI XML file: the expectation (object dictionary, PDOs, SMs, DC, ...)");
    app.add_option("--device", o.device,
                   "Device index in the ESI file (default: the one matching the SII identity)");
    app.add_option(
        "--modules", o.modules,
        "A modular device's module in each slot, as the slave was configured (ecat-slave --device "
        "SPEC@MODULES): Type names or idents, comma separated, '-' for an empty slot (default: each "
        "slot's default module)");
    app.add_option("--group", groups_arg,
                   "Only these groups (comma separated): esc,sii,esm,mbx,sdo,sdoinfo,pd,dc,foe,cia402");
    app.add_option("--filter", filter, "Only tests whose id matches this glob (comma separated globs)");
    app.add_flag("--list", list, "Print the catalogue and exit");
    app.add_flag("--markdown", markdown, "With --list: a markdown table");
    app.add_option("--junit", junit, "Write JUnit XML to FILE");
    app.add_option("--json", json, "Write the results as JSON to FILE");
    app.add_option("--timeout-scale", o.timeout_scale, "Multiply every timeout (slow slaves, busy hosts)")
        ->check(CLI::Range(0.1, 100.0));
    app.add_option("--foe-file", o.foe_file,
                   "A file name the device accepts over FoE in Bootstrap (enables the password test)");
    app.add_option("--foe-password", o.foe_password, "The FoE password of that file (default 0)");
    app.add_flag(
        "--allow-fault", o.allow_fault,
        "Allow tests that provoke a drive fault (communication loss while enabled; the drive's fault "
        "reaction runs)");
    app.add_flag("--allow-motion", o.allow_motion, "Allow tests that command motion of an axis");
    app.add_flag("--allow-foe-write", o.allow_foe_write,
                 "Allow an FoE write of --foe-file to go through (writes the device's firmware/flash)");
    std::string foe_image;
    app.add_option("--foe-image", foe_image,
                   "The file that write sends (the device's own firmware: the device keeps it)");
    app.add_option("--backend", backend, "Raw-socket backend: packet or pcap");
    double deadline = 0, budget = 30;
    app.add_option("--deadline", deadline,
                   "Stop the run after SECONDS (reports complete up to the running test; exit code 3)")
        ->check(CLI::PositiveNumber);
    app.add_option("--test-budget", budget,
                   "Seconds one test may wait in all (scaled by --timeout-scale); past it every wait is cut "
                   "short, so a slave that lies or stops answering cannot stretch the run (default 30)")
        ->check(CLI::PositiveNumber);
    app.add_flag("--verbose,-v", o.verbose, "Details of passed and skipped tests too");
    CLI11_PARSE(app, argc, argv);
    if (!foe_image.empty()) {
        try {
            o.foe_image = util::read_input_bytes(foe_image, std::size_t{64} << 20, "firmware image");
        } catch (const util::InputFileError& e) {
            std::fprintf(stderr, "ecat-conform: %s\n", e.what());
            return 2;
        }
    }

    // The ESI files are the user's input: one that cannot be read (a FIFO, a device, a directory, too large,
    // not EtherCATInfo) is a usage error naming the file and line, exit 2, before the bus is touched; not a
    // run of tests that each fail with "cannot start". Files of --esi-dir that are not ESI are passed over
    // there.
    if (!o.esi_path.empty()) {
        try {
            (void)esi::read_esi_file(o.esi_path);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "ecat-conform: --esi %s\n", e.what());
            return 2;
        }
    }
    if (std::error_code ec; !o.esi_dir.empty() && !std::filesystem::is_directory(o.esi_dir, ec)) {
        std::fprintf(stderr, "ecat-conform: --esi-dir %s: %s\n", o.esi_dir.c_str(),
                     ec ? ec.message().c_str() : "not a directory");
        return 2;
    }

    const conform::Catalogue catalogue = conform::build_catalogue();
    std::set<std::string> groups;
    for (const auto& g : split(groups_arg)) {
        bool known = false;
        for (const auto& n : conform::group_names())
            known = known || n == g;
        if (!known) {
            std::fprintf(stderr, "ecat-conform: unknown group '%s'\n", g.c_str());
            return 2;
        }
        groups.insert(g);
    }
    conform::Catalogue chosen;
    for (const auto& t : catalogue)
        if (selected(t, groups, filter)) chosen.push_back(t);
    if (list) {
        conform::write_list(std::cout, chosen, markdown);
        return 0;
    }
    if (o.iface.empty()) {
        std::fprintf(stderr, "ecat-conform: --iface is required (or --list)\n");
        return 2;
    }
    if (chosen.empty()) {
        std::fprintf(stderr, "ecat-conform: no test matches the selection\n");
        return 2;
    }
    std::unique_ptr<esc::Link> link;
    try {
        link = esc::open_link(o.iface, backend);
    } catch (const esc::LinkError& e) {
        std::fprintf(stderr, "ecat-conform: %s\n", e.what());
        return 2;
    }
    master::MasterOptions mo;
    mo.timeout = std::chrono::microseconds(static_cast<long>(20'000 * o.timeout_scale));
    mo.retries = 2;
    mo.accept_own_source = true;  // esc.frame.source_mac checks the bit; the rest still runs
    mo.sii_timeout = std::chrono::milliseconds(static_cast<long>(100 * o.timeout_scale));
    mo.al_timeout = std::chrono::milliseconds(static_cast<long>(5000 * o.timeout_scale));
    master::Master m(*link, mo);
    // The slaves under test: one position, a list, or all of the line.
    std::vector<uint16_t> units;
    const bool many = slave_arg == "all" || slave_arg.find(',') != std::string::npos;
    if (slave_arg == "all") {
        auto n = m.count_slaves();
        for (uint16_t i = 0; n && i < *n; ++i)
            units.push_back(i);
        if (units.empty()) units.push_back(0);  // the setup says that no slave answered
    } else {
        for (const auto& x : split(slave_arg)) {
            char* end = nullptr;
            const unsigned long v = std::strtoul(x.c_str(), &end, 0);
            if (!end || *end || v > 0xFFFF) {
                std::fprintf(stderr, "ecat-conform: --slave: '%s' is not a position, a list or 'all'\n",
                             x.c_str());
                return 2;
            }
            units.push_back(static_cast<uint16_t>(v));
        }
    }
    if (units.empty()) {
        std::fprintf(stderr, "ecat-conform: --slave: no position given\n");
        return 2;
    }

    const auto t0 = std::chrono::steady_clock::now();
    std::vector<conform::TestResult> results;
    results.reserve(chosen.size());
    conform::RunInfo info;
    info.iface = o.iface;
    const bool colour = isatty(STDOUT_FILENO) != 0;
    auto elapsed = [&] {
        return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0);
    };
    // The reports on disk: the results so far, and the running test (if any) marked as interrupted.
    auto save = [&](const conform::TestCase* running) {
        const StopSignalsHeld held;
        info.duration = elapsed();
        std::vector<conform::TestResult> rs = results;
        if (running) {
            conform::TestResult r;
            r.test = running;
            if (many) r.slave = o.slave;
            r.outcome = conform::fail("interrupted: the run was stopped while this test ran");
            rs.push_back(r);
        }
        save_atomically(junit, [&](std::ostream& f) { conform::write_junit(f, rs, info); });
        save_atomically(json, [&](std::ostream& f) { conform::write_json(f, rs, info); });
    };
    std::signal(SIGTERM, on_stop);
    std::signal(SIGINT, on_stop);
    std::signal(SIGALRM, on_stop);
    if (deadline > 0) alarm(static_cast<unsigned>(std::ceil(deadline)));
    std::string text_group;
    auto emit = [&](conform::TestResult r) {
        results.push_back(std::move(r));
        conform::write_text_result(std::cout, results.back(), text_group, colour, o.verbose);
        std::cout << std::flush;
    };
    if (many) {
        info.device = "slaves " + slave_arg;
        conform::write_text_header(std::cout, info);
    }
    for (const uint16_t unit : units) {
        o.slave = unit;
        conform::Context ctx(m, o);
        ctx.link = link.get();
        auto emit_unit = [&](conform::TestResult r) {
            if (many) r.slave = unit;
            emit(std::move(r));
        };
        const std::string setup_error = ctx.setup();
        if (!setup_error.empty()) {
            if (!many) {
                info.device = "(none)";
                conform::write_text_header(std::cout, info);
            }
            for (const auto& t : chosen) {
                conform::TestResult r;
                r.test = &t;
                r.outcome = conform::fail("cannot start: " + setup_error);
                emit_unit(r);
            }
        } else {
            std::string device;
            if (ctx.sii)
                device = util::strprintf("slave %u of %u, vendor 0x%08x product 0x%08x revision 0x%08x%s",
                                         o.slave, ctx.slave_count, ctx.sii->dword(0x08), ctx.sii->dword(0x0A),
                                         ctx.sii->dword(0x0C), ctx.esi ? "" : " (no ESI)");
            else
                device = util::strprintf("slave %u of %u (SII unreadable)", o.slave, ctx.slave_count);
            if (ctx.esi) device += ", ESI device \"" + ctx.esi->type_name + "\"";
            if (many) {
                std::cout << "\n=== slave " << unit << ": " << conform::printable(device) << "\n";
                info.device += (info.device.empty() ? "" : "; ") + std::string("slave ") +
                               std::to_string(unit) + ": " + device;
            } else {
                info.device = device;
                conform::write_text_header(std::cout, info);
            }
            std::cout << std::flush;
            std::string group;
            std::string
                group_broken;  // id of the test that reported the group's failed start, "" when it started
            std::string lost;  // id of the test during which the slave stopped answering, "" while it answers
            // Id of the test after which the slave's mailbox stopped serving (every request answered by a
            // mailbox error or not at all, in PREOP), "" while it serves: a mailbox that a defect wedged for
            // good is reported on that test, and the later failures that need it are not judged.
            std::string mbx_dead, mbx_dead_why;
            auto mailbox_fault = [&]() -> std::string {
                if (!ctx.has_coe() || ctx.to_preop() != master::Error::Ok) return {};
                auto v = ctx.upload_uint(0x1000, 0);
                if (v ||
                    (v.error() != master::Error::MailboxError && v.error() != master::Error::MailboxTimeout))
                    return {};
                return ctx.sdo_error(v.error());
            };
            auto about_mailbox = [](const conform::Outcome& x) {
                return (x.message + " " + x.observed).find("mailbox") != std::string::npos;
            };
            std::string previous = "none";  // id of the test run last
            // A slave that stopped answering is given this long to answer again before it is called lost: a
            // busy host may deschedule the slave (or this tool) for a few hundred milliseconds, and a
            // conformance verdict must not depend on that; a slave that is gone is still reported within it.
            const auto answer_grace =
                std::chrono::milliseconds(static_cast<long>(conform::kAnswerGraceMs * o.timeout_scale));
            // Waits (up to answer_grace) until the slave answers at its station address again, giving it its
            // address again when it lost it (reset); returns how long it did not answer, or nothing.
            auto answers_again = [&]() -> std::optional<std::chrono::milliseconds> {
                const auto since = std::chrono::steady_clock::now();
                for (;;) {
                    if (ctx.rd<uint16_t>(esc::reg::kStationAddress))
                        return std::chrono::duration_cast<std::chrono::milliseconds>(
                            std::chrono::steady_clock::now() - since);
                    auto n = m.count_slaves();
                    if (n && *n > o.slave && m.assign_station_addresses(*n) == master::Error::Ok)
                        return std::chrono::duration_cast<std::chrono::milliseconds>(
                            std::chrono::steady_clock::now() - since);
                    if (std::chrono::steady_clock::now() - since >= answer_grace) return std::nullopt;
                    std::this_thread::sleep_for(std::chrono::milliseconds(10));
                }
            };
            const auto budget_d =
                std::chrono::milliseconds(static_cast<long>(budget * 1000 * o.timeout_scale));
            for (const auto& t : chosen) {
                conform::TestResult r;
                r.test = &t;
                {
                    const StopSignalsHeld held;
                    prepare_stop_line(t.id);
                    save(&t);
                }
                const auto s0 = std::chrono::steady_clock::now();
                ctx.budget_end = {};
                if (!lost.empty()) {
                    // Back (restarted, replugged)? Addresses again and carry on; else fail at once.
                    auto n = m.count_slaves();
                    if (n && *n > o.slave && m.assign_station_addresses(*n) == master::Error::Ok) {
                        ctx.notes.push_back("the slave answered again after it was lost during " + lost);
                        lost.clear();
                        group.clear();
                    } else {
                        r.outcome = conform::fail("the slave no longer answers (lost during " + lost + ")");
                        emit_unit(r);
                        continue;
                    }
                }
                // Every group starts from INIT with SMs and FMMUs off (mailbox set up again by the tests that
                // need it), as a master's start-up does. A group that cannot start says so once, on its first
                // test; its other tests are not run.
                if (t.group != group) {
                    group = t.group;
                    group_broken.clear();
                    ctx.al_timeouts = 0;
                    ctx.budget_end = s0 + budget_d;
                    if (!mbx_dead.empty() && mailbox_fault().empty()) {
                        ctx.notes.push_back("the slave's mailbox served again at the start of group " +
                                            group + " (it had stopped after " + mbx_dead + ")");
                        mbx_dead.clear();
                    }
                    master::Error e = ctx.to_init();
                    if (e != master::Error::Ok) {
                        // Lost the slave (reset, unplugged)? Addresses again, then carry on.
                        (void)m.assign_station_addresses(ctx.slave_count);
                        e = ctx.to_init();
                    }
                    if (e != master::Error::Ok && ctx.esc_reset()) {
                        // Stuck (a register that should be read-only kept a test's write, a state machine
                        // that no longer moves): the ESC reset, where the device has one, gives the group
                        // its known start instead of failing every test after the defect.
                        (void)m.assign_station_addresses(ctx.slave_count);
                        e = ctx.to_init();
                        ctx.notes.push_back("group " + t.group + ": the slave did not go to INIT; it was " +
                                            (e == master::Error::Ok
                                                 ? "reset (ESC reset 0x0040) and the group ran"
                                                 : "reset (ESC reset 0x0040), in vain") +
                                            " (the test before it: " + previous + ")");
                    }
                    if (e != master::Error::Ok) {
                        auto st = ctx.rd<uint16_t>(esc::reg::kAlStatus);
                        r.outcome = conform::fail(
                            "group start: the slave could not be brought to INIT with SMs and FMMUs off: " +
                                std::string(master::to_string(e)),
                            st ? "AL status " + conform::hex(*st)
                               : std::string(master::to_string(st.error())),
                            "AL status 0x0001");
                        group_broken = t.id;
                    }
                } else if (!group_broken.empty()) {
                    r.outcome = conform::skip("not run: the group could not start from INIT (see " +
                                              group_broken + ")");
                }
                if (r.outcome.status == Status::Pass && r.outcome.message.empty() && group_broken.empty()) {
                    // Runs the test; says how the host disturbed it ("" not seen).
                    auto run_once = [&]() -> std::string {
                        ctx.budget_end = std::chrono::steady_clock::now() + budget_d;
                        ctx.sdo_open.reset();
                        ctx.pd_gap_reset();
                        const uint64_t unanswered = m.stats().timeouts;
                        try {
                            r.outcome = t.run(ctx);
                        } catch (const std::exception& e) {
                            r.outcome = conform::fail(std::string("test aborted: ") + e.what());
                        }
                        // A transfer a test's raw requests left open is ended whatever the test's outcome:
                        // a master starts no new transfer while one is in progress (ETG.1000.6 SDO).
                        conform::end_open_sdo(ctx);
                        if (m.stats().timeouts != unanswered) return "frames went unanswered during it";
                        if (const auto pause = ctx.pd_gap(); pause > kOwnPauseLimit)
                            return "this tool's process data paused " +
                                   std::to_string(
                                       std::chrono::duration_cast<std::chrono::milliseconds>(pause).count()) +
                                   " ms between two cycles during it";
                        return "";
                    };
                    // Frames went unanswered during the test, and the slave answers again within the grace:
                    // the host stalled the slave or this tool (a slave does not drop frames; a shared host
                    // deschedules processes). The requests the tool gave up on were served late: their
                    // answers are drained from the mailbox, or every later request would read the one
                    // before's. Or the tool's own process-data cycles paused longer than a slave may rightly
                    // take as a communication loss (its watchdog, its DC synchronisation check): a drive that
                    // then leaves its state did right. A test that failed runs once more and the second
                    // verdict counts; the stall is noted. A slave that stops answering for good is not given
                    // a second run.
                    for (int run = 0; run < 2; ++run) {
                        const std::string disturbed = run_once();
                        if (disturbed.empty()) break;
                        auto gap = answers_again();
                        if (!gap) break;
                        ctx.mbx_resync();
                        if (run > 0 || r.outcome.status != Status::Fail) break;
                        ctx.notes.push_back(
                            "test " + t.id + " ran twice: " + disturbed + " (" + r.outcome.message + ")" +
                            (gap->count() > 0
                                 ? "; the slave answered again after " + std::to_string(gap->count()) + " ms"
                                 : std::string()) +
                            " (a stalled host?)");
                    }
                    if ((r.outcome.status == Status::Fail || r.outcome.status == Status::Warn) &&
                        about_mailbox(r.outcome)) {
                        if (!mbx_dead.empty()) {
                            r.outcome = conform::skip(
                                "not judged: the slave's mailbox stopped serving after " + mbx_dead + " (" +
                                mbx_dead_why + "); here: " + r.outcome.message + " " + r.outcome.observed);
                        } else if (std::string why = mailbox_fault(); !why.empty()) {
                            mbx_dead = t.id;
                            mbx_dead_why = why + " to an upload of 0x1000 in PREOP";
                            r.outcome.message +=
                                " (after this test the slave's mailbox serves no request: " + mbx_dead_why +
                                "; the later failures that need it are not judged)";
                        }
                    }
                    if (std::chrono::steady_clock::now() > ctx.budget_end && r.outcome.status == Status::Fail)
                        r.outcome.message += " (the test used up its budget of " +
                                             std::to_string(static_cast<long>(budget * o.timeout_scale)) +
                                             " s; later waits were cut short)";
                    ctx.budget_end = {};
                    if (r.outcome.status == Status::Fail && t.severity == conform::Severity::Warning)
                        r.outcome.status = Status::Warn;
                    // A slave that stopped answering (reset, crash): say so on the test that saw it.
                    if (r.outcome.status == Status::Fail && !ctx.rd<uint16_t>(esc::reg::kStationAddress)) {
                        r.outcome.message += " (the slave no longer answers at its station address)";
                        if (!answers_again()) lost = t.id;
                    }
                }
                r.duration = std::chrono::duration_cast<std::chrono::microseconds>(
                    std::chrono::steady_clock::now() - s0);
                emit_unit(r);
                previous = t.id;
            }
            {
                const StopSignalsHeld held;
                prepare_stop_line("the final restore");
                save(nullptr);
            }
            const std::string note = ctx.restore();
            if (!note.empty()) ctx.notes.push_back(note);
        }
        for (const auto& n : ctx.notes)
            info.notes.push_back(many ? "slave " + std::to_string(unit) + ": " + n : n);
    }
    info.duration = elapsed();
    conform::write_text_footer(std::cout, results, info);
    std::cout << std::flush;
    alarm(0);
    save(nullptr);
    return conform::totals(results).failed ? 1 : 0;
}
