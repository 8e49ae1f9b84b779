// drive-sim: runs the CiA 402 drive (drive::Drive on the real drive dictionary) without EtherCAT through a
// scripted motion, records set-point, actual position, velocity, current and following error to CSV, and
// renders a PNG with gnuplot (plot.hpp: panels on one time axis, mode and CiA 402 state strips, events).
// `--bench` prints the cost of one drive cycle per axis (median, p99).
//
// Script: one command per line, `#` starts a comment. Times in ms of simulated time.
//   at <ms> mode <1|3|6|8|9|10>         0x6060
//   at <ms> cw <value>                  0x6040 (hex with 0x, or decimal)
//   at <ms> enable | disable | quickstop | reset
//   at <ms> target <inc>                0x607A (PPM target, or a CSP jump)
//   at <ms> velocity <rpm>              0x60FF
//   at <ms> torque <permille>           0x6071
//   at <ms> csp <inc> <rpm> <rpm/s>     master-side trapezoid to an absolute target, one 0x607A per cycle
//   at <ms> set <index>:<sub> <value>   any object, e.g. "set 0x6083:0 20000"
//   at <ms> input <pin 1..6> <0|1>      a digital input of the simulated machine
//   at <ms> limit-neg|limit-pos <inc>   limit switches; home <from> <to>; stops <lo> <hi>
// The dictionary starts commissioned for the simulated motor (drive::commission) unless --seed-defaults.
//   end <ms>
#include <CLI/CLI.hpp>

#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "drive/drive.hpp"
#include "drive/profile.hpp"
#include "maxpos/maxpos.hpp"
#include "plot.hpp"
#include "util/input_file.hpp"

namespace {

struct Step {
    double at_ms = 0;
    std::string op;
    std::vector<std::string> args;
};

struct Script {
    std::vector<Step> steps;
    double end_ms = 1000;
};

const char* kDemo = R"(# Default demo: CSP move and back, CSV step, PPM move, CST pulse.
at 0 mode 8
at 1 enable
at 10 csp 20000 2000 20000
at 700 csp 0 3000 30000
at 1300 mode 9
at 1300 velocity 1500
at 1700 velocity -500
at 2000 velocity 0
at 2200 mode 1
at 2200 set 0x6081:0 2500
at 2200 set 0x6083:0 25000
at 2200 set 0x6084:0 25000
at 2210 target 0
at 2210 cw 0x1F
at 2220 cw 0x0F
at 2900 mode 10
at 2900 torque 150
at 3000 torque -150
at 3100 torque 0
end 3300
)";

bool parse_number(const std::string& s, double& out) {
    try {
        std::size_t pos = 0;
        if (s.rfind("0x", 0) == 0 || s.rfind("0X", 0) == 0)
            out = static_cast<double>(std::stoll(s.substr(2), &pos, 16)), pos += 2;
        else
            out = std::stod(s, &pos);
        return pos == s.size();
    } catch (...) {
        return false;
    }
}

bool parse_script(std::istream& in, Script& sc, std::string& err) {
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
        ++n;
        if (auto h = line.find('#'); h != std::string::npos) line.erase(h);
        std::istringstream ls(line);
        std::string w;
        if (!(ls >> w)) continue;
        double t = 0;
        std::string ts;
        if (w == "end") {
            if (!(ls >> ts) || !parse_number(ts, sc.end_ms))
                return err = "line " + std::to_string(n) + ": end <ms>", false;
            continue;
        }
        if (w != "at" || !(ls >> ts) || !parse_number(ts, t)) {
            err = "line " + std::to_string(n) + ": expected 'at <ms> <command>' or 'end <ms>'";
            return false;
        }
        Step st;
        st.at_ms = t;
        if (!(ls >> st.op)) return err = "line " + std::to_string(n) + ": missing command", false;
        while (ls >> w)
            st.args.push_back(w);
        sc.steps.push_back(st);
    }
    std::stable_sort(sc.steps.begin(), sc.steps.end(),
                     [](const Step& a, const Step& b) { return a.at_ms < b.at_ms; });
    return true;
}

