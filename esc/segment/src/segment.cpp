// A segment of ESCs in one process (esc/segment.hpp): the wiring, the walk of a frame through the ESCs'
// ports, and the faults of the cables and devices.
//
// The walk is iterative: its whole state is "the frame is arriving at port P of device D at virtual time T"
// (the topology is a tree and each ESC decides where the frame goes next through Esc::receive()), so a walk
// needs no stack of its own and resume() restarts it at the external port. Nothing is allocated per frame.
#include "esc/segment.hpp"
#include "util/strfmt.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace esc {

namespace {

constexpr int kPortOrder[kPortCount] = {0, 3, 1, 2};  // the frame processing order of an ESC's ports
constexpr int order_index(int port) {
    return port == 0 ? 0 : port == 3 ? 1 : port == 1 ? 2 : 3;
}

// splitmix64 (a fixed-increment generator with a strong output mix): small, fast, deterministic.
uint64_t splitmix(uint64_t& state) {
    uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}
double uniform(uint64_t& state) {
    return static_cast<double>(splitmix(state) >> 11) * 0x1.0p-53;
}

std::string where(int device, int port) {
    return "device " + std::to_string(device) + " port " + std::to_string(port);
}

}  // namespace

struct Segment::Impl {
    struct Port {
        int peer = -1;  // device at the other end of the cable, -1: none
        int peer_port = -1;
        uint64_t delay_ns = 0;  // the cable's propagation delay, each direction
        bool cable_up = true;   // false: pulled (set_cable)
        bool down = false;      // the peer is this device's child (the cable is the peer's hop)
    };
    struct Device {
        Esc* esc = nullptr;
        uint8_t descriptor = 0;  // port descriptor 0x0007 of the ESC
        bool powered = true;
        int parent = -1;   // -1: the root, or not (yet) connected to the root
        int up_port = -1;  // port towards the master; the root: 0; -1 while not connected
        Port ports[kPortCount];
        bool implements(int p) const { return ((descriptor >> (2 * p)) & 0x3) != 0; }
    };
    struct Hop {
        HopFaults faults;
        HopStats stats;
        double drop_per_crossing = 0.0;  // 1 - sqrt(1 - drop): two crossings lose `drop` of the frames
        uint64_t rng = 0;
    };

    SegmentTiming timing;
    std::vector<Device> devs;
    std::vector<EscSignals> signals;  // one per device, side by side (Segment::signals())
    std::vector<Hop> hops;            // hops[k]: the cable into device k from upstream
    // ahead[k]: the device whose processing unit a frame meets after k's (order()), -1 after the last. A
    // hint for the walk's prefetching (Esc::prefetch), refreshed when the wiring or a link changes here; a
    // stale one (a master changed a loop) costs speed, never a result.
    std::vector<int> ahead;
    bool root_cable_up = true;
    int ext_dev = -1;
    int ext_port = -1;
    std::function<void(std::span<const uint8_t>)> ext_send;
    bool ext_carrier = true;
    bool ext_cable_up = true;

    // ---- setup ---------------------------------------------------------------------------------------
    void check_device(int d, const char* fn) const {
        if (d < 0 || static_cast<std::size_t>(d) >= devs.size())
            throw std::invalid_argument(std::string("Segment::") + fn + ": unknown device " +
                                        std::to_string(d) + " (the segment has " +
                                        std::to_string(devs.size()) + " devices)");
    }
    void check_port(int d, int p, const char* fn) const {
        check_device(d, fn);
        if (p < 0 || p >= kPortCount)
            throw std::invalid_argument(std::string("Segment::") + fn + ": " + where(d, p) +
                                        ": port out of range 0.." + std::to_string(kPortCount - 1));
        if (!devs[d].implements(p)) {
            throw std::invalid_argument(
                std::string("Segment::") + fn + ": " + where(d, p) +
                util::strprintf(": the ESC does not implement this port (port descriptor "
                                "0x%02X)",
                                devs[d].descriptor));
        }
    }
    void check_hop(int hop, const char* fn) const {
        if (hop < 0 || static_cast<std::size_t>(hop) >= hops.size())
            throw std::invalid_argument(std::string("Segment::") + fn + ": unknown hop " +
                                        std::to_string(hop) + " (the segment has " +
                                        std::to_string(hops.size()) + " hops)");
    }
    bool is_external(int d, int p) const { return d == ext_dev && p == ext_port; }
    bool reachable(int d) const { return d == 0 || devs[d].parent >= 0; }

