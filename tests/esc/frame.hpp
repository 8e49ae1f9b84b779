#pragma once
// Frame-building helper for the ESC unit tests: builds EtherCAT frames from datagrams and parses the reply.
#include <cstdint>
#include <cstring>
#include <vector>

#include "esc/esc.hpp"

namespace esc_test {

enum Cmd : uint8_t {
    NOP = 0,
    APRD = 1,
    APWR = 2,
    APRW = 3,
    FPRD = 4,
    FPWR = 5,
    FPRW = 6,
    BRD = 7,
    BWR = 8,
    BRW = 9,
    LRD = 10,
    LWR = 11,
    LRW = 12,
    ARMW = 13,
    FRMW = 14,
};

struct Datagram {
    uint8_t cmd = 0;
    uint8_t idx = 0;
    uint16_t adp = 0;
    uint16_t ado = 0;
    std::vector<uint8_t> data;
    uint16_t irq = 0;
    uint16_t wkc = 0;
    uint16_t flags = 0;  // Len/flags word as found in the frame
    uint32_t logical() const { return static_cast<uint32_t>(adp) | (static_cast<uint32_t>(ado) << 16); }
    uint16_t u16(std::size_t at = 0) const { return static_cast<uint16_t>(data[at] | (data[at + 1] << 8)); }
    uint32_t u32(std::size_t at = 0) const {
        return static_cast<uint32_t>(u16(at)) | (static_cast<uint32_t>(u16(at + 2)) << 16);
    }
    uint64_t u64(std::size_t at = 0) const {
        return static_cast<uint64_t>(u32(at)) | (static_cast<uint64_t>(u32(at + 4)) << 32);
    }
};

inline std::vector<uint8_t> le(uint64_t v, std::size_t n) {
    std::vector<uint8_t> b(n);
    for (std::size_t i = 0; i < n; ++i)
        b[i] = static_cast<uint8_t>(v >> (8 * i));
    return b;
}

inline Datagram dg(uint8_t cmd, uint16_t adp, uint16_t ado, std::vector<uint8_t> data) {
    Datagram d;
    d.cmd = cmd;
    d.adp = adp;
    d.ado = ado;
    d.data = std::move(data);
    return d;
}
inline Datagram dg_len(uint8_t cmd, uint16_t adp, uint16_t ado, std::size_t len) {
    return dg(cmd, adp, ado, std::vector<uint8_t>(len, 0));
}
inline Datagram lg(uint8_t cmd, uint32_t la, std::vector<uint8_t> data) {
    return dg(cmd, static_cast<uint16_t>(la), static_cast<uint16_t>(la >> 16), std::move(data));
}

// Ethernet II (broadcast destination, master source 01:01:01:01:01:01), EtherType 0x88A4, type 1 header,
// datagrams chained with the M bit, padded with zeros up to min_len.
inline std::vector<uint8_t> build(const std::vector<Datagram>& dgs, std::size_t min_len = 60) {
    std::vector<uint8_t> f(12, 0xFF);
    for (int i = 6; i < 12; ++i)
        f[i] = 0x01;
    f.push_back(0x88);
    f.push_back(0xA4);
    std::size_t total = 0;
    for (const auto& d : dgs)
        total += 12 + d.data.size();
    f.push_back(static_cast<uint8_t>(total));
    f.push_back(static_cast<uint8_t>(0x10 | ((total >> 8) & 0x07)));
    for (std::size_t k = 0; k < dgs.size(); ++k) {
        const Datagram& d = dgs[k];
        const uint16_t lf = static_cast<uint16_t>(d.data.size() | (k + 1 < dgs.size() ? 0x8000 : 0));
        const uint8_t h[10] = {d.cmd,
                               d.idx,
                               static_cast<uint8_t>(d.adp),
                               static_cast<uint8_t>(d.adp >> 8),
                               static_cast<uint8_t>(d.ado),
                               static_cast<uint8_t>(d.ado >> 8),
                               static_cast<uint8_t>(lf),
                               static_cast<uint8_t>(lf >> 8),
                               static_cast<uint8_t>(d.irq),
                               static_cast<uint8_t>(d.irq >> 8)};
        f.insert(f.end(), h, h + 10);
        f.insert(f.end(), d.data.begin(), d.data.end());
        f.push_back(static_cast<uint8_t>(d.wkc));
        f.push_back(static_cast<uint8_t>(d.wkc >> 8));
    }
    if (f.size() < min_len) f.resize(min_len, 0);
    return f;
}

// Parses the datagrams of a (returned) frame; stops at the first inconsistency.
inline std::vector<Datagram> parse(const std::vector<uint8_t>& f) {
    std::vector<Datagram> out;
    std::size_t p = 16;
    if (f.size() < p) return out;
    const std::size_t end = p + ((f[14] | (f[15] << 8)) & 0x07FF);
    while (p + 12 <= end && end <= f.size()) {
        Datagram d;
        d.cmd = f[p];
        d.idx = f[p + 1];
        d.adp = static_cast<uint16_t>(f[p + 2] | (f[p + 3] << 8));
        d.ado = static_cast<uint16_t>(f[p + 4] | (f[p + 5] << 8));
        d.flags = static_cast<uint16_t>(f[p + 6] | (f[p + 7] << 8));
        d.irq = static_cast<uint16_t>(f[p + 8] | (f[p + 9] << 8));
        const std::size_t len = d.flags & 0x07FF;
        if (p + 12 + len > end) break;
        d.data.assign(f.begin() + static_cast<long>(p + 10), f.begin() + static_cast<long>(p + 10 + len));
        d.wkc = static_cast<uint16_t>(f[p + 10 + len] | (f[p + 11 + len] << 8));
        out.push_back(d);
        p += 12 + len;
        if (!(d.flags & 0x8000)) break;
    }
    return out;
}

// Sends the datagrams through one ESC and returns the processed datagrams.
inline std::vector<Datagram> run(esc::Esc& e, const std::vector<Datagram>& dgs, uint64_t rx = 0) {
    auto f = build(dgs);
    e.process_frame(f, rx);
    return parse(f);
}
inline Datagram run1(esc::Esc& e, const Datagram& d, uint64_t rx = 0) {
    return run(e, {d}, rx).at(0);
}

// Convenience register accessors through ECAT (station address must be set with set_station()).
inline void set_station(esc::Esc& e, uint16_t station) {
    run1(e, dg(APWR, 0, 0x0010, le(station, 2)));
}
inline Datagram fpwr(esc::Esc& e, uint16_t ado, std::vector<uint8_t> data, uint16_t station = 0x1001) {
    return run1(e, dg(FPWR, station, ado, std::move(data)));
}
inline Datagram fprd(esc::Esc& e, uint16_t ado, std::size_t len, uint16_t station = 0x1001) {
    return run1(e, dg_len(FPRD, station, ado, len));
}

}  // namespace esc_test