// Writes a value given as text into any scalar object, encoded as its declared type.
bool write_object(od::Dictionary& d, const std::string& spec, const std::string& value, std::string& err) {
    const auto colon = spec.find(':');
    double idx = 0, sub = 0, v = 0;
    if (colon == std::string::npos || !parse_number(spec.substr(0, colon), idx) ||
        !parse_number(spec.substr(colon + 1), sub) || !parse_number(value, v)) {
        err = "bad object or value: " + spec + " " + value;
        return false;
    }
    const od::Entry* e = d.find(static_cast<uint16_t>(idx), static_cast<uint8_t>(sub));
    if (!e) {
        err = "no such object " + spec;
        return false;
    }
    uint8_t b[8] = {};
    const auto iv = static_cast<int64_t>(std::llround(v));
    std::memcpy(b, &iv, 8);  // little-endian host: the low bytes are the value in any width
    const od::Status s = d.set_raw(e->index, e->subindex, std::span<const uint8_t>(b, e->byte_size()));
    if (s != od::Status::Ok) {
        err = "write " + spec + " = " + value + ": " + std::string(od::to_string(s));
        return false;
    }
    return true;
}

using drivesim::Sample;

class Sim {
  public:
    // commissioned = the dictionary holds the simulated motor's data and a matched tuning
    // (drive::commission); otherwise the seed defaults (torque constant 0: enabling fails with 0x8331 until
    // the script sets it).
    explicit Sim(bool commissioned = true)
        : dict_(maxpos::dictionary(maxpos::description())), drive_(dict_, nullptr, maxpos::drive_objects()) {
        if (commissioned) drive::commission(dict_, maxpos::drive_objects(), drive_.motor());
    }

    bool apply(const Step& st, std::string& err) {
        auto arg = [&](std::size_t i, double& out) {
            if (i >= st.args.size() || !parse_number(st.args[i], out)) {
                err = "'" + st.op + "': missing or bad argument " + std::to_string(i + 1);
                return false;
            }
            return true;
        };
        double a = 0, b = 0, c = 0;
        Environment& env = drive_.environment();
        if (st.op == "mode") {
            if (!arg(0, a)) return false;
            dict_.set<int8_t>(0x6060, 0, static_cast<int8_t>(a));
            csp_active_ = false;
            dict_.set<int32_t>(0x60B1, 0, 0);
        } else if (st.op == "cw") {
            if (!arg(0, a)) return false;
            cw_ = static_cast<uint16_t>(a);
        } else if (st.op == "enable") {
            enable_steps_ = 3;
        } else if (st.op == "disable") {
            cw_ = 0x0006;
        } else if (st.op == "quickstop") {
            cw_ = 0x000B;
        } else if (st.op == "reset") {
            reset_pending_ = true;
        } else if (st.op == "target") {
            if (!arg(0, a)) return false;
            dict_.set<int32_t>(0x607A, 0, static_cast<int32_t>(a));
            setpoint_ = a;
        } else if (st.op == "velocity") {
            if (!arg(0, a)) return false;
            dict_.set<int32_t>(0x60FF, 0, static_cast<int32_t>(a));
            setpoint_ = a;
        } else if (st.op == "torque") {
            if (!arg(0, a)) return false;
            dict_.set<int16_t>(0x6071, 0, static_cast<int16_t>(a));
            setpoint_ = a;
        } else if (st.op == "csp") {
            if (!arg(0, a) || !arg(1, b) || !arg(2, c)) return false;
            const double res = drive_.axis().increments_per_rev();
            if (!csp_active_) master_.reset(dict_.get<int32_t>(0x6064, 0), 0);
            csp_target_ = a;
            csp_vmax_ = b * res / 60.0;
            csp_acc_ = c * res / 60.0;
            csp_active_ = true;
        } else if (st.op == "set") {
            if (st.args.size() != 2) return err = "'set <index>:<sub> <value>'", false;
            return write_object(dict_, st.args[0], st.args[1], err);
        } else if (st.op == "input") {
            if (!arg(0, a) || !arg(1, b)) return false;
            env.set_input(static_cast<int>(a), b != 0);
        } else if (st.op == "limit-neg") {
            if (!arg(0, a)) return false;
            env.set_negative_limit(a);
        } else if (st.op == "limit-pos") {
            if (!arg(0, a)) return false;
            env.set_positive_limit(a);
        } else if (st.op == "home") {
            if (!arg(0, a) || !arg(1, b)) return false;
            env.set_home_switch(a, b);
        } else if (st.op == "stops") {
            if (!arg(0, a) || !arg(1, b)) return false;
            env.set_mechanical_stops(a, b);
        } else {
            err = "unknown command '" + st.op + "'";
            return false;
        }
        return true;
    }

