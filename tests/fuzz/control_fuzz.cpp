// (8) The control command parser (tools/lib/device: control.cpp and line.cpp, what `ecat-slave --control`
// executes): any text, one command per line, applied to a segment of two soft drives that lives for the
// whole run (built once: the commands' effects accumulate as they would on a running slave). Every line is
// answered "" (blank or comment), "ok ..." or "error: ..."; the devices keep running between lines; the
// environment never holds a non-finite position.
#include <stdlib.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "device/line.hpp"
#include "esc/clock.hpp"
#include "fuzz_support.hpp"
#include "harnesses.hpp"
#include "slave/topology.hpp"

namespace fuzz::control {
namespace {

struct Rig {
    ScratchDir scratch;
    const std::filesystem::path& dir = scratch.path;
    esc::ManualClock clock;
    std::unique_ptr<device::Line> line;
    Rig() {
        clock.set(1'000'000'000);
        device::LineOptions o;
        o.topology = ::slave::line_topology(2);
        for (::slave::TopologyDevice& d : o.topology.devices)
            d.state_dir = (dir / d.name).string();
        o.base.state_dir = dir;
        line = std::make_unique<device::Line>(clock, std::move(o));
    }
    ~Rig() { line.reset(); }  // the devices before their directory
};

Rig& rig() {
    static Rig r;
    return r;
}

}  // namespace

int fuzz_one(const uint8_t* data, std::size_t size) {
    Rig& r = rig();
    std::string_view text(reinterpret_cast<const char*>(data), size);
    int lines = 0;
    while (!text.empty() && lines < 64) {  // a datagram's lines (a 4 KiB datagram holds a few hundred)
        const std::size_t nl = text.find('\n');
        const std::string answer = r.line->apply(text.substr(0, nl));
        FUZZ_CHECK(answer.empty() || answer.rfind("ok", 0) == 0 || answer.rfind("error: ", 0) == 0);
        text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
        ++lines;
        r.clock.advance(100'000);
        r.line->poll(r.clock.now_ns());
    }
    for (int k = 0; k < 2; ++k) {
        device::Device* d = r.line->device(k);
        if (d == nullptr) continue;
        const auto& env = d->environment();
        for (const double v :
             {env.negative_limit, env.positive_limit, env.home_from, env.home_to, env.stop_lo, env.stop_hi})
            FUZZ_CHECK(std::isnan(v) || std::isfinite(v));
    }
    return 0;
}

}  // namespace fuzz::control
