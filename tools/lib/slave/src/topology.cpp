// The topology file of a segment (see slave/topology.hpp).
#include "slave/topology.hpp"

#include <filesystem>
#include <limits>
#include <map>

#include "util/input_file.hpp"
#include "util/lex.hpp"

namespace slave {

namespace {

// Decimal or 0x-hexadecimal integer in [lo, hi] (the one lexer's rule, util/lex.hpp).
bool parse_int(std::string_view s, int64_t lo, int64_t hi, int64_t& out) {
    return util::parse_number(s, out, lo, hi) == util::NumberError::None;
}

// A device name: 1..kMaxNameLength characters of [A-Za-z0-9_.-], beginning with a letter or a digit, not
// a number. It names the device's state directory under --state-dir: no '/', no "." or "..", nothing that
// leads out of it.
std::string name_error(std::string_view name) {
    if (name.empty() || name.size() > kMaxNameLength)
        return "must have 1.." + std::to_string(kMaxNameLength) + " characters";
    const auto alnum = [](char c) {
        return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    };
    if (!alnum(name[0])) return "must begin with a letter or a digit";
    for (const char c : name)
        if (!alnum(c) && c != '_' && c != '.' && c != '-')
            return "may hold letters, digits, '_', '.' and '-' only (it names the state directory)";
    int64_t numeric = 0;
    if (parse_int(name, 0, std::numeric_limits<int64_t>::max(), numeric))
        return "must not be a number (numbers are device indexes)";
    return {};
}

struct Parser {
    Topology topo;
    std::string base_dir;
    PortsOfEsi ports_of_esi;
    int line_no = 0;
    // Unresolved at= of each device (name, port, line); resolved when the whole file is read, so a device
    // may be plugged into one declared further down.
    struct At {
        std::string parent;
        int port = 1;
        bool given = false;
    };
    std::vector<At> at;

    [[noreturn]] void fail(const std::string& message) const {
        throw TopologyError(topo.where(line_no) + message);
    }
    [[noreturn]] void fail_at(int line, const std::string& message) const {
        throw TopologyError(topo.where(line) + message);
    }

    std::string resolve(std::string_view path) const {
        const std::filesystem::path p{std::string(path)};
        if (p.is_absolute() || base_dir.empty()) return p.string();
        return (std::filesystem::path(base_dir) / p).lexically_normal().string();
    }

    int64_t integer(std::string_view key, std::string_view value, int64_t lo, int64_t hi) const {
        int64_t v = 0;
        if (util::parse_number(value, v, lo, hi) != util::NumberError::None)
            fail(util::number_message(key, value, lo, hi));
        return v;
    }

    // "NAME:PORT" -> name and port number.
    std::pair<std::string, int> device_port(std::string_view key, std::string_view value) const {
        const std::size_t colon = value.rfind(':');
        if (colon == std::string_view::npos || colon == 0)
            fail(std::string(key) + "='" + std::string(value) + "': expected DEVICE:PORT");
        return {std::string(value.substr(0, colon)),
                static_cast<int>(integer(key, value.substr(colon + 1), 0, esc::kPortCount - 1))};
    }

    void timing(const std::vector<std::string>& w) {
        for (std::size_t i = 1; i < w.size(); ++i) {
            const auto [key, value] = key_value(w[i]);
            const auto v = static_cast<uint32_t>(integer(key, value, 0, 100'000'000));
            if (key == "processing-ns")
                topo.timing.processing_delay_ns = v;
            else if (key == "forwarding-ns")
                topo.timing.forwarding_delay_ns = v;
            else if (key == "cable-ns")
                topo.timing.cable_delay_ns = v;
            else
                fail("unknown key '" + std::string(key) +
                     "' (timing takes processing-ns, forwarding-ns, cable-ns)");
        }
    }

    std::pair<std::string_view, std::string_view> key_value(std::string_view word) const {
        const auto kv = util::key_value(word);
        if (!kv) fail("expected KEY=VALUE, got '" + std::string(word) + "'");
        return *kv;
    }

