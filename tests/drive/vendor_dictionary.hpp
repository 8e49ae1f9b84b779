#pragma once
// A vendor's CiA 402 dictionary for the drive's tests: only the standard objects (IEC 61800-7-201) and a few
// vendor objects that mean nothing to the drive, another PDO layout, other defaults than the MAXPOS's; and
// the helpers that run a drive::Drive on it (vendor_402_test.cpp, vendor_402_modes_test.cpp).
#include <array>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include "drive/drive.hpp"
#include "od/dictionary.hpp"
#include "recorder.hpp"

namespace drive::test::vendor {

using od::DataType;
namespace access = od::access;

constexpr uint16_t RO = access::RO;
constexpr uint16_t RW = access::RW;
constexpr uint16_t RWP = access::RW_PreOp;
constexpr uint16_t TX = access::TxPdo;
constexpr uint16_t RX = access::RxPdo;

inline od::Entry entry(uint16_t index, uint8_t sub, DataType type, uint16_t acc, od::Number def,
                       std::string name, od::Number min = {}, od::Number max = {}) {
    od::Entry e;
    e.index = index;
    e.subindex = sub;
    e.type = type;
    e.access = acc;
    e.default_value = def;
    e.minimum = min;
    e.maximum = max;
    e.name = std::move(name);
    return e;
}

inline void var(od::Dictionary& d, uint16_t index, DataType type, uint16_t acc, od::Number def,
                const std::string& name, od::Number min = {}, od::Number max = {}) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Var;
    o.type = type;
    o.name = name;
    o.entries.push_back(entry(index, 0, type, acc, def, name, min, max));
    d.add(std::move(o));
}

// An ARRAY/RECORD with subindex 0 = highest subindex and the given entries.
inline void rec(od::Dictionary& d, uint16_t index, DataType type, const std::string& name,
                std::vector<od::Entry> subs) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Record;
    o.type = type;
    o.name = name;
    o.entries.push_back(entry(index, 0, DataType::Unsigned8, RO, uint64_t{subs.size()}, "Highest sub-index"));
    for (od::Entry& e : subs)
        o.entries.push_back(std::move(e));
    d.add(std::move(o));
}

inline od::Entry u32(uint16_t index, uint8_t sub, uint16_t acc, uint64_t def, const char* name) {
    return entry(index, sub, DataType::Unsigned32, acc, def, name);
}

constexpr uint32_t kResolution = 8192;  // 0x608F:01 encoder increments per motor revolution

