// Bring-up of the whole line and distributed clocks over it (bus.hpp).
#include "master/bus.hpp"

#include <time.h>

#include "util/le.hpp"

namespace master {

namespace {
using util::get16;
using util::get32;
using util::get64;
using util::put32;
using util::put64;

constexpr uint16_t kFeatureDc = 1u << 2;  // ESC features 0x0008 bit 2: distributed clocks available

// Signed distance a - b of two 32-bit receive times (they lie within one frame's round trip of each other).
int64_t diff32(uint32_t a, uint32_t b) {
    return static_cast<int32_t>(a - b);
}

// Active ports of a slave from its entry port on, in processing order.
struct PortCycle {
    int port[4] = {};
    int count = 0;
};
PortCycle port_cycle(const SlaveInfo& s) {
    PortCycle c;
    int p = s.entry_port;
    for (int k = 0; k < 4; ++k, p = next_port(p))
        if (p == s.entry_port || (s.active_ports & (1u << p))) c.port[c.count++] = p;
    return c;
}
}  // namespace

uint8_t active_ports_from_dl_status(uint16_t dl_status) {
    uint8_t ports = 0;
    for (int p = 0; p < 4; ++p) {
        const bool loop_closed = dl_status & (1u << (8 + 2 * p));
        const bool communication = dl_status & (1u << (9 + 2 * p));
        if (!loop_closed && communication) ports = static_cast<uint8_t>(ports | (1u << p));
    }
    return ports;
}

int next_port(int port) {
    static constexpr int kNext[4] = {3, 2, 0, 1};  // 0 -> 3 -> 1 -> 2 -> 0
    return kNext[port & 3];
}

uint64_t master_system_time() {
    timespec ts{};
    clock_gettime(CLOCK_REALTIME, &ts);
    constexpr uint64_t k2000 = 946'684'800ull;
    return (static_cast<uint64_t>(ts.tv_sec) - k2000) * 1'000'000'000ull + static_cast<uint64_t>(ts.tv_nsec);
}

Result<std::vector<SlaveInfo>> scan_bus(Master& m, const BusOptions& options) {
    auto n = m.count_slaves();
    if (!n) return n.error();
    if (Error e = m.assign_station_addresses(*n, options.first_station); e != Error::Ok) return e;
    std::vector<SlaveInfo> slaves(*n);
    for (uint16_t i = 0; i < *n; ++i) {
        SlaveInfo& s = slaves[i];
        s.position = i;
        s.station = static_cast<uint16_t>(options.first_station + i);
        const Address a = Address::station(s.station);
        uint8_t head[10];  // 0x0000 type .. 0x0007 port descriptor, 0x0008 features
        if (Error e = m.read(a, reg::Type, head); e != Error::Ok) return e;
        s.port_descriptor = head[7];
        s.has_dc = (get16(head + 8) & kFeatureDc) != 0;
        if (auto al = m.al_status(a))
            s.al = *al;
        else
            s.error = al.error();
        if (options.identity && s.error == Error::Ok) {
            uint8_t id[16];
            if (Error e = m.sii_read(a, sii::VendorId, id); e != Error::Ok) {
                s.error = e;
                continue;
            }
            s.vendor_id = get32(id);
            s.product_code = get32(id + 4);
            s.revision = get32(id + 8);
            s.serial = get32(id + 12);
        }
    }
    if (Error e = read_ports(m, slaves); e != Error::Ok) return e;
    return slaves;
}

Error read_ports(Master& m, std::span<SlaveInfo> slaves) {
    for (SlaveInfo& s : slaves) {
        auto dl = m.read_reg<uint16_t>(Address::station(s.station), reg::DlStatus);
        if (!dl) return dl.error();
        s.dl_status = *dl;
        s.active_ports = active_ports_from_dl_status(*dl);
    }
    return Error::Ok;
}

int reference_clock(std::span<const SlaveInfo> slaves) {
    for (std::size_t i = 0; i < slaves.size(); ++i)
        if (slaves[i].has_dc) return static_cast<int>(i);
    return -1;
}

Error compute_dc_topology(std::span<SlaveInfo> slaves) {
    // Entry port: the active port the frame reached first (the earliest receive time).
    for (SlaveInfo& s : slaves) {
        s.entry_port = 0;
        bool any = false;
        for (int p = 0; p < 4; ++p) {
            if (!(s.active_ports & (1u << p))) continue;
            if (!any || diff32(s.port_time[p], s.port_time[s.entry_port]) < 0) s.entry_port = p;
            any = true;
        }
    }
    // Parents: the frame meets the processing units depth first, so slave i+1 hangs at the next unused
    // downstream port of the nearest slave (i itself, or going back up) that still has one.
    struct Open {
        int slave;
        int next;  // index into its port cycle of the next downstream port to hand out
    };
    std::vector<Open> stack;
    for (std::size_t i = 0; i < slaves.size(); ++i) {
        SlaveInfo& s = slaves[i];
        s.parent = -1;
        s.parent_port = -1;
        if (i > 0) {
            while (!stack.empty() && stack.back().next >= port_cycle(slaves[stack.back().slave]).count)
                stack.pop_back();
            if (stack.empty()) return Error::InvalidArgument;
            Open& o = stack.back();
            s.parent = o.slave;
            s.parent_port = port_cycle(slaves[o.slave]).port[o.next++];
        }
        if (port_cycle(s).count > 1) stack.push_back({static_cast<int>(i), 1});
    }
    // Delays. A child at port q of its parent: the frame left the parent towards q when it came back at the
    // port before q in the cycle (or entered the parent), and came back at q: that round trip holds the cable
    // both ways and the child's own subtree, whose time the child's receive times give. Half of the rest is
    // the one-way delay (forward and return delays taken as equal, as ETG.1020 does); the time the frame
    // spent in the parent's earlier branches is added to it.
    const int ref = reference_clock(slaves);
    for (std::size_t i = 0; i < slaves.size(); ++i) {
        SlaveInfo& s = slaves[i];
        s.delay_ns = 0;
        if (ref < 0 || static_cast<int>(i) <= ref || s.parent < 0) continue;
        const SlaveInfo& p = slaves[static_cast<std::size_t>(s.parent)];
        const PortCycle pc = port_cycle(p);
        int k = 1;
        while (k < pc.count && pc.port[k] != s.parent_port)
            ++k;
        if (k >= pc.count) return Error::InvalidArgument;
        const int before = pc.port[k - 1];
        const int64_t round_trip = diff32(p.port_time[s.parent_port], p.port_time[before]);
        const int64_t earlier = diff32(p.port_time[before], p.port_time[p.entry_port]);
        const PortCycle sc = port_cycle(s);
        const int64_t subtree =
            sc.count > 1 ? diff32(s.port_time[sc.port[sc.count - 1]], s.port_time[s.entry_port]) : 0;
        s.delay_ns = p.delay_ns + earlier  // 0 for the reference clock and any slave before it
                     + (round_trip - subtree) / 2;
    }
    return Error::Ok;
}

namespace {
// BWR 0x0900 (every receive time latched), then the times of every DC slave and the topology.
Error measure(Master& m, std::span<SlaveInfo> slaves, uint64_t& master_now) {
    const uint8_t zero4[4] = {};
    master_now = master_system_time();
    auto w = m.broadcast_write(esc::reg::kDcRecvTime0, zero4);  // latches every receive time
    if (!w) return w.error();
    for (SlaveInfo& s : slaves) {
        if (!s.has_dc) continue;
        uint8_t t[32];  // 0x0900..0x091F: port receive times, system time, processing-unit receive time
        if (Error e = m.read(Address::station(s.station), esc::reg::kDcRecvTime0, t); e != Error::Ok)
            return e;
        for (int p = 0; p < 4; ++p)
            s.port_time[static_cast<std::size_t>(p)] = get32(t + 4 * p);
        s.rx_time_pu = get64(t + 24);
    }
    return compute_dc_topology(slaves);
}
}  // namespace

Error measure_dc(Master& m, std::span<SlaveInfo> slaves) {
    uint64_t master_now = 0;
    return measure(m, slaves, master_now);
}

Error configure_dc(Master& m, std::span<SlaveInfo> slaves, const DcMeasureOptions& options) {
    const int ref = reference_clock(slaves);
    if (ref < 0) return Error::Ok;
    uint64_t master_now = 0;
    if (Error e = measure(m, slaves, master_now); e != Error::Ok) return e;
    for (SlaveInfo& s : slaves) {
        if (!s.has_dc) continue;
        const Address a = Address::station(s.station);
        // The frame reached this slave delay_ns after the reference clock: its system time then was the
        // reference's (= the master's clock at the BWR) plus the delay.
        s.offset_ns = static_cast<int64_t>(master_now - s.rx_time_pu) + s.delay_ns;
        uint8_t off[8];
        put64(off, static_cast<uint64_t>(s.offset_ns));
        if (Error e = m.write(a, esc::reg::kDcOffset, off); e != Error::Ok) return e;
        uint8_t delay[4];
        put32(delay, static_cast<uint32_t>(s.delay_ns));
        if (Error e = m.write(a, esc::reg::kDcDelay, delay); e != Error::Ok) return e;
        // Writing the speed counter start resets the drift filters (ESC datasheet section II, 0x0930).
        uint8_t speed[2];
        if (Error e = m.read(a, esc::reg::kDcSpeedStart, speed); e != Error::Ok) return e;
        if (Error e = m.write(a, esc::reg::kDcSpeedStart, speed); e != Error::Ok) return e;
    }
    if (options.drift_frames) {
        uint8_t time[8] = {};
        Datagram d{Command::FRMW, slaves[static_cast<std::size_t>(ref)].station, reg::DcSystemTime, time};
        for (unsigned i = 0; i < options.drift_frames; ++i)
            if (Error e = m.exchange(d); e != Error::Ok) return e;
    }
    return Error::Ok;
}

}  // namespace master