    void device(const std::vector<std::string>& w) {
        if (w.size() < 2 || w[1].find('=') != std::string_view::npos) fail("device: a name is missing");
        if (topo.devices.size() >= kMaxDevices)
            fail("more than " + std::to_string(kMaxDevices) + " devices (the limit of a segment)");
        TopologyDevice d;
        d.name = w[1];
        d.line = line_no;
        if (const std::string e = name_error(d.name); !e.empty()) fail("device name '" + d.name + "' " + e);
        if (topo.find(d.name) >= 0)
            fail("device '" + d.name + "' declared twice (first at line " +
                 std::to_string(topo.devices[static_cast<std::size_t>(topo.find(d.name))].line) + ")");
        At a;
        for (std::size_t i = 2; i < w.size(); ++i) {
            const auto [key, value] = key_value(w[i]);
            if (key == "config") {
                d.config = resolve(value);
            } else if (key == "esi") {
                d.esi = resolve(value);
            } else if (key == "device") {
                d.device_spec = std::string(value);
            } else if (key == "at") {
                std::tie(a.parent, a.port) = device_port(key, value);
                a.given = true;
            } else if (key == "port") {
                d.port = static_cast<int>(integer(key, value, 0, esc::kPortCount - 1));
            } else if (key == "ports") {
                const auto ports = integer(key, value, 2, 4);
                if (ports == 3) fail("ports=3: an ESC has 2 or 4 ports");
                d.descriptor = ports == 4 ? 0xFF : 0x0F;
                d.ports_given = true;
            } else if (key == "serial") {
                d.serial = static_cast<uint32_t>(integer(key, value, 0, 0xFFFFFFFF));
            } else if (key == "drift-ppm") {
                if (util::parse_number(value, d.drift_ppm, -1000.0, 1000.0) != util::NumberError::None)
                    fail(util::number_message("drift-ppm", value, -1000.0, 1000.0));
            } else if (key == "offset-ns") {
                d.offset_ns = integer(key, value, std::numeric_limits<int64_t>::min() / 2,
                                      std::numeric_limits<int64_t>::max() / 2);
            } else if (key == "cable-ns") {
                d.cable_ns = integer(key, value, 0, 100'000'000);
            } else if (key == "state-dir") {
                d.state_dir = resolve(value);
                for (const TopologyDevice& o : topo.devices)
                    if (o.state_dir == d.state_dir)
                        fail("state-dir=" + std::string(value) + ": also the state directory of '" + o.name +
                             "' (line " + std::to_string(o.line) + "); each device needs its own");
            } else {
                fail("unknown key '" + std::string(key) +
                     "' (device takes config, esi, device, at, port, ports, serial, drift-ppm, offset-ns, "
                     "cable-ns, state-dir)");
            }
        }
        if (!d.device_spec.empty() && d.esi.empty()) fail("device=" + d.device_spec + ": without esi=FILE");
        if (!d.esi.empty() && !d.config.empty())
            fail(
                "esi= and config= together: config= configures the built-in drive, esi= serves another "
                "device");
        if (!d.esi.empty() && !d.ports_given && ports_of_esi) {
            try {
                d.descriptor = ports_of_esi(d);
            } catch (const std::exception& e) {
                fail("device " + d.name + ": " + e.what());
            }
            if (d.descriptor == 0) fail("device " + d.name + ": its ESI declares no port");
            d.ports_from_esi = true;
        }
        if (!d.has_port(d.port))
            fail("port=" + std::to_string(d.port) + ": the device has only ports " + d.port_list());
        if (topo.devices.empty()) {
            if (a.given) fail("the first device is the root (its port 0 faces the master); it takes no at=");
            if (d.port != 0) fail("the first device is the root: it faces the master with port 0");
        } else if (!a.given) {
            a.parent = topo.devices.back().name;  // a line: the previous device's port 1
            a.port = 1;
        }
        topo.devices.push_back(std::move(d));
        at.push_back(std::move(a));
    }

    void external(const std::vector<std::string>& w) {
        if (w.size() != 2) fail("usage: external DEVICE:PORT");
        if (topo.external_line != 0)
            fail("external declared twice (first at line " + std::to_string(topo.external_line) + ")");
        auto [name, port] = device_port("external", w[1]);
        ext_name = std::move(name);
        topo.external_port = port;
        topo.external_line = line_no;
    }
    std::string ext_name;

    void statement(std::string_view line) {
        std::vector<std::string> w;
        try {
            for (util::Word& word : util::split(line))
                w.push_back(std::move(word.text));
        } catch (const util::LexError& e) {
            fail(e.what());
        }
        if (w.empty()) return;
        if (w[0] == "timing")
            timing(w);
        else if (w[0] == "device")
            device(w);
        else if (w[0] == "external")
            external(w);
        else
            fail("unknown statement '" + std::string(w[0]) + "' (timing, device, external)");
    }