    // Is device b reachable from device a over the cables (pulled or not)?
    bool connected(int a, int b) const {
        std::vector<int> todo{a};
        std::vector<bool> seen(devs.size(), false);
        seen[a] = true;
        while (!todo.empty()) {
            const int d = todo.back();
            todo.pop_back();
            if (d == b) return true;
            for (const Port& p : devs[d].ports)
                if (p.peer >= 0 && !seen[p.peer]) {
                    seen[p.peer] = true;
                    todo.push_back(p.peer);
                }
        }
        return false;
    }

    // Parents, upstream ports and cable directions from the root down.
    void recompute_tree() {
        for (Device& dv : devs) {
            dv.parent = -1;
            dv.up_port = -1;
            for (Port& p : dv.ports)
                p.down = false;
        }
        if (devs.empty()) return;
        devs[0].up_port = 0;
        std::vector<int> todo{0};
        while (!todo.empty()) {
            const int d = todo.back();
            todo.pop_back();
            for (int p = 0; p < kPortCount; ++p) {
                Port& pt = devs[d].ports[p];
                if (pt.peer < 0 || p == devs[d].up_port) continue;  // no cable, or the cable up
                devs[pt.peer].parent = d;
                devs[pt.peer].up_port = pt.peer_port;
                pt.down = true;
                todo.push_back(pt.peer);
            }
        }
    }

    // What the link of (d, p) should be: a cable plugged in at both ends, both devices powered.
    bool wanted_link(int d, int p) const {
        const Port& pt = devs[d].ports[p];
        if (pt.peer >= 0) return pt.cable_up && devs[pt.peer].powered;
        if (d == 0 && p == 0) return root_cable_up;
        if (is_external(d, p)) return ext_cable_up && ext_carrier;
        return false;
    }
    // Brings the links of a powered device connected to the root in line with the wiring. Touches only
    // ports whose link changes (a change counts in the ESC's lost-link counter and raises its DL status
    // event). A powered-off device's own ESC is left alone (it is dead); a device not yet wired to the root
    // is left alone until it is.
    void apply_links(int d) {
        Device& dv = devs[d];
        if (!dv.powered || !reachable(d)) return;
        for (int p = 0; p < kPortCount; ++p) {
            if (!dv.implements(p)) continue;
            const bool want = wanted_link(d, p);
            if (dv.esc->link(p) != want) dv.esc->set_link(p, want);
        }
    }
    void apply_links_with_peers(int d) {
        apply_links(d);
        for (const Port& pt : devs[d].ports)
            if (pt.peer >= 0) apply_links(pt.peer);
    }

    void update_ahead() {
        ahead.assign(devs.size(), -1);
        if (devs.empty() || !devs[0].powered || !root_cable_up) return;
        std::vector<int> seq;
        seq.reserve(devs.size());
        visit(0, 0, seq);
        for (std::size_t i = 0; i + 1 < seq.size(); ++i)
            ahead[static_cast<std::size_t>(seq[i])] = seq[i + 1];
    }

    // ---- the walk --------------------------------------------------------------------------------
    // Before the frame enters the processing unit of device d: the state of the devices it meets next is
    // asked for, in three stages a step apart, each needing what the one before brought: the Device entry
    // and the Esc object three ahead, the ESC's own state two ahead (through the Esc object), the process
    // RAM one ahead (through the FMMU mappings). Changes nothing.
    void prefetch_after(int d) const {
        const std::size_t n = ahead.size();
        const int a1 = static_cast<std::size_t>(d) < n ? ahead[static_cast<std::size_t>(d)] : -1;
        if (a1 < 0) return;
        devs[static_cast<std::size_t>(a1)].esc->prefetch(true);
        const int a2 = ahead[static_cast<std::size_t>(a1)];
        if (a2 < 0) return;
        devs[static_cast<std::size_t>(a2)].esc->prefetch(false);
        const int a3 = ahead[static_cast<std::size_t>(a2)];
        if (a3 < 0) return;
        __builtin_prefetch(&devs[static_cast<std::size_t>(a3)]);
        __builtin_prefetch(devs[static_cast<std::size_t>(a3)].esc);
        __builtin_prefetch(&hops[static_cast<std::size_t>(a3)]);
    }

    // A frame crossing a cable: false if the cable loses it.
    static bool survives(Hop& h) {
        if (h.drop_per_crossing > 0.0 && uniform(h.rng) < h.drop_per_crossing) {
            ++h.stats.dropped;
            return false;
        }
        return true;
    }

