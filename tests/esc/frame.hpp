#pragma once
// Frame-building helper for the ESC unit tests: builds EtherCAT frames from datagrams and parses the reply.
#include <cstdint>
#include <cstring>
#include <vector>

#include "esc/esc.hpp"
#include "esc/wire/frame_builder.hpp"
#include "util/le.hpp"

namespace esc_test {

// The clock time (ns) the tests that need an absolute time set their ESC's clock to at construction (the
// local time starts equal to it): 1 s, so that times before it are representable.
inline constexpr uint64_t kT0 = 1'000'000'000;

// Datagram commands as the raw command byte the tests put into a frame (esc/wire/datagram.hpp).
constexpr uint8_t command_byte(esc::Command c) {
    return static_cast<uint8_t>(c);
}
constexpr uint8_t NOP = command_byte(esc::Command::NOP);
constexpr uint8_t APRD = command_byte(esc::Command::APRD);
constexpr uint8_t APWR = command_byte(esc::Command::APWR);
constexpr uint8_t APRW = command_byte(esc::Command::APRW);
constexpr uint8_t FPRD = command_byte(esc::Command::FPRD);
constexpr uint8_t FPWR = command_byte(esc::Command::FPWR);
constexpr uint8_t FPRW = command_byte(esc::Command::FPRW);
constexpr uint8_t BRD = command_byte(esc::Command::BRD);
constexpr uint8_t BWR = command_byte(esc::Command::BWR);
constexpr uint8_t BRW = command_byte(esc::Command::BRW);
constexpr uint8_t LRD = command_byte(esc::Command::LRD);
constexpr uint8_t LWR = command_byte(esc::Command::LWR);
constexpr uint8_t LRW = command_byte(esc::Command::LRW);
constexpr uint8_t ARMW = command_byte(esc::Command::ARMW);
constexpr uint8_t FRMW = command_byte(esc::Command::FRMW);

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
    return util::le_bytes(v, n);
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
    esc::wire::FrameBuilder b;
    for (const auto& d : dgs)
        b.add(d.cmd, d.idx, d.adp, d.ado, d.data, d.irq, d.wkc);
    return b.build(min_len);
}

// Parses the datagrams of a (returned) frame; stops at the first inconsistency.
inline std::vector<Datagram> parse(const std::vector<uint8_t>& f) {
    std::vector<Datagram> out;
    esc::wire::DatagramReader r(f, false, false);
    esc::wire::DatagramView v;
    while (r.next(v)) {
        Datagram d;
        d.cmd = v.command;
        d.idx = v.index;
        d.adp = v.adp;
        d.ado = v.ado;
        d.flags = v.length_flags;
        d.irq = v.irq;
        d.data.assign(v.data.begin(), v.data.end());
        d.wkc = v.wkc;
        out.push_back(d);
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
