// The topology file of a segment (see slave/topology.hpp).
#include "slave/topology.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

namespace slave {

namespace {

std::vector<std::string_view> split_words(std::string_view line) {
    std::vector<std::string_view> out;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r'))
            ++i;
        std::size_t j = i;
        while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r')
            ++j;
        if (j > i) out.push_back(line.substr(i, j - i));
        i = j;
    }
    return out;
}

// Decimal or 0x-hexadecimal integer in [lo, hi].
bool parse_int(std::string_view s, int64_t lo, int64_t hi, int64_t& out) {
    bool negative = false;
    if (!s.empty() && (s[0] == '-' || s[0] == '+')) {
        negative = s[0] == '-';
        s.remove_prefix(1);
    }
    int base = 10;
    if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
        base = 16;
        s.remove_prefix(2);
    }
    if (s.empty()) return false;
    uint64_t v = 0;
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v, base);
    if (ec != std::errc{} || ptr != s.data() + s.size()) return false;
    if (v > static_cast<uint64_t>(std::numeric_limits<int64_t>::max())) return false;
    const int64_t value = negative ? -static_cast<int64_t>(v) : static_cast<int64_t>(v);
    if (value < lo || value > hi) return false;
    out = value;
    return true;
}

bool parse_double(std::string_view s, double& out) {
    const std::string text(s);
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || errno != 0 || !std::isfinite(v)) return false;
    out = v;
    return true;
}

struct Parser {
    Topology topo;
    std::string base_dir;
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
        if (!parse_int(value, lo, hi, v))
            fail("bad number '" + std::string(value) + "' for " + std::string(key) +
                 " (expected an integer " + std::to_string(lo) + ".." + std::to_string(hi) + ")");
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

    void timing(const std::vector<std::string_view>& w) {
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
        const std::size_t eq = word.find('=');
        if (eq == std::string_view::npos || eq == 0 || eq + 1 == word.size())
            fail("expected KEY=VALUE, got '" + std::string(word) + "'");
        return {word.substr(0, eq), word.substr(eq + 1)};
    }

    void device(const std::vector<std::string_view>& w) {
        if (w.size() < 2 || w[1].find('=') != std::string_view::npos) fail("device: a name is missing");
        TopologyDevice d;
        d.name = std::string(w[1]);
        d.line = line_no;
        if (d.name.find(':') != std::string::npos) fail("device name '" + d.name + "' must not contain ':'");
        int64_t numeric = 0;
        if (parse_int(d.name, 0, std::numeric_limits<int64_t>::max(), numeric))
            fail("device name '" + d.name + "' must not be a number (numbers are device indexes)");
        if (topo.find(d.name) >= 0)
            fail("device '" + d.name + "' declared twice (first at line " +
                 std::to_string(topo.devices[static_cast<std::size_t>(topo.find(d.name))].line) + ")");
        At a;
        for (std::size_t i = 2; i < w.size(); ++i) {
            const auto [key, value] = key_value(w[i]);
            if (key == "config") {
                d.config = resolve(value);
            } else if (key == "at") {
                std::tie(a.parent, a.port) = device_port(key, value);
                a.given = true;
            } else if (key == "port") {
                d.port = static_cast<int>(integer(key, value, 0, esc::kPortCount - 1));
            } else if (key == "ports") {
                d.ports = static_cast<int>(integer(key, value, 2, 4));
                if (d.ports == 3) fail("ports=3: an ESC has 2 or 4 ports");
            } else if (key == "serial") {
                d.serial = static_cast<uint32_t>(integer(key, value, 0, 0xFFFFFFFF));
            } else if (key == "drift-ppm") {
                if (!parse_double(value, d.drift_ppm) || std::fabs(d.drift_ppm) > 1000.0)
                    fail("bad number '" + std::string(value) + "' for drift-ppm (expected -1000..1000)");
            } else if (key == "offset-ns") {
                d.offset_ns = integer(key, value, std::numeric_limits<int64_t>::min() / 2,
                                      std::numeric_limits<int64_t>::max() / 2);
            } else if (key == "cable-ns") {
                d.cable_ns = integer(key, value, 0, 100'000'000);
            } else if (key == "state-dir") {
                d.state_dir = resolve(value);
            } else {
                fail("unknown key '" + std::string(key) +
                     "' (device takes config, at, port, ports, serial, drift-ppm, offset-ns, cable-ns, "
                     "state-dir)");
            }
        }
        if (d.port >= d.ports)
            fail("port=" + std::to_string(d.port) + ": the device has only ports 0.." +
                 std::to_string(d.ports - 1));
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

    void external(const std::vector<std::string_view>& w) {
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
        if (const std::size_t hash = line.find('#'); hash != std::string_view::npos)
            line = line.substr(0, hash);
        const auto w = split_words(line);
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
            if (port >= d.ports)
                fail_at(line, what + ": device '" + d.name + "' has only ports 0.." +
                                  std::to_string(d.ports - 1) + " (ports=4 for a junction)");
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

std::string Topology::where(int line) const {
    return file + ":" + std::to_string(line) + ": ";
}

Topology parse_topology(std::string_view text, const std::string& file, const std::string& base_dir) {
    Parser p;
    p.topo.file = file;
    p.base_dir = base_dir;
    while (!text.empty()) {
        ++p.line_no;
        const std::size_t nl = text.find('\n');
        p.statement(text.substr(0, nl));
        text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
    }
    p.finish();
    return std::move(p.topo);
}

Topology load_topology(const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw TopologyError(file + ": cannot read the topology file: " + std::strerror(errno));
    std::ostringstream text;
    text << in.rdbuf();
    const std::filesystem::path parent = std::filesystem::path(file).parent_path();
    return parse_topology(text.str(), file, parent.string());
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