    Result run(std::span<uint8_t> frame, int d, int port, uint64_t t, FrameCheck& check, Result r) {
        // Every ESC passes a frame in at most once per port and once more when it circulates: more steps
        // than that is a loop (which a tree cannot have; a guard, not a path).
        const std::size_t limit = 2 * (kPortCount + 1) * devs.size() + 8;
        r.kind = Result::Kind::Dropped;
        for (std::size_t step = 0; step < limit; ++step) {
            Device& dv = devs[static_cast<std::size_t>(d)];
            if (port == 0) prefetch_after(d);
            const int out = dv.esc->receive(frame, port, t, check);
            if (out < 0) return r;
            if (t != 0) t += port == 0 ? timing.processing_delay_ns : timing.forwarding_delay_ns;
            // A frame with a bad FCS (corrupted on a cable, or aborted by an ESC for a length error) is
            // discarded by the master's NIC, and cannot be sent on with its bad FCS through a socket: it ends
            // here (ESC datasheet section I, Table 57; docs/decisions/esc.md, "Frame tolerance").
            if (check.crc_bad && ((d == 0 && out == 0) || is_external(d, out))) return r;
            if (d == 0 && out == 0) {  // back to the master
                Hop& h = hops[0];
                if (!survives(h)) return r;
                r.hold_ns += h.faults.hold_ns;
                r.kind = Result::Kind::Reply;
                return r;
            }
            if (is_external(d, out)) {
                if (!(ext_cable_up && ext_carrier) || !ext_send) return r;
                ext_send(frame);
                r.kind = Result::Kind::External;
                return r;
            }
            const Port& pt = dv.ports[out];
            if (pt.peer < 0) return r;  // an open port with nothing behind it: the frame is gone
            const int next = pt.peer;
            Hop& h = hops[static_cast<std::size_t>(pt.down ? next : d)];
            if (pt.down) ++h.stats.frames;
            if (!pt.cable_up || !devs[static_cast<std::size_t>(next)].powered) {
                ++h.stats.dropped;  // sent into a pulled cable or a dead device (a port forced open)
                return r;
            }
            if (!survives(h)) return r;
            if (pt.down) {
                if (h.faults.corrupt > 0.0 && uniform(h.rng) < h.faults.corrupt) {
                    ++h.stats.corrupted;
                    check.crc_bad = true;
                }
            } else {
                r.hold_ns += h.faults.hold_ns;
            }
            if (t != 0) t += pt.delay_ns + h.faults.extra_delay_ns;
            d = next;
            port = pt.peer_port;
        }
        return r;
    }

    // ---- order -----------------------------------------------------------------------------------
    // The frame enters device d at port `in`; it meets the processing unit when it is received at port 0
    // (from the cable or looped back there), then passes the other ports in the order 0 -> 3 -> 1 -> 2.
    void visit(int d, int in, std::vector<int>& out) const {
        const Device& dv = devs[static_cast<std::size_t>(d)];
        if (in == 0) out.push_back(d);
        for (int i = 1; i < kPortCount; ++i) {
            const int q = kPortOrder[(order_index(in) + i) % kPortCount];
            const Port& pt = dv.ports[q];
            if (pt.down && dv.esc->port_open(q) && pt.cable_up &&
                devs[static_cast<std::size_t>(pt.peer)].powered)
                visit(pt.peer, pt.peer_port, out);
            if (q == 0) out.push_back(d);
        }
    }
};

Segment::Segment(SegmentTiming timing) : impl_(std::make_unique<Impl>()) {
    impl_->timing = timing;
}
Segment::~Segment() {
    for (Impl::Device& dv : impl_->devs)
        dv.esc->set_signals(nullptr);
}

int Segment::add(Esc& esc) {
    Impl::Device dv;
    dv.esc = &esc;
    dv.descriptor = esc.port_descriptor();
    const int index = static_cast<int>(impl_->devs.size());
    if (index == 0) dv.up_port = 0;
    impl_->devs.push_back(dv);
    impl_->signals.emplace_back();
    for (std::size_t k = 0; k < impl_->devs.size(); ++k)  // the array may have moved
        impl_->devs[k].esc->set_signals(&impl_->signals[k]);
    Impl::Hop hop;
    hop.rng = 0x5EC7'0000'0000'0000ULL ^ (static_cast<uint64_t>(index) * 0x100000001B3ULL);
    impl_->hops.push_back(hop);
    impl_->update_ahead();
    return index;
}

