// (9) The topology file parser (tools/lib/slave/src/topology.cpp, what `ecat-slave --topology` reads): any
// text. A bad file is a TopologyError naming the file and a line; a good one is a tree the segment can be
// wired from: at most ::slave::kMaxDevices devices with valid, unique names (the state directory rule),
// unique explicit state directories, every parent declared and on an existing, free port, no loop.
#include <set>
#include <string>
#include <string_view>
#include <utility>

#include "fuzz_support.hpp"
#include "harnesses.hpp"
#include "slave/topology.hpp"

namespace fuzz::topology {

int fuzz_one(const uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    ::slave::Topology t;
    try {
        t = ::slave::parse_topology(text, "fuzz.topo", "/base");
    } catch (const ::slave::TopologyError& e) {
        FUZZ_CHECK(std::string_view(e.what()).substr(0, 10) == "fuzz.topo:");
        return 0;
    }
    FUZZ_CHECK(!t.devices.empty() && t.devices.size() <= ::slave::kMaxDevices);
    std::set<std::string> names, dirs;
    std::set<std::pair<int, int>> ports;
    for (std::size_t i = 0; i < t.devices.size(); ++i) {
        const ::slave::TopologyDevice& d = t.devices[i];
        FUZZ_CHECK(!d.name.empty() && d.name.size() <= ::slave::kMaxNameLength);
        for (const char c : d.name)
            FUZZ_CHECK((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                       c == '_' || c == '.' || c == '-');
        FUZZ_CHECK(d.name[0] != '.' && d.name[0] != '-' && d.name[0] != '_');
        FUZZ_CHECK(names.insert(d.name).second);
        FUZZ_CHECK(d.state_dir.empty() || dirs.insert(d.state_dir).second);
        FUZZ_CHECK(d.port_descriptor() == 0x0F ||
                   d.port_descriptor() == 0xFF);  // no esi= callback: 2 or 4 ports
        FUZZ_CHECK(d.has_port(d.port));
        FUZZ_CHECK(ports.emplace(static_cast<int>(i), d.port).second);
        if (i == 0) {
            FUZZ_CHECK(d.parent == -1);
            continue;
        }
        FUZZ_CHECK(d.parent >= 0 && static_cast<std::size_t>(d.parent) < t.devices.size());
        FUZZ_CHECK(t.devices[static_cast<std::size_t>(d.parent)].has_port(d.parent_port));
        FUZZ_CHECK(ports.emplace(d.parent, d.parent_port).second);
        // Follows its parents to the root in fewer steps than there are devices (no loop).
        int p = d.parent;
        std::size_t steps = 0;
        while (p > 0 && steps <= t.devices.size()) {
            p = t.devices[static_cast<std::size_t>(p)].parent;
            ++steps;
        }
        FUZZ_CHECK(p == 0);
        FUZZ_CHECK(t.find(d.name) == static_cast<int>(i));
    }
    if (t.external_device >= 0) {
        FUZZ_CHECK(static_cast<std::size_t>(t.external_device) < t.devices.size());
        FUZZ_CHECK(ports.emplace(t.external_device, t.external_port).second);
    }
    return 0;
}

}  // namespace fuzz::topology
