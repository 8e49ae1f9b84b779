// A segment of soft drives in one process (see device/line.hpp).
#include "device/line.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "device/firmware.hpp"
#include "esc/wire/al.hpp"
#include "util/lex.hpp"

namespace device {

namespace {

bool to_uint(std::string_view s, uint64_t max, uint64_t& out) {
    return util::parse_number<uint64_t>(s, out, 0, max) == util::NumberError::None;
}

bool to_fraction(std::string_view s, double& out) {
    return util::parse_number(s, out, 0.0, 1.0) == util::NumberError::None;
}

bool port_exists(const esc::EscConfig& config, int port) {
    return ((config.port_descriptor >> (2 * port)) & 0x03) != 0;
}

// Longest extra delay on one hop: a second (a hold queue of kHoldSlots frames covers it at 256 frames/s).
constexpr uint64_t kMaxDelayNs = 1'000'000'000;

}  // namespace

struct Line::Unit {
    std::string name;
    std::string log_name;             // "ecat-slave: NAME", the prefix of the device's log lines
    std::unique_ptr<slave::Log> log;  // the device's events, on the segment log's stream
    DeviceOptions options;
    esc::EscConfig esc_config;
    std::unique_ptr<esc::Esc> esc;   // before device: the Device is destroyed first
    std::unique_ptr<Device> device;  // null while powered off
};

Line::Line(const esc::Clock& clock, LineOptions options, slave::ExternalSend send)
    : clock_(clock), options_(std::move(options)), segment_(options_.topology.timing) {
    const slave::Topology& topo = options_.topology;
    units_.reserve(topo.devices.size());
    std::vector<const od::Product*> announced;  // products whose warnings a unit said already
    for (std::size_t i = 0; i < topo.devices.size(); ++i) {
        const slave::TopologyDevice& d = topo.devices[i];
        auto u = std::make_unique<Unit>();
        u->name = d.name;
        u->log_name = "ecat-slave: " + d.name;
        if (options_.log != nullptr)
            u->log = std::make_unique<slave::Log>(options_.log->stream(), options_.log->level(),
                                                  options_.log->colour(), u->log_name);
        u->options = options_.base;
        if (!d.config.empty()) u->options.config_file = d.config;
        if (i < options_.products.size() && options_.products[i]) u->options.product = options_.products[i];
        u->options.state_dir =
            d.state_dir.empty() ? options_.base.state_dir / d.name : std::filesystem::path(d.state_dir);
        if (d.serial) u->options.serial_number = d.serial;
        u->options.events = u->log.get();
        if (const od::Product* p = u->options.product.get()) {
            u->options.announce_product = std::find(announced.begin(), announced.end(), p) == announced.end();
            if (u->options.announce_product) announced.push_back(p);
        }
        u->options.load_sii = true;
        u->esc_config = options_.esc;
        u->esc_config.port_descriptor = d.port_descriptor();
        u->esc_config.clock_drift_ppm = d.drift_ppm;
        u->esc_config.clock_offset_ns = d.offset_ns;
        u->esc_config.thread_safe = false;  // the runtime's thread serves every ESC of the line
        u->esc = std::make_unique<esc::Esc>(u->esc_config, clock_);
        u->device = std::make_unique<Device>(*u->esc, u->options);
        segment_.add(*u->esc);
        units_.push_back(std::move(u));
    }
    for (std::size_t i = 1; i < topo.devices.size(); ++i) {
        const slave::TopologyDevice& d = topo.devices[i];
        segment_.connect(d.parent, d.parent_port, static_cast<int>(i), d.port, d.cable_ns);
    }
    if (send) {
        const int dev =
            topo.external_device >= 0 ? topo.external_device : static_cast<int>(units_.size()) - 1;
        segment_.set_external(dev, topo.external_device >= 0 ? topo.external_port : 1, std::move(send));
    }
    stats_.power_cycles.assign(units_.size(), 0);
    if (!options_.control_path.empty())
        control_ = std::make_unique<ControlSocket>(options_.control_path, options_.control_group);
}

Line::~Line() = default;

void Line::event(slave::LogLevel level, const std::string& text) const {
    if (options_.log != nullptr) options_.log->write(level, text);
}

void Line::poll(uint64_t now_ns) {
    // Each device polled gets the time it is polled at: a pass over many devices takes a while, and a device
    // that compares its ESC's registers (read now) with a stale time would misjudge when its next SYNC0
    // comes. One whose deadline falls due while the pass goes on is skipped; its deadline, now past, brings
    // the runtime straight back to serve it.
    //
    // A device is looked at only when something may be there for it, as the interrupt line of a hardware
    // ESC wakes its controller: its ESC signalled a new event (EscSignals::wake: a frame or a tick raised a
    // masked AL event, a master wrote the EEPROM), its own deadline is due, or its last poll left it not
    // quiet (an event still pending, a mailbox message waiting for SM1, ...; then it is asked on every
    // pass, as before). A device whose only reason not to be quiet is an interrupt line it cannot use (its
    // SMs without the PDI interrupt, as the ESIs of digital IO terminals declare them) reads the registers
    // themselves, as such a controller polls them: it is asked when its ESC's registers changed since its
    // last poll (EscSignals::activity: a frame passed the ESC, or a timer fired), not on every pass; a
    // poll in between would read what the last one left. The others cost a look at the arrays. After a
    // control command, a power change or a caller's access to a device (deadline_known_ false) every
    // device is asked once. A device's deadline changes only in its own poll or through those; frames
    // served meanwhile change ESCs, which wake what they concern.
    const std::size_t n = units_.size();
    if (due_.size() != n) {
        due_.assign(n, 0);
        ask_.assign(n, kEveryPass);
        seen_.assign(n, 0);
    }
    if (!deadline_known_) std::fill(ask_.begin(), ask_.end(), uint8_t{kEveryPass});
    esc::EscSignals* sig = segment_.signals();
    const auto looked_at = [&](std::size_t k, uint64_t t) {
        return sig[k].wake != 0 || due_[k] <= t ||
               !(ask_[k] == kQuiet || (ask_[k] == kOnActivity && sig[k].activity == seen_[k]));
    };
    // The devices this pass will look at (as far as the arrays say now: a frame served during the pass may
    // add some) are asked for first, stage by stage over all of them (Device::prefetch): their state, last
    // touched a cycle ago, comes in with the misses overlapping instead of one device after the other.
    // Changes nothing.
    for (std::size_t k = 0; k < n; ++k)
        if (looked_at(k, now_ns)) __builtin_prefetch(&units_[k]->device);
    for (int stage = 0; stage < 3; ++stage)
        for (std::size_t k = 0; k < n; ++k)
            if (looked_at(k, now_ns) && units_[k]->device) units_[k]->device->prefetch(stage);
    uint64_t now = now_ns;
    bool fresh = true;  // now_ns is still the time: no device polled yet
    for (std::size_t k = 0; k < n; ++k) {
        const bool woken = sig[k].wake != 0;
        if (!looked_at(k, now)) continue;
        sig[k].wake = 0;
        Device* d = units_[k]->device.get();
        if (d == nullptr) {
            ask_[k] = kQuiet;
            due_[k] = std::numeric_limits<uint64_t>::max();
            continue;
        }
        // Woken: polled at once (a poll that finds the device quiet returns at once). Asked or due: the
        // quiet check first, which costs less than a poll when nothing is there after all.
        if (!woken && d->quiet(now)) {
            ask_[k] = kQuiet;
            due_[k] = d->next_deadline_ns();
            continue;
        }
        if (!fresh) now = std::max(now, clock_.now_ns());
        d->poll(now);
        ++stats_.polls;
        seen_[k] = sig[k].activity;  // a poll's own PDI accesses do not count
        ask_[k] = d->quiet(now) ? kQuiet : d->quiet(now, true) ? kOnActivity : kEveryPass;
        due_[k] = d->next_deadline_ns();
        fresh = false;
        // Frames that came during this device's work are answered before the next device's (the runtime's
        // FrameService): a frame never waits for a pass over the whole line.
        serve_frames();
    }
    deadline_known_ = true;
}

// The earliest device deadline, or now (0) when an ESC signalled an event after its device was looked at
// (a frame served during the pass, the runtime's ticks after it).
uint64_t Line::next_deadline_ns() const {
    if (!deadline_known_) {
        uint64_t deadline = std::numeric_limits<uint64_t>::max();
        for (const auto& u : units_)
            if (u->device) deadline = std::min(deadline, u->device->next_deadline_ns());
        return deadline;
    }
    const std::size_t n = units_.size();
    const esc::EscSignals* sig = segment_.signals();
    uint64_t deadline = std::numeric_limits<uint64_t>::max();
    for (std::size_t k = 0; k < n; ++k) {
        if (sig[k].wake != 0 && units_[k]->device) return 0;
        deadline = std::min(deadline, due_[k]);
    }
    return deadline;
}

void Line::on_control(uint64_t /*now_ns*/) {
    deadline_known_ = false;
    if (control_) control_->service([this](std::string_view line) { return apply(line); });
}

int Line::find(std::string_view name_or_index) const {
    for (std::size_t i = 0; i < units_.size(); ++i)
        if (units_[i]->name == name_or_index) return static_cast<int>(i);
    uint64_t index = 0;
    if (!units_.empty() && to_uint(name_or_index, units_.size() - 1, index)) return static_cast<int>(index);
    return -1;
}

const std::string& Line::name(int device) const {
    return units_.at(static_cast<std::size_t>(device))->name;
}

bool Line::powered(int device) const {
    return units_.at(static_cast<std::size_t>(device))->device != nullptr;
}

Device* Line::device(int index) {
    deadline_known_ = false;  // the caller may change the device
    return units_.at(static_cast<std::size_t>(index))->device.get();
}

esc::Esc& Line::esc(int index) {
    return *units_.at(static_cast<std::size_t>(index))->esc;
}

void Line::power(int index, bool on) {
    deadline_known_ = false;
    Unit& u = *units_.at(static_cast<std::size_t>(index));
    if (on == (u.device != nullptr)) return;
    if (!on) {
        // Off: nothing passes the device any more and its neighbours lose their links; the firmware and the
        // ESC go (what they stored on disk stays). A blank ESC holds the device's place in the segment.
        segment_.set_power(index, false);
        u.device.reset();
        auto blank = std::make_unique<esc::Esc>(u.esc_config, clock_);
        segment_.replace(index, *blank);
        u.esc = std::move(blank);
        event(slave::LogLevel::Warn, "power: " + u.name + " (device " + std::to_string(index) +
                                         ") switched off; its neighbours lose their links");
        return;
    }
    // On: a fresh ESC and firmware on the same state directory, as after switching a drive on (Init).
    auto fresh = std::make_unique<esc::Esc>(u.esc_config, clock_);
    auto device = std::make_unique<Device>(*fresh, u.options);  // throws: the device stays off
    segment_.replace(index, *fresh);
    u.esc = std::move(fresh);
    u.device = std::move(device);
    segment_.set_power(index, true);
    ++stats_.power_cycles[static_cast<std::size_t>(index)];
    event(slave::LogLevel::Warn, "power: " + u.name + " (device " + std::to_string(index) +
                                     ") switched on, in Init with a fresh ESC (power cycle " +
                                     std::to_string(stats_.power_cycles[static_cast<std::size_t>(index)]) +
                                     ")");
}

std::string Line::segment_text() const {
    std::ostringstream s;
    s << "ok segment " << units_.size() << " devices";
    for (std::size_t i = 0; i < units_.size(); ++i) {
        const Unit& u = *units_[i];
        s << "\ndevice " << i << ' ' << u.name << " power " << (u.device ? "on" : "off");
        if (u.device) s << " state " << esc::al_state_name(u.device->stack().state());
        s << " links";
        for (int p = 0; p < esc::kPortCount; ++p) {
            s << ' ' << p << ':';
            if (!port_exists(u.esc_config, p))
                s << '-';
            else
                s << (u.esc->link(p) ? "up" : "down");
        }
    }
    for (std::size_t k = 0; k < units_.size(); ++k) {
        const esc::HopFaults& f = segment_.hop_faults(static_cast<int>(k));
        const esc::HopStats& h = segment_.hop_stats(static_cast<int>(k));
        s << "\nhop " << k << " drop " << f.drop << " corrupt " << f.corrupt << " delay " << f.extra_delay_ns
          << " frames " << h.frames << " dropped " << h.dropped << " corrupted " << h.corrupted;
    }
    return s.str();
}

std::string Line::apply(std::string_view line) {
    deadline_known_ = false;  // a device command may change what a device waits for
    const std::string_view text = line;
    std::vector<std::string> w;
    std::size_t third = 0;  // where the third word begins (slave <k> <command ...>)
    try {
        for (util::Word& word : util::split(text)) {
            if (w.size() == 2) third = word.begin;
            w.push_back(std::move(word.text));
        }
    } catch (const util::LexError& e) {
        return std::string("error: ") + e.what();
    }
    if (w.empty()) return {};
    const std::string_view cmd = w[0];
    const int hops = static_cast<int>(units_.size());
    auto device_arg = [this](std::string_view arg) { return find(arg); };
    auto unknown_device = [](std::string_view arg) {
        return "error: no device '" + std::string(arg) + "' (a name from the topology or an index from 0)";
    };
    try {
        if (cmd == "slave") {
            if (w.size() < 3) return "error: usage: slave <index|name> <command>";
            const int k = device_arg(w[1]);
            if (k < 0) return unknown_device(w[1]);
            Device* d = device(k);
            if (d == nullptr) return "error: " + name(k) + " is powered off";
            // The rest of the line after the device argument, as typed.
            return ControlSocket::apply(*d, text.substr(third));
        }
        if (cmd == "link") {
            bool up = false;
            uint64_t port = 0;
            if (w.size() != 4 || !to_uint(w[2], esc::kPortCount - 1, port) ||
                (w[3] != "up" && w[3] != "down"))
                return "error: usage: link <index|name> <port 0-3> up|down";
            up = w[3] == "up";
            const int k = device_arg(w[1]);
            if (k < 0) return unknown_device(w[1]);
            if (!port_exists(units_[static_cast<std::size_t>(k)]->esc_config, static_cast<int>(port)))
                return "error: " + name(k) + " has no port " + std::to_string(port);
            segment_.set_cable(k, static_cast<int>(port), up);
            ++stats_.link_changes;
            event(up ? slave::LogLevel::Info : slave::LogLevel::Warn,
                  "link: cable at port " + std::to_string(port) + " of " + name(k) +
                      (up ? " plugged" : " pulled"));
            return "ok link " + name(k) + ' ' + std::to_string(port) + (up ? " up" : " down");
        }
        if (cmd == "drop" || cmd == "corrupt" || cmd == "delay") {
            uint64_t hop = 0;
            if (w.size() != 3 || hops == 0 || !to_uint(w[1], static_cast<uint64_t>(hops - 1), hop))
                return "error: usage: " + std::string(cmd) + " <hop 0-" + std::to_string(hops - 1) + "> " +
                       (cmd == "delay" ? "<ns>" : "<fraction 0-1>");
            esc::HopFaults f = segment_.hop_faults(static_cast<int>(hop));
            std::string what;
            if (cmd == "delay") {
                uint64_t ns = 0;
                if (!to_uint(w[2], kMaxDelayNs, ns))
                    return "error: usage: delay <hop> <ns 0-" + std::to_string(kMaxDelayNs) + ">";
                f.extra_delay_ns = static_cast<uint32_t>(ns);
                f.hold_ns = ns;
                what = std::to_string(ns) + " ns";
            } else {
                double fraction = 0;
                if (!to_fraction(w[2], fraction))
                    return "error: usage: " + std::string(cmd) + " <hop> <fraction 0-1>";
                (cmd == "drop" ? f.drop : f.corrupt) = fraction;
                what = std::string(w[2]) + " of the frames";
            }
            segment_.set_hop_faults(static_cast<int>(hop), f);
            ++stats_.fault_changes;
            event(slave::LogLevel::Warn, "fault: " + std::string(cmd) + ' ' + what + " on hop " +
                                             std::to_string(hop) + " (the cable into " +
                                             name(static_cast<int>(hop)) + ")");
            return "ok " + std::string(cmd) + " hop " + std::to_string(hop) + ' ' + std::string(w[2]);
        }
        if (cmd == "clear" && w.size() == 1) {
            for (int k = 0; k < hops; ++k)
                segment_.set_hop_faults(k, esc::HopFaults{});
            ++stats_.fault_changes;
            event(slave::LogLevel::Info, "fault: all hop faults cleared");
            return "ok clear";
        }
        if (cmd == "power") {
            if (w.size() != 3 || (w[2] != "on" && w[2] != "off" && w[2] != "cycle"))
                return "error: usage: power <index|name> off|on|cycle";
            const int k = device_arg(w[1]);
            if (k < 0) return unknown_device(w[1]);
            if (w[2] == "off" || w[2] == "cycle") power(k, false);
            if (w[2] == "on" || w[2] == "cycle") power(k, true);
            return "ok power " + name(k) + ' ' + std::string(w[2]);
        }
        if (cmd == "segment" && w.size() == 1) return segment_text();
    } catch (const std::exception& e) {
        return std::string("error: ") + e.what();
    }
    Device* d0 = units_.empty() ? nullptr : device(0);
    if (d0 == nullptr)
        return "error: " + (units_.empty() ? std::string("no device") : name(0)) + " is powered off";
    std::string answer = ControlSocket::apply(*d0, text);
    if (answer.rfind("error: unknown command", 0) == 0)
        answer.insert(answer.size() - 1, ", slave, link, drop, corrupt, delay, power, clear, segment");
    return answer;
}

void Line::report(std::ostream& out) const {
    if (!units_.empty() && units_[0]->device) report_device(out, *units_[0]->device);
    out << "segment.devices " << units_.size() << '\n'
        << "segment.link_changes " << stats_.link_changes << '\n'
        << "segment.fault_changes " << stats_.fault_changes << '\n';
    for (std::size_t k = 0; k < units_.size(); ++k) {
        const esc::HopStats& h = segment_.hop_stats(static_cast<int>(k));
        out << "segment.hop" << k << ".frames " << h.frames << '\n'
            << "segment.hop" << k << ".dropped " << h.dropped << '\n'
            << "segment.hop" << k << ".corrupted " << h.corrupted << '\n';
    }
    for (std::size_t k = 0; k < units_.size(); ++k) {
        const Unit& u = *units_[k];
        out << "segment.device" << k << ".power_cycles " << stats_.power_cycles[k] << '\n'
            << "segment.device" << k << ".powered " << (u.device ? 1 : 0) << '\n'
            << "segment.device" << k << ".frames_processed " << u.esc->stats().frames_processed << '\n';
        if (u.device) out << "segment.device" << k << ".drive_cycles " << u.device->stats().cycles << '\n';
    }
    // Every device's own figures (ecat.*, device.*) under its prefix: segment.device<k>.ecat.frames ...
    for (std::size_t k = 0; k < units_.size(); ++k) {
        if (!units_[k]->device) continue;
        std::ostringstream own;
        report_device(own, *units_[k]->device);
        std::istringstream lines(own.str());
        for (std::string line; std::getline(lines, line);)
            out << "segment.device" << k << '.' << line << '\n';
    }
}

}  // namespace device