void Segment::connect(int a, int a_port, int b, int b_port, int64_t cable_delay_ns) {
    Impl& m = *impl_;
    m.check_port(a, a_port, "connect");
    m.check_port(b, b_port, "connect");
    if (a == b)
        throw std::invalid_argument("Segment::connect: " + where(a, a_port) + " to " + where(b, b_port) +
                                    ": a device cannot be connected to itself (a loop)");
    for (const auto& [d, p] : {std::pair{a, a_port}, std::pair{b, b_port}}) {
        if (d == 0 && p == 0)
            throw std::invalid_argument("Segment::connect: " + where(d, p) +
                                        ": the root's port 0 faces the master and cannot be connected");
        const Impl::Port& pt = m.devs[static_cast<std::size_t>(d)].ports[p];
        if (pt.peer >= 0)
            throw std::invalid_argument("Segment::connect: " + where(d, p) +
                                        " is used twice (already connected to " +
                                        where(pt.peer, pt.peer_port) + ")");
        if (m.is_external(d, p))
            throw std::invalid_argument("Segment::connect: " + where(d, p) +
                                        " is used twice (the external port)");
    }
    if (m.connected(a, b))
        throw std::invalid_argument("Segment::connect: " + where(a, a_port) + " to " + where(b, b_port) +
                                    " would close a loop (the devices are already connected)");
    const uint64_t delay =
        cable_delay_ns < 0 ? m.timing.cable_delay_ns : static_cast<uint64_t>(cable_delay_ns);
    m.devs[static_cast<std::size_t>(a)].ports[a_port] = {b, b_port, delay, true, false};
    m.devs[static_cast<std::size_t>(b)].ports[b_port] = {a, a_port, delay, true, false};
    m.recompute_tree();
    for (std::size_t d = 0; d < m.devs.size(); ++d)
        m.apply_links(static_cast<int>(d));
    m.update_ahead();
}

void Segment::set_external(int device, int port, std::function<void(std::span<const uint8_t>)> send) {
    Impl& m = *impl_;
    if (!send) {  // no callback: the port no longer leads out
        if (m.ext_dev >= 0 && m.ext_dev == device && m.ext_port == port) {
            m.ext_dev = m.ext_port = -1;
            m.ext_send = nullptr;
            m.apply_links(device);
        }
        return;
    }
    m.check_port(device, port, "set_external");
    if (device == 0 && port == 0)
        throw std::invalid_argument("Segment::set_external: " + where(device, port) +
                                    ": the root's port 0 faces the master");
    const Impl::Port& pt = m.devs[static_cast<std::size_t>(device)].ports[port];
    if (pt.peer >= 0)
        throw std::invalid_argument("Segment::set_external: " + where(device, port) +
                                    " is used twice (already connected to " + where(pt.peer, pt.peer_port) +
                                    ")");
    if (m.ext_dev >= 0 && !m.is_external(device, port))
        throw std::invalid_argument("Segment::set_external: " + where(device, port) +
                                    ": there is already an external port (" + where(m.ext_dev, m.ext_port) +
                                    ")");
    m.ext_dev = device;
    m.ext_port = port;
    m.ext_send = std::move(send);
    m.apply_links(device);
}

void Segment::set_external_link(bool up) {
    impl_->ext_carrier = up;
    if (impl_->ext_dev >= 0) impl_->apply_links(impl_->ext_dev);
}

std::size_t Segment::size() const {
    return impl_->devs.size();
}

EscSignals* Segment::signals() {
    return impl_->signals.data();
}

const EscSignals* Segment::signals() const {
    return impl_->signals.data();
}

Esc& Segment::esc(int device) {
    impl_->check_device(device, "esc");
    return *impl_->devs[static_cast<std::size_t>(device)].esc;
}

int Segment::neighbour(int device, int port) const {
    impl_->check_device(device, "neighbour");
    if (port < 0 || port >= kPortCount) return -1;
    return impl_->devs[static_cast<std::size_t>(device)].ports[port].peer;
}

int Segment::upstream_port(int device) const {
    impl_->check_device(device, "upstream_port");
    return impl_->devs[static_cast<std::size_t>(device)].up_port;
}

int Segment::parent(int device) const {
    impl_->check_device(device, "parent");
    return impl_->devs[static_cast<std::size_t>(device)].parent;
}