    // at= resolved, ports checked, loops found.
    void finish() {
        if (topo.devices.empty()) fail_at(line_no, "no device declared");
        // Which device/port is taken by whom (the line that took it).
        std::map<std::pair<int, int>, int> used;
        auto take = [&](int dev, int port, int line, const std::string& what) {
            const TopologyDevice& d = topo.devices[static_cast<std::size_t>(dev)];
            if (!d.has_port(port))
                fail_at(line, what + ": device '" + d.name + "' has only ports " + d.port_list() +
                                  (d.ports_from_esi ? " (its ESI's Physics; ports=4 for a junction)"
                                                    : " (ports=4 for a junction)"));
            const auto [it, fresh] = used.emplace(std::make_pair(dev, port), line);
            if (!fresh)
                fail_at(line, what + ": port " + std::to_string(port) + " of '" + d.name +
                                  "' used twice (also at line " + std::to_string(it->second) + ")");
        };
        for (std::size_t i = 0; i < topo.devices.size(); ++i) {
            TopologyDevice& d = topo.devices[i];
            take(static_cast<int>(i), d.port, d.line, "port=" + std::to_string(d.port));
            if (i == 0) continue;
            const int parent = topo.find_name(at[i].parent);
            if (parent < 0)
                fail_at(d.line, "at=" + at[i].parent + ":" + std::to_string(at[i].port) +
                                    ": unknown device '" + at[i].parent + "'");
            if (parent == static_cast<int>(i))
                fail_at(d.line, "at=: device '" + d.name + "' plugged into itself (a loop)");
            d.parent = parent;
            d.parent_port = at[i].port;
        }
        for (std::size_t i = 1; i < topo.devices.size(); ++i) {
            const TopologyDevice& d = topo.devices[i];
            take(d.parent, d.parent_port, d.line,
                 "at=" + topo.devices[static_cast<std::size_t>(d.parent)].name + ":" +
                     std::to_string(d.parent_port));
            // Follow the parents: a tree reaches the root in fewer steps than there are devices.
            int p = d.parent;
            for (std::size_t steps = 0; p > 0; ++steps) {
                if (steps > topo.devices.size() || p == static_cast<int>(i))
                    fail_at(d.line, "device '" + d.name +
                                        "' is part of a loop (follow at= from here: it never reaches '" +
                                        topo.devices[0].name + "')");
                p = topo.devices[static_cast<std::size_t>(p)].parent;
            }
        }
        if (topo.external_line != 0) {
            topo.external_device = topo.find_name(ext_name);
            if (topo.external_device < 0)
                fail_at(topo.external_line, "external " + ext_name + ":" +
                                                std::to_string(topo.external_port) + ": unknown device '" +
                                                ext_name + "'");
            take(topo.external_device, topo.external_port, topo.external_line, "external");
        }
    }
};

}  // namespace

int Topology::find_name(std::string_view name) const {
    for (std::size_t i = 0; i < devices.size(); ++i)
        if (devices[i].name == name) return static_cast<int>(i);
    return -1;
}

int Topology::find(std::string_view name_or_index) const {
    if (const int i = find_name(name_or_index); i >= 0) return i;
    int64_t index = 0;
    if (parse_int(name_or_index, 0, static_cast<int64_t>(devices.size()) - 1, index))
        return static_cast<int>(index);
    return -1;
}

std::string TopologyDevice::port_list() const {
    std::string s;
    int n = 0;  // ports 0..n-1 all there
    while (n < 4 && has_port(n))
        ++n;
    bool contiguous = true;
    for (int p = n; p < 4; ++p)
        contiguous = contiguous && !has_port(p);
    if (contiguous && n > 1) return "0.." + std::to_string(n - 1);
    for (int p = 0; p < 4; ++p)
        if (has_port(p)) s += (s.empty() ? "" : ", ") + std::to_string(p);
    return s;
}

std::string Topology::where(int line) const {
    return file + ":" + std::to_string(line) + ": ";
}

Topology parse_topology(std::string_view text, const std::string& file, const std::string& base_dir,
                        const PortsOfEsi& ports_of_esi) {
    Parser p;
    p.topo.file = file;
    p.base_dir = base_dir;
    p.ports_of_esi = ports_of_esi;
    while (!text.empty()) {
        ++p.line_no;
        const std::size_t nl = text.find('\n');
        p.statement(text.substr(0, nl));
        text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
    }
    p.finish();
    return std::move(p.topo);
}

Topology load_topology(const std::string& file, const PortsOfEsi& ports_of_esi) {
    std::string text;
    try {
        text = util::read_input_file(file, kMaxTopologyBytes, "topology file");
    } catch (const util::InputFileError& e) {
        throw TopologyError(e.what());
    }
    const std::filesystem::path parent = std::filesystem::path(file).parent_path();
    return parse_topology(text, file, parent.string(), ports_of_esi);
}

Topology line_topology(int count) {
    Topology t;
    t.file = "--slaves";
    for (int k = 1; k <= count; ++k) {
        TopologyDevice d;
        d.name = "drive" + std::to_string(k);
        d.serial = static_cast<uint32_t>(k);
        d.parent = k - 2;
        d.parent_port = 1;
        t.devices.push_back(std::move(d));
    }
    return t;
}

}  // namespace slave