    void cycle(int64_t t_ns, int64_t dt_ns) {
        if (enable_steps_ > 0) {
            static const uint16_t seq[] = {0x0006, 0x0007, 0x000F};
            cw_ = seq[3 - enable_steps_];
            if (enable_steps_ == 3) dict_.set<int32_t>(0x607A, 0, dict_.get<int32_t>(0x6064, 0));
            --enable_steps_;
        }
        uint16_t cw = cw_;
        if (reset_pending_) {
            cw = static_cast<uint16_t>(cw_ | 0x80);
            reset_pending_ = (cw_prev_ & 0x80) != 0;  // need a 0 -> 1 edge
            if (reset_pending_) cw = static_cast<uint16_t>(cw_ & ~0x80);
        }
        if (csp_active_) {
            master_.step_position(csp_target_, csp_vmax_, csp_acc_, csp_acc_,
                                  static_cast<double>(dt_ns) * 1e-9);
            dict_.set<int32_t>(0x607A, 0, static_cast<int32_t>(std::lround(master_.position())));
            // Velocity pre-control through 0x60B1, as TwinCAT does in CSP.
            const double res = drive_.axis().increments_per_rev();
            dict_.set<int32_t>(0x60B1, 0, static_cast<int32_t>(std::lround(master_.velocity() * 60.0 / res)));
            setpoint_ = master_.position();
        }
        dict_.set<uint16_t>(0x6040, 0, cw);
        cw_prev_ = cw;
        drive_.cycle(t_ns, dt_ns);
    }

    Sample sample(double t_ms) const {
        return {t_ms,
                setpoint_,
                dict_.get<int32_t>(0x6062, 0),
                dict_.get<int32_t>(0x6064, 0),
                dict_.get<int32_t>(0x606C, 0),
                dict_.get<int32_t>(0x606B, 0),
                dict_.get<int32_t>(0x60F4, 0),
                dict_.get<int16_t>(0x6078, 0),
                dict_.get<uint16_t>(0x6041, 0),
                dict_.get<int8_t>(0x6061, 0),
                dict_.get<uint32_t>(0x60FD, 0),
                dict_.get<uint16_t>(0x603F, 0)};
    }
    drive::Drive& drive() { return drive_; }
    od::Dictionary& dict() { return dict_; }

  private:
    using Environment = drive::Environment;
    od::Dictionary dict_;
    drive::Drive drive_;
    drive::Profile master_;
    bool csp_active_ = false;
    double csp_target_ = 0, csp_vmax_ = 0, csp_acc_ = 0;
    double setpoint_ = 0;
    uint16_t cw_ = 0, cw_prev_ = 0;
    int enable_steps_ = 0;
    bool reset_pending_ = false;
};