std::vector<int> Segment::order() const {
    std::vector<int> out;
    const Impl& m = *impl_;
    if (m.devs.empty() || !m.devs[0].powered || !m.root_cable_up) return out;
    out.reserve(m.devs.size());
    m.visit(0, 0, out);
    return out;
}

Segment::Result Segment::walk(std::span<uint8_t> frame, uint64_t rx_clock_ns) {
    Impl& m = *impl_;
    Result r;
    if (m.devs.empty()) return r;
    Impl::Hop& h0 = m.hops[0];
    ++h0.stats.frames;
    if (!m.root_cable_up || !m.devs[0].powered) {
        ++h0.stats.dropped;
        return r;
    }
    if (!Impl::survives(h0)) return r;
    FrameCheck check;
    if (h0.faults.corrupt > 0.0 && uniform(h0.rng) < h0.faults.corrupt) {
        ++h0.stats.corrupted;
        check.crc_bad = true;
    }
    const uint64_t t = rx_clock_ns == 0 ? 0 : rx_clock_ns + h0.faults.extra_delay_ns;
    return m.run(frame, 0, 0, t, check, r);
}

Segment::Result Segment::resume(std::span<uint8_t> frame, uint64_t rx_clock_ns) {
    Impl& m = *impl_;
    Result r;
    if (m.ext_dev < 0 || !m.devs[static_cast<std::size_t>(m.ext_dev)].powered || !m.reachable(m.ext_dev))
        return r;
    FrameCheck check;  // a real interface delivers only frames with a good FCS
    return m.run(frame, m.ext_dev, m.ext_port, rx_clock_ns, check, r);
}

void Segment::set_cable(int device, int port, bool up) {
    Impl& m = *impl_;
    m.check_port(device, port, "set_cable");
    Impl::Port& pt = m.devs[static_cast<std::size_t>(device)].ports[port];
    if (pt.peer >= 0) {
        pt.cable_up = up;
        m.devs[static_cast<std::size_t>(pt.peer)].ports[pt.peer_port].cable_up = up;
        m.apply_links(device);
        m.apply_links(pt.peer);
    } else if (device == 0 && port == 0) {
        m.root_cable_up = up;
        m.apply_links(0);
    } else if (m.is_external(device, port)) {
        m.ext_cable_up = up;
        m.apply_links(device);
    } else {
        throw std::invalid_argument("Segment::set_cable: " + where(device, port) + " has no cable");
    }
    m.update_ahead();
}

void Segment::set_power(int device, bool on) {
    Impl& m = *impl_;
    m.check_device(device, "set_power");
    m.devs[static_cast<std::size_t>(device)].powered = on;
    m.apply_links_with_peers(device);
    m.update_ahead();
}

bool Segment::powered(int device) const {
    impl_->check_device(device, "powered");
    return impl_->devs[static_cast<std::size_t>(device)].powered;
}

void Segment::replace(int device, Esc& esc) {
    Impl& m = *impl_;
    m.check_device(device, "replace");
    Impl::Device& dv = m.devs[static_cast<std::size_t>(device)];
    dv.esc = &esc;  // the one replaced may be gone already: not touched
    dv.descriptor = esc.port_descriptor();
    esc.set_signals(&m.signals[static_cast<std::size_t>(device)]);
    m.apply_links(device);
    m.update_ahead();
}

void Segment::set_hop_faults(int hop, const HopFaults& faults) {
    Impl& m = *impl_;
    m.check_hop(hop, "set_hop_faults");
    auto fraction = [&](double v, const char* what) {
        if (!(v >= 0.0 && v <= 1.0))
            throw std::invalid_argument("Segment::set_hop_faults: hop " + std::to_string(hop) + ": " + what +
                                        " must be a fraction in [0, 1]");
        return v;
    };
    fraction(faults.corrupt, "corrupt");
    Impl::Hop& h = m.hops[static_cast<std::size_t>(hop)];
    h.drop_per_crossing = 1.0 - std::sqrt(1.0 - fraction(faults.drop, "drop"));
    h.faults = faults;
}

const HopFaults& Segment::hop_faults(int hop) const {
    impl_->check_hop(hop, "hop_faults");
    return impl_->hops[static_cast<std::size_t>(hop)].faults;
}

const HopStats& Segment::hop_stats(int hop) const {
    impl_->check_hop(hop, "hop_stats");
    return impl_->hops[static_cast<std::size_t>(hop)].stats;
}

const SegmentTiming& Segment::timing() const {
    return impl_->timing;
}

}  // namespace esc