// A vendor's CiA 402 servo drive as its ESI would declare it: CSP, CSV and CST only (0x6502), position in
// encoder increments (0x608F, gear 1:1, feed = one revolution), its own PDO layout, two vendor objects.
// feed != 0: with a gear ratio 0x6091 of 1:1 and a feed constant 0x6092 of `feed` position units per
// revolution.
inline od::Dictionary vendor_dictionary(uint32_t supported_modes = 0x00000380, uint32_t feed = 0,
                                        bool resolution = true) {
    using T = DataType;
    od::Dictionary d;
    var(d, 0x1000, T::Unsigned32, RO, uint64_t{0x00020192}, "Device type");
    var(d, 0x1001, T::Unsigned8, RO | TX, uint64_t{0}, "Error register");
    rec(d, 0x1018, T::Identity, "Identity",
        {u32(0x1018, 1, RO, 0x00000A5A, "Vendor ID"), u32(0x1018, 2, RO, 0x00001234, "Product code"),
         u32(0x1018, 3, RO, 0x00010000, "Revision"), u32(0x1018, 4, RO, 0, "Serial number")});
    // RxPDO 0x1600: target position, controlword, mode, touch probe function (another order than MAXPOS).
    rec(d, 0x1600, T::PdoMapping, "RxPDO",
        {u32(0x1600, 1, RWP, 0x607A0020, "1"), u32(0x1600, 2, RWP, 0x60400010, "2"),
         u32(0x1600, 3, RWP, 0x60600008, "3"), u32(0x1600, 4, RWP, 0x60B80010, "4")});
    rec(d, 0x1A00, T::PdoMapping, "TxPDO",
        {u32(0x1A00, 1, RWP, 0x60640020, "1"), u32(0x1A00, 2, RWP, 0x60410010, "2"),
         u32(0x1A00, 3, RWP, 0x60F40020, "3"), u32(0x1A00, 4, RWP, 0x60610008, "4"),
         u32(0x1A00, 5, RWP, 0x603F0010, "5"), u32(0x1A00, 6, RWP, 0x60B90010, "6"),
         u32(0x1A00, 7, RWP, 0x60BA0020, "7")});
    // Vendor objects: a brake delay and a record of I/O settings, meaningless to the drive.
    var(d, 0x2002, T::Unsigned16, RW, uint64_t{120}, "Brake release delay");
    rec(d, 0x2010, T::Unsigned8, "Vendor I/O",
        {entry(0x2010, 1, T::Unsigned16, RW, uint64_t{7}, "Input filter"),
         entry(0x2010, 2, T::Integer32, RW, int64_t{-5}, "Offset")});
    var(d, 0x603F, T::Unsigned16, RO | TX, uint64_t{0}, "Error code");
    var(d, 0x6040, T::Unsigned16, RW | RX, uint64_t{0}, "Controlword");
    var(d, 0x6041, T::Unsigned16, RO | TX, uint64_t{0}, "Statusword");
    var(d, 0x605A, T::Integer16, RW, int64_t{2}, "Quick stop option code");
    var(d, 0x6060, T::Integer8, RW | RX, int64_t{8}, "Modes of operation");
    var(d, 0x6061, T::Integer8, RO | TX, int64_t{0}, "Modes of operation display");
    var(d, 0x6064, T::Integer32, RO | TX, int64_t{0}, "Position actual value");
    var(d, 0x6065, T::Unsigned32, RW, uint64_t{4000}, "Following error window");
    var(d, 0x606C, T::Integer32, RO | TX, int64_t{0}, "Velocity actual value");
    var(d, 0x6071, T::Integer16, RW | RX, int64_t{0}, "Target torque");
    var(d, 0x6077, T::Integer16, RO | TX, int64_t{0}, "Torque actual value");
    var(d, 0x607A, T::Integer32, RW | RX, int64_t{0}, "Target position");
    rec(d, 0x607D, T::Integer32, "Software position limit",
        {entry(0x607D, 1, T::Integer32, RW, int64_t{-1000000}, "Min"),
         entry(0x607D, 2, T::Integer32, RW, int64_t{1000000}, "Max")});
    // In rpm without a factor group, in position units per second with one.
    var(d, 0x607F, T::Unsigned32, RW, uint64_t{feed != 0 ? 200000u : 3000u}, "Max profile velocity");
    var(d, 0x6083, T::Unsigned32, RW, uint64_t{20000}, "Profile acceleration");
    var(d, 0x6084, T::Unsigned32, RW, uint64_t{20000}, "Profile deceleration");
    var(d, 0x6085, T::Unsigned32, RW, uint64_t{50000}, "Quick stop deceleration");
    if (resolution)
        rec(d, 0x608F, T::Unsigned32, "Position encoder resolution",
            {u32(0x608F, 1, RW, kResolution, "Encoder increments"),
             u32(0x608F, 2, RW, 1, "Motor revolutions")});
    if (feed != 0) {
        rec(d, 0x6091, T::Unsigned32, "Gear ratio",
            {u32(0x6091, 1, RW, 1, "Motor revolutions"), u32(0x6091, 2, RW, 1, "Shaft revolutions")});
        rec(d, 0x6092, T::Unsigned32, "Feed constant",
            {u32(0x6092, 1, RW, feed, "Feed"), u32(0x6092, 2, RW, 1, "Shaft revolutions")});
    }
    var(d, 0x60B8, T::Unsigned16, RW | RX, uint64_t{0}, "Touch probe function");
    var(d, 0x60B9, T::Unsigned16, RO | TX, uint64_t{0}, "Touch probe status");
    var(d, 0x60BA, T::Integer32, RO | TX, int64_t{0}, "Touch probe 1 positive edge");
    var(d, 0x60F4, T::Integer32, RO | TX, int64_t{0}, "Following error actual value");
    var(d, 0x60FF, T::Integer32, RW | RX, int64_t{0}, "Target velocity");
    var(d, 0x6502, T::Unsigned32, RO, uint64_t{supported_modes}, "Supported drive modes");
    return d;
}

struct VendorRig {
    VendorRig() = default;
    explicit VendorRig(od::Dictionary dict) : d(std::move(dict)) {}

    od::Dictionary d = vendor_dictionary();
    drive::test::Recorder rec;
    drive::Drive drv{d, &rec};
    int64_t t = 0;

    void cycle(int n = 1) {
        for (int i = 0; i < n; ++i, t += 1'000'000)
            drv.cycle(t, 1'000'000);
    }
    void cw(uint16_t c, int n = 1) {
        d.set<uint16_t>(0x6040, 0, c);
        cycle(n);
    }
    uint16_t sw() const { return d.get<uint16_t>(0x6041, 0); }
    int32_t position() const { return d.get<int32_t>(0x6064, 0); }
    void enable() {
        cycle();
        if (d.find(0x607A, 0)) d.set<int32_t>(0x607A, 0, position());
        cw(0x06);
        cw(0x07);
        cw(0x0F);
    }
};

// A master's SDO write of one value in Pre-Op.
inline od::Status sdo_write(od::Dictionary& d, uint16_t index, uint8_t sub, int64_t v, std::size_t size) {
    std::array<uint8_t, 8> b{};
    for (std::size_t k = 0; k < size; ++k)
        b[k] = static_cast<uint8_t>(static_cast<uint64_t>(v) >> (8 * k));
    return d.write(index, sub, od::AlState::PreOp, std::span<const uint8_t>(b.data(), size));
}

// The same dictionary without the objects `left_out` (whole objects), as a vendor's ESI that does not
// declare them.
inline od::Dictionary without(const od::Dictionary& d, std::initializer_list<uint16_t> left_out) {
    od::Dictionary out;
    for (const od::Object& o : d.objects()) {
        bool keep = true;
        for (uint16_t i : left_out)
            keep = keep && o.index != i;
        if (keep) out.add(o);
    }
    return out;
}

}  // namespace drive::test::vendor