bool render_png(const std::string& csv, const std::string& png, const std::string& title, double end_ms,
                const std::vector<drivesim::Event>& events, std::string& err) {
    const std::string gp = png + ".gp";
    {
        std::ofstream f(gp);
        f << drivesim::gnuplot_script(csv, png, title, end_ms, events);
        if (!f) return err = "cannot write " + gp, false;
    }
    const pid_t pid = fork();
    if (pid < 0) return err = "fork failed", false;
    if (pid == 0) {
        execlp("gnuplot", "gnuplot", gp.c_str(), static_cast<char*>(nullptr));
        _exit(127);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        err = "gnuplot failed (exit " + std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")";
        // pngcairo may be missing in gnuplot-nox builds: retry with the plain png terminal.
        std::ifstream in(gp);
        std::stringstream ss;
        ss << in.rdbuf();
        std::string text = ss.str();
        const auto p = text.find("pngcairo");
        if (p == std::string::npos) return false;
        text.replace(p, 8, "png");
        std::ofstream(gp) << text;
        const pid_t p2 = fork();
        if (p2 == 0) {
            execlp("gnuplot", "gnuplot", gp.c_str(), static_cast<char*>(nullptr));
            _exit(127);
        }
        waitpid(p2, &status, 0);
        if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) return false;
    }
    std::remove(gp.c_str());
    return true;
}

