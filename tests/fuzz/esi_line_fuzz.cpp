// (13) The slave harness's frames against a line of devices built from ESI files, as `ecat-slave --topology`
// with esi= lines serves them: every device of every example ESI (esi/examples: a coupler without mailbox,
// digital and analog IO terminals, a modular device, a CiA 402 drive that is not the MAXPOS, a device with
// its own EEPROM image, an ISO-8859-1 file), each on its own ESC in one device::Line over an esc::Segment.
// Input: the slave harness's format, [time byte][16-bit length][frame]; the time byte moves the clock
// (10 us steps), the frame walks the line from the master's side, then every device runs, as the runtime
// does. Checked: nothing crashes (ASan, UBSan), every device's AL state is one of the five.
// Per input: the products (read from the files once) are kept; the line (ESCs, devices) is built afresh on
// emptied state directories, so every finding replays on its own.
#include <algorithm>
#include <filesystem>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "device/device.hpp"
#include "device/line.hpp"
#include "esc/clock.hpp"
#include "esi/device/product.hpp"
#include "esi/esi_reader.hpp"
#include "fuzz_support.hpp"
#include "harnesses.hpp"
#include "slave/log.hpp"
#include "slave/topology.hpp"

#ifndef SOFTECAT_ESI_EXAMPLES
#error "SOFTECAT_ESI_EXAMPLES (the folder of the example ESI files) must be defined"
#endif

namespace fuzz::esi_line {
namespace {

struct Prototype {
    ScratchDir scratch;  // the line's state directories, emptied for every input
    const std::filesystem::path& dir = scratch.path;
    std::vector<std::shared_ptr<const od::Product>> products;
    Prototype() {
        std::vector<std::filesystem::path> files;
        for (const auto& e : std::filesystem::directory_iterator(SOFTECAT_ESI_EXAMPLES))
            if (e.path().extension() == ".xml") files.push_back(e.path());
        std::sort(files.begin(), files.end());  // a stable line order, whatever the directory's order
        for (const auto& f : files) {
            const esi::EsiFile file = esi::read_esi_file(f.string());
            for (const esi::EsiDevice& d : file.devices)
                products.push_back(std::make_shared<const od::Product>(esi::load_product(file, d)));
        }
        if (products.empty()) finding("no example ESI device in " SOFTECAT_ESI_EXAMPLES);
    }
};

Prototype& prototype() {
    static Prototype p;
    return p;
}

// The devices' warnings (the products' "declared but not emulated" lines, every build) and events go nowhere:
// a line per input on stderr would cost more than the input.
std::ostream& discard() {
    static std::ostream null(nullptr);
    return null;
}
::slave::Log& quiet_log() {
    static ::slave::Log log(discard(), ::slave::LogLevel::Error);
    return log;
}

}  // namespace

int fuzz_one(const uint8_t* data, std::size_t size) {
    Prototype& proto = prototype();
    esc::ManualClock clock;
    clock.set(1'000'000'000);
    device::LineOptions o;
    o.topology = ::slave::line_topology(static_cast<int>(proto.products.size()));
    for (::slave::TopologyDevice& d : o.topology.devices) {
        const std::filesystem::path sd = proto.dir / d.name;
        std::error_code ec;
        std::filesystem::remove_all(sd, ec);  // nothing a former input stored carries over
        d.state_dir = sd.string();
    }
    o.base.state_dir = proto.dir;
    o.base.log = &discard();
    o.base.events = &quiet_log();
    o.log = &quiet_log();
    o.products = proto.products;
    device::Line line(clock, std::move(o));
    line.poll(clock.now_ns());

    for_each_frame(data, size, [&](uint8_t dt, std::vector<uint8_t>& frame) {
        clock.advance(uint64_t{dt} * 10'000);
        line.poll(clock.now_ns());
        (void)line.segment().walk(frame, clock.now_ns());
        line.poll(clock.now_ns());
        for (std::size_t k = 0; k < line.size(); ++k) {
            const device::Device* d = line.device(static_cast<int>(k));
            FUZZ_CHECK(d != nullptr);  // nothing here switches a device off
            const auto s = static_cast<uint8_t>(d->stack().state());
            FUZZ_CHECK(s == 1 || s == 2 || s == 3 || s == 4 || s == 8);
        }
    });
    return 0;
}

}  // namespace fuzz::esi_line
