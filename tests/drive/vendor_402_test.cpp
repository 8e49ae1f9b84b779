// The CiA 402 core on another vendor's dictionary: only the standard objects (IEC 61800-7-201) and a few
// vendor objects that mean nothing to the drive, another PDO layout, other defaults; no MAXPOS motor data,
// encoder or tuning objects, no commissioning objects. The drive binds what it finds by index and runs the
// rest on its own defaults (the motor model's tuning): it reaches Operation enabled, tracks a CSP ramp,
// faults on a following error and resets as CiA 402 says, refuses a mode 0x6502 does not announce, and leaves
// the vendor's own objects alone.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "drive/drive.hpp"
#include "drive/wire/error_codes.hpp"
#include "od/dictionary.hpp"
#include "recorder.hpp"
#include "support/alloc_counter.hpp"

namespace {

using od::DataType;
namespace access = od::access;

constexpr uint16_t RO = access::RO;
constexpr uint16_t RW = access::RW;
constexpr uint16_t RWP = access::RW_PreOp;
constexpr uint16_t TX = access::TxPdo;
constexpr uint16_t RX = access::RxPdo;

od::Entry entry(uint16_t index, uint8_t sub, DataType type, uint16_t acc, od::Number def, std::string name,
                od::Number min = {}, od::Number max = {}) {
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

void var(od::Dictionary& d, uint16_t index, DataType type, uint16_t acc, od::Number def,
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
void rec(od::Dictionary& d, uint16_t index, DataType type, const std::string& name,
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

od::Entry u32(uint16_t index, uint8_t sub, uint16_t acc, uint64_t def, const char* name) {
    return entry(index, sub, DataType::Unsigned32, acc, def, name);
}

constexpr uint32_t kResolution = 8192;  // 0x608F:01 encoder increments per motor revolution

// A vendor's CiA 402 servo drive as its ESI would declare it: CSP, CSV and CST only (0x6502), position in
// encoder increments (0x608F, gear 1:1, feed = one revolution), its own PDO layout, two vendor objects.
// feed != 0: with a gear ratio 0x6091 of 1:1 and a feed constant 0x6092 of `feed` position units per
// revolution.
od::Dictionary vendor_dictionary(uint32_t supported_modes = 0x00000380, uint32_t feed = 0,
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
        d.set<int32_t>(0x607A, 0, position());
        cw(0x06);
        cw(0x07);
        cw(0x0F);
    }
};

// A master's SDO write of one value in Pre-Op.
od::Status sdo_write(od::Dictionary& d, uint16_t index, uint8_t sub, int64_t v, std::size_t size) {
    std::array<uint8_t, 8> b{};
    for (std::size_t k = 0; k < size; ++k)
        b[k] = static_cast<uint8_t>(static_cast<uint64_t>(v) >> (8 * k));
    return d.write(index, sub, od::AlState::PreOp, std::span<const uint8_t>(b.data(), size));
}

TEST(Vendor402, BindsTheStandardObjectsByIndexAndLeavesVendorObjectsAlone) {
    VendorRig r;
    EXPECT_TRUE(r.drv.binds(0x6040, 0));
    EXPECT_TRUE(r.drv.binds(0x6041, 0));
    EXPECT_TRUE(r.drv.binds(0x607A, 0));
    EXPECT_TRUE(r.drv.binds(0x6064, 0));
    EXPECT_TRUE(r.drv.binds(0x60B9, 0));
    EXPECT_FALSE(r.drv.binds(0x2002, 0));
    EXPECT_FALSE(r.drv.binds(0x2010, 1));
    EXPECT_GT(r.drv.missing(), 0u);  // the MAXPOS-only standard objects it has not got
    r.enable();
    r.cycle(50);
    EXPECT_EQ(r.d.get<uint16_t>(0x2002, 0), 120u);
    EXPECT_EQ(r.d.get<uint16_t>(0x2010, 1), 7u);
    EXPECT_EQ(r.d.get<int32_t>(0x2010, 2), -5);
}

TEST(Vendor402, CommissionTouchesOnlyObjectsThatExist) {
    od::Dictionary d = vendor_dictionary();
    std::vector<uint8_t> before;
    for (const od::Object& o : d.objects())
        for (const od::Entry& e : o.entries) {
            const auto v = d.raw(e.index, e.subindex);
            before.insert(before.end(), v.begin(), v.end());
        }
    EXPECT_EQ(drive::commission(d, drive::VendorObjects{}), od::Status::Ok);
    std::vector<uint8_t> after;
    for (const od::Object& o : d.objects())
        for (const od::Entry& e : o.entries) {
            const auto v = d.raw(e.index, e.subindex);
            after.insert(after.end(), v.begin(), v.end());
        }
    EXPECT_EQ(before, after);
}

TEST(Vendor402, ReachesOperationEnabledWithoutMotorDataAndTracksACspRamp) {
    VendorRig r;
    r.cycle();
    EXPECT_EQ(r.sw() & 0x6F, 0x40);  // switch on disabled
    r.enable();
    ASSERT_EQ(r.sw() & 0x6F, 0x27) << std::hex << r.sw();  // operation enabled
    EXPECT_EQ(r.d.get<uint16_t>(0x603F, 0), 0u);
    EXPECT_EQ(r.d.get<int8_t>(0x6061, 0), 8);
    // The units of the dictionary: 0x608F says 8192 increments per revolution.
    EXPECT_EQ(r.drv.axis().increments_per_rev(), static_cast<int32_t>(kResolution));
    // A cyclic position ramp: accelerate to 20 inc/ms, cruise, the master's set-point every 1 ms cycle.
    // Touch probe 1 on the encoder's index pulse, positive edge, first event (0x60B8 through the PDO).
    r.d.set<uint16_t>(0x60B8, 0, 0x0015);
    int32_t target = r.position();
    const int32_t start = target;
    int32_t worst = 0;
    for (int k = 0; k < 1500; ++k) {
        target += std::min(k / 10, 20);
        r.d.set<int32_t>(0x607A, 0, target);
        r.cycle();
        if (k > 200) worst = std::max(worst, std::abs(r.d.get<int32_t>(0x60F4, 0)));
    }
    r.cycle(300);
    EXPECT_GT(target - start, 25000);
    EXPECT_NEAR(r.position(), target, 5);
    EXPECT_LT(worst, 400);  // tracked within 0x6065 all along
    EXPECT_EQ(r.sw() & 0x6F, 0x27);
    EXPECT_EQ(r.d.get<uint16_t>(0x603F, 0), 0u);
    // The index pulse (once per revolution of 8192 increments) was latched inside the move.
    EXPECT_EQ(r.d.get<uint16_t>(0x60B9, 0) & 0x3, 0x3);
    const int32_t latched = r.d.get<int32_t>(0x60BA, 0);
    EXPECT_GE(latched, start);
    EXPECT_LE(latched, start + static_cast<int32_t>(kResolution) + 1);
}

TEST(Vendor402, FollowingErrorFaultsAndFaultResetRecovers) {
    VendorRig r;
    r.enable();
    ASSERT_EQ(r.sw() & 0x6F, 0x27);
    ASSERT_EQ(sdo_write(r.d, 0x6065, 0, 200, 4), od::Status::Ok);  // a tight window
    // A set-point step the motor cannot follow.
    r.d.set<int32_t>(0x607A, 0, r.position() + 100000);
    r.cycle();
    // Fault reaction active (0x605E absent: the drive's default, the quick stop ramp), then fault.
    EXPECT_EQ(r.sw() & 0x4F, 0x0F) << std::hex << r.sw();
    for (int k = 0; k < 3000 && (r.sw() & 0x4F) != 0x08; ++k)
        r.cycle();
    EXPECT_EQ(r.sw() & 0x4F, 0x08) << std::hex << r.sw();  // fault
    EXPECT_EQ(r.d.get<uint16_t>(0x603F, 0), drive::error_code::FollowingError);
    EXPECT_NE(r.d.get<uint8_t>(0x1001, 0), 0);
    EXPECT_TRUE(r.rec.has(drive::error_code::FollowingError));
    // Fault reset: a rising edge of bit 7, with the cause gone (the set-point back where the motor is).
    r.d.set<int32_t>(0x607A, 0, r.position());
    r.cw(0x00);
    r.cw(0x80);
    EXPECT_EQ(r.sw() & 0x4F, 0x40) << std::hex << r.sw();  // switch on disabled
    EXPECT_EQ(r.d.get<uint16_t>(0x603F, 0), 0u);
    EXPECT_EQ(r.d.get<uint8_t>(0x1001, 0), 0u);
    r.cw(0x00);
    r.d.set<int32_t>(0x607A, 0, r.position());
    r.cw(0x06);
    r.cw(0x07);
    r.cw(0x0F);
    EXPECT_EQ(r.sw() & 0x6F, 0x27);
}

// A vendor's drive as Ingenia's ESIs declare it: no encoder resolution (0x608F absent, the position unit is
// the encoder increment), a following error window of 100 increments for 10 ms (0x6065/0x6066). The master
// ramps the set-point as a CSP user does, 10 increments per 1 ms cycle from standstill: a drive that
// interpolates the set-points feeds its own demand's velocity forward and stays well inside the window, as
// the real one does (without the feed-forward the lag of a bare position loop, some 100 increments at this
// speed, faulted it with 0x8611 within the first 20 ms).
TEST(Vendor402, ACspRampStaysInsideAVendorsTightFollowingErrorWindow) {
    od::Dictionary d = vendor_dictionary(0x00000380, 0, false);
    ASSERT_EQ(sdo_write(d, 0x6065, 0, 100, 4), od::Status::Ok);
    var(d, 0x6066, DataType::Unsigned16, RW, uint64_t{10}, "Following error time out");
    drive::test::Recorder rec;
    drive::Drive drv{d, &rec};
    int64_t t = 0;
    auto cycle = [&](int n) {
        for (int i = 0; i < n; ++i, t += 1'000'000)
            drv.cycle(t, 1'000'000);
    };
    auto sw = [&] { return d.get<uint16_t>(0x6041, 0); };
    cycle(1);
    d.set<int32_t>(0x607A, 0, d.get<int32_t>(0x6064, 0));
    for (uint16_t c : {0x06, 0x07, 0x0F}) {
        d.set<uint16_t>(0x6040, 0, c);
        cycle(1);
    }
    ASSERT_EQ(sw() & 0x6F, 0x27) << std::hex << sw();
    int32_t target = d.get<int32_t>(0x6064, 0);
    const int32_t end = target + 2000;
    int32_t worst = 0;
    while (target < end) {
        target += 20;
        d.set<int32_t>(0x607A, 0, target);
        cycle(2);
        worst = std::max(worst, std::abs(d.get<int32_t>(0x60F4, 0)));
        ASSERT_EQ(sw() & 0x6F, 0x27) << std::hex << sw() << " at " << target << ", error code 0x"
                                     << d.get<uint16_t>(0x603F, 0);
    }
    cycle(200);
    EXPECT_LT(worst, 100);
    EXPECT_NEAR(d.get<int32_t>(0x6064, 0), end, 2);
    EXPECT_EQ(d.get<uint16_t>(0x603F, 0), 0u);
}

// 0x6065 = 0 switches the following error monitoring off, as 0xFFFFFFFF does (CiA 402-2 / IEC 61800-7-201,
// following error window): a set-point step the motor cannot follow is no fault then.
TEST(Vendor402, AFollowingErrorWindowOfZeroSwitchesTheMonitoringOff) {
    VendorRig r;
    r.enable();
    ASSERT_EQ(r.sw() & 0x6F, 0x27);
    ASSERT_EQ(sdo_write(r.d, 0x6065, 0, 0, 4), od::Status::Ok);
    r.d.set<int32_t>(0x607A, 0, r.position() + 100000);
    r.cycle(50);
    EXPECT_EQ(r.sw() & 0x6F, 0x27) << std::hex << r.sw();
    EXPECT_EQ(r.d.get<uint16_t>(0x603F, 0), 0u);
    EXPECT_FALSE(r.rec.has(drive::error_code::FollowingError));
}

TEST(Vendor402, QuickStopFollowsTheVendorsOptionCode) {
    VendorRig r;
    r.enable();
    ASSERT_EQ(r.sw() & 0x6F, 0x27);
    // 0x605A = 2: slow down on the quick stop ramp, then switch on disabled (IEC 61800-7-201).
    r.cw(0x02);
    EXPECT_EQ(r.sw() & 0x6F, 0x07) << std::hex << r.sw();  // quick stop active
    r.cycle(2000);
    EXPECT_EQ(r.sw() & 0x4F, 0x40) << std::hex << r.sw();  // switch on disabled
    // 0x605A = 6: stay in Quick Stop Active; enable operation resumes (transition 16).
    ASSERT_EQ(sdo_write(r.d, 0x605A, 0, 6, 2), od::Status::Ok);
    r.enable();
    ASSERT_EQ(r.sw() & 0x6F, 0x27);
    r.cw(0x02);
    r.cycle(2000);
    EXPECT_EQ(r.sw() & 0x6F, 0x07) << std::hex << r.sw();
    r.cw(0x0F);
    EXPECT_EQ(r.sw() & 0x6F, 0x27) << std::hex << r.sw();
}

TEST(Vendor402, AModeNotAnnouncedIn6502IsRefused) {
    VendorRig r;
    // An SDO write of a mode the drive implements but 0x6502 does not announce: value range exceeded.
    EXPECT_EQ(sdo_write(r.d, 0x6060, 0, 1, 1), od::Status::InvalidValue);  // profile position
    EXPECT_EQ(sdo_write(r.d, 0x6060, 0, 6, 1), od::Status::InvalidValue);  // homing
    EXPECT_EQ(sdo_write(r.d, 0x6060, 0, 2, 1), od::Status::InvalidValue);  // velocity mode: not implemented
    EXPECT_EQ(sdo_write(r.d, 0x6060, 0, 9, 1), od::Status::Ok);            // CSV
    EXPECT_EQ(sdo_write(r.d, 0x6060, 0, 10, 1), od::Status::Ok);           // CST
    EXPECT_EQ(sdo_write(r.d, 0x6060, 0, 8, 1), od::Status::Ok);            // CSP
    r.enable();
    ASSERT_EQ(r.d.get<int8_t>(0x6061, 0), 8);
    // Through process data (no SDO check): the display does not follow a mode that is not announced.
    r.d.set<int8_t>(0x6060, 0, 3);
    r.cycle(5);
    EXPECT_EQ(r.d.get<int8_t>(0x6061, 0), 8);
    r.d.set<int8_t>(0x6060, 0, 9);
    r.cycle(5);
    EXPECT_EQ(r.d.get<int8_t>(0x6061, 0), 9);
}

TEST(Vendor402, ModesAnnouncedAreTaken) {
    // The same dictionary announcing profile position and homing as well: now they are accepted.
    od::Dictionary d = vendor_dictionary(0x000003A5);
    drive::Drive drv(d);
    EXPECT_EQ(sdo_write(d, 0x6060, 0, 1, 1), od::Status::Ok);
    EXPECT_EQ(sdo_write(d, 0x6060, 0, 6, 1), od::Status::Ok);
    EXPECT_EQ(sdo_write(d, 0x6060, 0, 2, 1), od::Status::InvalidValue);
    d.set<int8_t>(0x6060, 0, 1);
    drv.cycle(0, 1'000'000);
    EXPECT_EQ(d.get<int8_t>(0x6061, 0), 1);
}

TEST(Vendor402, PositionsAreInTheDevicesUnitsThroughGearAndFeed) {
    // 8192 increments per revolution, 4096 position units per revolution: one unit is two increments.
    od::Dictionary d = vendor_dictionary(0x00000380, 4096);
    drive::Drive drv(d);
    int64_t t = 0;
    auto cycle = [&](int n) {
        for (int i = 0; i < n; ++i, t += 1'000'000)
            drv.cycle(t, 1'000'000);
    };
    cycle(1);
    // Limits and windows of the dictionary arrive in increments.
    EXPECT_EQ(drv.axis().params.following_error_window, 8000u);
    EXPECT_EQ(drv.axis().params.sw_limit_max, 2000000);
    EXPECT_EQ(drv.axis().params.sw_limit_min, -2000000);
    // Velocities in units per second: 200000 units/s = 400000 inc/s = 2929.7 rpm of an 8192-inc motor; the
    // profile acceleration 20000 units/s^2 = 292.97 rpm/s.
    EXPECT_EQ(drv.axis().params.max_profile_velocity, 2930u);
    EXPECT_EQ(drv.axis().params.profile_acceleration, 293u);
    d.set<int32_t>(0x607A, 0, d.get<int32_t>(0x6064, 0));
    for (uint16_t cw : {0x06, 0x07, 0x0F}) {
        d.set<uint16_t>(0x6040, 0, cw);
        cycle(1);
    }
    ASSERT_EQ(d.get<uint16_t>(0x6041, 0) & 0x6F, 0x27);
    const int32_t start_units = d.get<int32_t>(0x6064, 0);
    const int32_t start_inc = drv.axis().feedback().position_actual;
    EXPECT_NEAR(start_units, start_inc / 2.0, 1);
    int32_t target = start_units;
    for (int k = 0; k < 400; ++k) {
        target += std::min(k / 20, 5);
        d.set<int32_t>(0x607A, 0, target);
        cycle(1);
    }
    cycle(300);
    EXPECT_GT(target - start_units, 1000);
    EXPECT_NEAR(d.get<int32_t>(0x6064, 0), target, 2);
    EXPECT_NEAR(drv.axis().feedback().position_actual - start_inc, 2.0 * (target - start_units), 4);
    EXPECT_EQ(d.get<uint16_t>(0x603F, 0), 0u);
    // At rest the velocity reads near 0; moving at 5 units/ms = 5000 units/s it reads about 5000.
    EXPECT_LT(std::abs(d.get<int32_t>(0x606C, 0)), 50);
}

TEST(Vendor402, WithoutAnEncoderResolutionTheFeedConstantGivesTheIncrements) {
    // A 20-bit feed per revolution, gear 1:1, no 0x608F: one position unit is one increment.
    od::Dictionary d = vendor_dictionary(0x00000380, 1u << 20, false);
    drive::Drive drv(d);
    drv.cycle(0, 1'000'000);
    drv.cycle(1'000'000, 1'000'000);
    EXPECT_EQ(drv.axis().increments_per_rev(), 1 << 20);
    EXPECT_EQ(drv.axis().params.following_error_window, 4000u);
    EXPECT_EQ(d.get<int32_t>(0x6064, 0), drv.axis().feedback().position_actual);
}

TEST(Vendor402, TheScaledCycleAllocatesNothing) {
    od::Dictionary d = vendor_dictionary(0x00000380, 4096);
    drive::NullEventSink sink;
    drive::Drive drv(d, &sink);
    int64_t t = 0;
    for (uint16_t cw : {0x06, 0x07, 0x0F}) {
        d.set<uint16_t>(0x6040, 0, cw);
        drv.cycle(t, 1'000'000);
        t += 1'000'000;
    }
    const alloc_counter::Scope counting;
    for (int k = 0; k < 300; ++k, t += 1'000'000) {
        d.set<int32_t>(0x607A, 0, k * 3);
        drv.cycle(t, 1'000'000);
    }
    EXPECT_EQ(counting.count(), 0u);
}

TEST(Vendor402, TheValidatorGoesWithTheDrive) {
    od::Dictionary d = vendor_dictionary();
    {
        drive::Drive drv(d);
        EXPECT_EQ(sdo_write(d, 0x6060, 0, 1, 1), od::Status::InvalidValue);
    }
    EXPECT_EQ(sdo_write(d, 0x6060, 0, 1, 1), od::Status::Ok);  // no drive, no CiA 402 check
}

}  // namespace