int bench(int axes, int cycles, int64_t dt_ns) {
    // N independent axes in CSP, each following a moving set-point: the cost the process-data cycle pays.
    std::vector<std::unique_ptr<Sim>> sims;
    for (int i = 0; i < axes; ++i) {
        sims.push_back(std::make_unique<Sim>());
        std::string err;
        sims.back()->apply({0, "enable", {}}, err);
    }
    std::vector<double> per_axis;
    per_axis.reserve(static_cast<std::size_t>(cycles));
    int64_t t = 0;
    for (int k = 0; k < cycles; ++k) {
        if (k == 10)
            for (auto& s : sims) {
                std::string err;
                s->apply({0, "csp", {"1000000", "1500", "10000"}}, err);
            }
        const auto a = std::chrono::steady_clock::now();
        for (auto& s : sims)
            s->cycle(t, dt_ns);
        const auto b = std::chrono::steady_clock::now();
        per_axis.push_back(
            static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(b - a).count()) / axes);
        t += dt_ns;
    }
    std::sort(per_axis.begin(), per_axis.end());
    const double median = per_axis[per_axis.size() / 2];
    const double p99 = per_axis[std::min(per_axis.size() - 1, per_axis.size() * 99 / 100)];
    std::printf(
        "drive cycle (%lld us simulated, %d axes, %d cycles): median %.0f ns/axis, p99 %.0f ns/axis\n",
        static_cast<long long>(dt_ns / 1000), axes, cycles, median, p99);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"drive-sim: the CiA 402 drive without EtherCAT, through a scripted motion"};
    app.set_version_flag("--version", std::string("drive-sim ") + SOFTECAT_VERSION);
    std::string script_path, csv_path = "drive-sim.csv", png_path;
    double cycle_us = 1000;
    bool do_bench = false, print_demo = false, seed_defaults = false;
    int axes = 1, cycles = 5000;
    app.add_option("-s,--script", script_path, "motion script (default: a built-in demo, see --print-demo)");
    app.add_option("-o,--csv", csv_path, "CSV output")->capture_default_str();
    app.add_option("-p,--png", png_path, "PNG output rendered with gnuplot (default: <csv>.png)");
    app.add_option("-c,--cycle-us", cycle_us, "drive cycle in microseconds")
        ->capture_default_str()
        ->check(CLI::Range(40.0, 100000.0));
    app.add_flag("--bench", do_bench, "print ns per drive cycle per axis (median, p99)");
    app.add_option("--axes", axes, "axes for --bench")->capture_default_str()->check(CLI::Range(1, 64));
    app.add_option("--cycles", cycles, "cycles for --bench")
        ->capture_default_str()
        ->check(CLI::Range(100, 10000000));
    app.add_flag("--print-demo", print_demo, "print the built-in demo script and exit");
    app.add_flag("--seed-defaults", seed_defaults,
                 "start from the seed's defaults instead of the commissioned motor data (torque constant 0)");
    try {
        app.parse(argc, argv);
    } catch (const CLI::Success& e) {  // --help, --version
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::cerr << "drive-sim: " << e.what() << " (drive-sim --help)\n";  // one line
        return 2;  // usage error, as every program of the project
    }

    const auto dt_ns = static_cast<int64_t>(std::llround(cycle_us * 1000.0));
    if (print_demo) {
        std::cout << kDemo;
        return 0;
    }
    if (do_bench) return bench(axes, cycles, dt_ns);

    Script sc;
    std::string err;
    if (script_path.empty()) {
        std::istringstream in(kDemo);
        parse_script(in, sc, err);
    } else {
        std::istringstream in;
        try {  // a regular file of at most 1 MiB, checked before it is read
            in.str(util::read_input_file(script_path, std::size_t{1} << 20, "script"));
        } catch (const util::InputFileError& e) {
            std::cerr << "drive-sim: " << e.what() << "\n";
            return 2;
        }
        if (!parse_script(in, sc, err)) {
            std::cerr << "drive-sim: " << script_path << ": " << err << "\n";
            return 2;
        }
    }
    Sim sim(!seed_defaults);
    std::vector<Sample> samples;
    const auto n = static_cast<int64_t>(sc.end_ms * 1e6 / static_cast<double>(dt_ns));
    samples.reserve(static_cast<std::size_t>(n + 1));
    std::size_t next = 0;
    for (int64_t k = 0; k <= n; ++k) {
        const int64_t t = k * dt_ns;
        const double t_ms = static_cast<double>(t) * 1e-6;
        while (next < sc.steps.size() && sc.steps[next].at_ms <= t_ms + 1e-9) {
            if (!sim.apply(sc.steps[next], err)) {
                std::cerr << "drive-sim: at " << sc.steps[next].at_ms << " ms: " << err << "\n";
                return 2;
            }
            ++next;
        }
        sim.cycle(t, dt_ns);
        samples.push_back(sim.sample(t_ms));
    }
    // "-o -": the CSV goes to standard output (and the summary to stderr); a plot then needs -p and is
    // rendered from a temporary copy of the CSV.
    const bool csv_stdout = csv_path == "-";
    if (csv_stdout) {
        drivesim::write_csv(std::cout, samples);
        if (!std::cout.flush()) {
            std::cerr << "drive-sim: cannot write the CSV to standard output: " << std::strerror(errno)
                      << "\n";
            return 1;
        }
        csv_path = png_path.empty() || png_path == "-" ? "" : png_path + ".csv";
    }
    if (!csv_path.empty() && !drivesim::write_csv(csv_path, samples)) {
        std::cerr << "drive-sim: cannot write " << csv_path << ": " << std::strerror(errno) << "\n";
        return 1;
    }
    const Sample& last = samples.back();
    std::fprintf(
        csv_stdout ? stderr : stdout,
        "%zu samples -> %s; end: position %d inc, velocity %d rpm, statusword 0x%04X, error 0x%04X\n",
        samples.size(), csv_stdout ? "<stdout>" : csv_path.c_str(), last.actual, last.velocity,
        last.statusword, sim.dict().get<uint16_t>(0x603F, 0));
    if (png_path.empty() && !csv_stdout) png_path = csv_path + ".png";
    if (!png_path.empty() && png_path != "-") {  // "-p -": no plot
        const std::string name = script_path.empty() ? std::string("built-in demo")
                                                     : std::filesystem::path(script_path).filename().string();
        char cycle[32];
        std::snprintf(cycle, sizeof cycle, "%g", cycle_us);
        const std::vector<drivesim::Event> events = drivesim::find_events(samples);
        if (!render_png(csv_path, png_path, "drive-sim: " + name + " (" + cycle + " us cycle)", sc.end_ms,
                        events, err)) {
            std::cerr << "drive-sim: " << err << "\n";
            return 1;
        }
        std::fprintf(csv_stdout ? stderr : stdout, "plot -> %s\n", png_path.c_str());
        if (csv_stdout) std::remove(csv_path.c_str());  // the temporary copy
    }
    return 0;
}
