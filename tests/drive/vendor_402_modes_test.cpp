// The CiA 402 core on a vendor's dictionary (vendor_dictionary.hpp): quick stop with every option code of
// 0x605A and the ramp each one names, a dictionary without the stop objects, a deceleration of 0; the
// interpolated position mode (0x60C0/0x60C1/0x60C2, controlword bit 4, statusword bits 10 and 12) and the
// profile torque mode (0x6071, 0x6087, 0x6088, statusword bit 10); and the modes 0x6502 announces against
// the ones the dictionary lets the drive serve (IEC 61800-7-201).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "drive/drive.hpp"
#include "drive/wire/error_codes.hpp"
#include "od/dictionary.hpp"
#include "vendor_dictionary.hpp"

namespace {

using namespace drive::test::vendor;

constexpr uint16_t kSod = 0x40, kSodMask = 0x4F;
constexpr uint16_t kOe = 0x27, kQsa = 0x07, kStateMask = 0x6F;

// The objects of the interpolated position mode and the profile torque mode, as a vendor's ESI declares
// them: sub-mode 0x60C0, the data record 0x60C1 (one position set-point), the time period 0x60C2 (1 ms), the
// torque slope 0x6087 and profile type 0x6088, the torque demand 0x6074.
void add_ip_and_pt(od::Dictionary& d, uint32_t torque_slope = 0, int16_t torque_profile = 0) {
    using T = DataType;
    var(d, 0x6074, T::Integer16, RO | TX, int64_t{0}, "Torque demand");
    var(d, 0x6087, T::Unsigned32, RW, uint64_t{torque_slope}, "Torque slope");
    var(d, 0x6088, T::Integer16, RW, int64_t{torque_profile}, "Torque profile type");
    var(d, 0x60C0, T::Integer16, RW, int64_t{0}, "Interpolation sub mode select");
    rec(d, 0x60C1, T::Integer32, "Interpolation data record",
        {entry(0x60C1, 1, T::Integer32, RW | RX, int64_t{0}, "Interpolation data record 1")});
    rec(d, 0x60C2, T::Unsigned8, "Interpolation time period",
        {entry(0x60C2, 1, T::Unsigned8, RW, uint64_t{1}, "Interpolation time period value"),
         entry(0x60C2, 2, T::Integer8, RW, int64_t{-3}, "Interpolation time index")});
}

// PP, PV, PT, HM, IP, CSP, CSV, CST: every mode the drive implements (IEC 61800-7-201 bits).
constexpr uint32_t kAllModes = 0x000003ED;

struct Motion {
    VendorRig& r;
    int16_t velocity() const { return static_cast<int16_t>(r.d.get<int32_t>(0x606C, 0)); }
    // Runs CSV at `rpm` until the speed has settled.
    void spin(int32_t rpm) {
        ASSERT_EQ(sdo_write(r.d, 0x6060, 0, 9, 1), od::Status::Ok);
        r.d.set<int32_t>(0x60FF, 0, rpm);
        r.enable();
        ASSERT_EQ(r.sw() & kStateMask, kOe) << std::hex << r.sw();
        r.cycle(300);
        ASSERT_NEAR(velocity(), rpm, 20);
    }
};

// The stop of one quick stop: ms until the motor is at rest, the largest torque on the way, the state 1.5 s
// after the command.
struct Stop {
    int rest_ms = -1;
    int peak_torque = 0;
    uint16_t sw_after = 0;
};
Stop quick_stop(VendorRig& r) {
    Motion run{r};
    Stop s;
    r.d.set<uint16_t>(0x6040, 0, 0x0002);
    for (int ms = 1; ms <= 1500; ++ms) {
        r.cycle();
        s.peak_torque = std::max(s.peak_torque, std::abs(static_cast<int>(r.d.get<int16_t>(0x6077, 0))));
        if (s.rest_ms < 0 && std::abs(run.velocity()) <= 5) s.rest_ms = ms;
    }
    s.sw_after = r.sw();
    return s;
}

// 0x605A, every value IEC 61800-7-201 defines, from 1000 rpm: 0 switches the power stage off (the motor
// coasts), 1/5 ramp on the slow-down ramp 0x6084, 2/6 on the quick stop ramp 0x6085, 3/4/7/8 at the current
// limit; 0...4 then go to Switch On Disabled by themselves, 5...8 stay in Quick Stop Active and hold, until
// enable operation resumes (transition 16).
TEST(Vendor402Stop, EveryQuickStopOptionCodeStopsWithItsRampAndEndsWhereItSays) {
    Stop stops[9];
    for (int code = 0; code <= 8; ++code) {
        SCOPED_TRACE(code);
        VendorRig r;
        ASSERT_EQ(sdo_write(r.d, 0x605A, 0, code, 2), od::Status::Ok);
        ASSERT_EQ(sdo_write(r.d, 0x6084, 0, 2000, 4), od::Status::Ok);   // rpm/s: 500 ms from 1000 rpm
        ASSERT_EQ(sdo_write(r.d, 0x6085, 0, 20000, 4), od::Status::Ok);  // 50 ms
        Motion{r}.spin(1000);
        stops[code] = quick_stop(r);
        const Stop& s = stops[code];
        ASSERT_GT(s.rest_ms, 0);
        if (code <= 4) {
            EXPECT_EQ(s.sw_after & kSodMask, kSod) << std::hex << s.sw_after;
        } else {
            EXPECT_EQ(s.sw_after & kStateMask, kQsa) << std::hex << s.sw_after;
            EXPECT_NE(s.sw_after & 0x0400, 0);  // target reached: the stop is over
            EXPECT_LE(std::abs(Motion{r}.velocity()), 5);
            r.cw(0x0F);  // transition 16
            EXPECT_EQ(r.sw() & kStateMask, kOe) << std::hex << r.sw();
        }
        EXPECT_EQ(r.d.get<uint16_t>(0x603F, 0), 0u);
    }
    // The ramps: 0x6084 takes ~500 ms, 0x6085 ~50 ms, the current limit less; the drive without power makes
    // no torque and the motor coasts on its friction.
    for (int code : {1, 5}) {
        EXPECT_NEAR(stops[code].rest_ms, 500, 25) << code;
        EXPECT_LT(stops[code].peak_torque, 1000) << code;
    }
    for (int code : {2, 6})
        EXPECT_NEAR(stops[code].rest_ms, 50, 10) << code;
    for (int code : {3, 4, 7, 8}) {
        EXPECT_LT(stops[code].rest_ms, stops[2].rest_ms) << code;
        // At the current limit: the drive's output limit (15 A) is three times the rated current (5 A).
        EXPECT_GT(stops[code].peak_torque, 2500) << code;
    }
    EXPECT_EQ(stops[0].peak_torque, 0);  // 0: the power stage off at once, the motor coasts to rest
}

// A vendor's ESI without 0x605A, 0x6084 and 0x6085 (Beckhoff EJ7211, Elmo): the drive runs on the profile's
// quick stop option code 2 (quick stop ramp, then switch on disabled), not the MAXPOS's 6, and on its own
// quick stop deceleration.
TEST(Vendor402Stop, WithoutTheStopObjectsTheDriveStopsAndSwitchesOffAsTheProfileSays) {
    VendorRig r(without(vendor_dictionary(), {0x605A, 0x6084, 0x6085}));
    EXPECT_FALSE(r.drv.binds(0x605A, 0));
    EXPECT_EQ(r.drv.axis().params.quick_stop, drive::kProfileQuickStopOptionCode);
    Motion{r}.spin(1000);
    const Stop s = quick_stop(r);
    EXPECT_GT(s.rest_ms, 0);
    EXPECT_LT(s.rest_ms, 200);
    EXPECT_EQ(s.sw_after & kSodMask, kSod) << std::hex << s.sw_after;
    // Enabled again, the drive stops as before.
    r.d.set<int32_t>(0x60FF, 0, 0);
    r.cw(0x00);
    Motion{r}.spin(-600);
    EXPECT_EQ(quick_stop(r).sw_after & kSodMask, kSod);
}

// A deceleration of 0 (Synapticon ships 0x6085 = 0, Novanta 0x6084 = 0) is no ramp: the drive stops at the
// current limit rather than never.
TEST(Vendor402Stop, ADecelerationOfZeroStopsAtTheCurrentLimit) {
    for (int code : {1, 2}) {
        SCOPED_TRACE(code);
        VendorRig r;
        ASSERT_EQ(sdo_write(r.d, 0x605A, 0, code, 2), od::Status::Ok);
        ASSERT_EQ(sdo_write(r.d, 0x6084, 0, 0, 4), od::Status::Ok);
        ASSERT_EQ(sdo_write(r.d, 0x6085, 0, 0, 4), od::Status::Ok);
        Motion{r}.spin(1000);
        const Stop s = quick_stop(r);
        EXPECT_GT(s.rest_ms, 0);
        EXPECT_LT(s.rest_ms, 30);
        EXPECT_GT(s.peak_torque, 2500);
        EXPECT_EQ(s.sw_after & kSodMask, kSod) << std::hex << s.sw_after;
    }
}

// The fault reaction 0x605E = 3 (current limit): the drive brakes at the current limit, then Fault.
TEST(Vendor402Stop, FaultReactionAtTheCurrentLimit) {
    od::Dictionary d = vendor_dictionary();
    var(d, 0x605E, DataType::Integer16, RW, int64_t{3}, "Fault reaction option code");
    VendorRig r(std::move(d));
    Motion{r}.spin(1000);
    r.drv.axis().raise_error(drive::error_code::FollowingError);
    r.cycle();
    EXPECT_EQ(r.sw() & kSodMask, 0x0F) << std::hex << r.sw();  // fault reaction active
    int ms = 1;
    int peak = 0;
    for (; ms < 1500 && (r.sw() & kSodMask) != 0x08; ++ms) {
        r.cycle();
        peak = std::max(peak, std::abs(static_cast<int>(r.d.get<int16_t>(0x6077, 0))));
    }
    EXPECT_EQ(r.sw() & kSodMask, 0x08) << std::hex << r.sw();
    EXPECT_GT(peak, 2500);
    EXPECT_LT(ms, 100);
}

// 0x6502 announces what the drive serves on this dictionary: a mode whose set-point object the dictionary
// lacks (interpolated position without 0x60C1, the torque modes without 0x6071) and the manufacturer-specific
// bits are taken out, said by withheld_modes(), and refused in 0x6060.
TEST(Vendor402Modes, AnAnnouncedModeTheDictionaryCannotServeIsWithheld) {
    od::Dictionary d = without(vendor_dictionary(0x000F03ED), {0x6071});
    drive::Drive drv(d);
    // Without 0x60C1 and 0x6071: no IP (bit 6), PT (bit 3) or CST (bit 9); bits 16-19 (the vendor's own).
    EXPECT_EQ(d.get<uint32_t>(0x6502, 0), 0x000001A5u);
    EXPECT_EQ(drv.withheld_modes(), 0x000F0248u);
    EXPECT_EQ(sdo_write(d, 0x6060, 0, 7, 1), od::Status::InvalidValue);
    EXPECT_EQ(sdo_write(d, 0x6060, 0, 4, 1), od::Status::InvalidValue);
    EXPECT_EQ(sdo_write(d, 0x6060, 0, 10, 1), od::Status::InvalidValue);
    EXPECT_EQ(sdo_write(d, 0x6060, 0, 1, 1), od::Status::Ok);
    drv.cycle(0, 1'000'000);
    ASSERT_EQ(d.get<int8_t>(0x6061, 0), 1);
    // 0, "no mode change" (IEC 61800-7-201), is taken and changes nothing: the value a vendor dictionary
    // holds before a master chooses a mode can be written back.
    EXPECT_EQ(sdo_write(d, 0x6060, 0, 0, 1), od::Status::Ok);
    drv.cycle(500'000, 1'000'000);
    EXPECT_EQ(d.get<int8_t>(0x6061, 0), 1);
    // Through process data (no SDO check) neither.
    d.set<int8_t>(0x6060, 0, 7);
    drv.cycle(1'000'000, 1'000'000);
    EXPECT_EQ(d.get<int8_t>(0x6061, 0), 1);

    // With the objects every mode is served and 0x6502 stays as announced.
    od::Dictionary full = vendor_dictionary(kAllModes);
    add_ip_and_pt(full);
    drive::Drive served(full);
    EXPECT_EQ(full.get<uint32_t>(0x6502, 0), kAllModes);
    EXPECT_EQ(served.withheld_modes(), 0u);
    for (int m : {1, 3, 4, 6, 7, 8, 9, 10})
        EXPECT_EQ(sdo_write(full, 0x6060, 0, m, 1), od::Status::Ok) << m;
    EXPECT_EQ(sdo_write(full, 0x6060, 0, 2, 1), od::Status::InvalidValue);  // velocity mode: not implemented

    // 0x6502 = 0 states nothing: the modes served are announced.
    od::Dictionary zero = vendor_dictionary(0);
    drive::Drive on_zero(zero);
    EXPECT_EQ(zero.get<uint32_t>(0x6502, 0), 0x000003ADu);  // no 0x60C1: all but IP
    EXPECT_EQ(on_zero.withheld_modes(), 0u);
}

struct ModesRig : VendorRig {
    explicit ModesRig(uint32_t slope = 0, int16_t profile = 0) : VendorRig(dictionary(slope, profile)) {}
    static od::Dictionary dictionary(uint32_t slope, int16_t profile) {
        od::Dictionary d = vendor_dictionary(kAllModes);
        add_ip_and_pt(d, slope, profile);
        return d;
    }
    void mode(int8_t m) {
        ASSERT_EQ(sdo_write(d, 0x6060, 0, m, 1), od::Status::Ok);
        cycle();
        ASSERT_EQ(d.get<int8_t>(0x6061, 0), m);
    }
};

// Interpolated position mode: controlword bit 4 takes the interpolation on (statusword bit 12 "ip mode
// active"), each cycle's 0x60C1:01 is a set-point the axis follows; bit 10 is set once the last set-point is
// reached at rest; taking bit 4 off stops the axis where it is, bit 12 clears.
TEST(Vendor402Modes, InterpolatedPositionFollowsTheDataRecordWhileBit4IsSet) {
    ModesRig r;
    r.mode(drive::modes::InterpolatedPosition);
    r.enable();
    ASSERT_EQ(r.sw() & kStateMask, kOe) << std::hex << r.sw();
    EXPECT_EQ(r.sw() & 0x1000, 0);  // not active before bit 4
    const int32_t start = r.position();
    r.d.set<int32_t>(0x60C1, 1, start);
    r.cw(0x1F);
    EXPECT_NE(r.sw() & 0x1000, 0) << std::hex << r.sw();
    // A ramp of set-points, 20 inc per 1 ms cycle, then hold.
    int32_t target = start;
    int32_t worst = 0;
    for (int k = 0; k < 500; ++k) {
        target += std::min(k / 10, 20);
        r.d.set<int32_t>(0x60C1, 1, target);
        r.cycle();
        worst = std::max(worst, std::abs(r.d.get<int32_t>(0x60F4, 0)));
        if (k > 100) {
            EXPECT_EQ(r.sw() & 0x0400, 0) << k;  // moving: not reached
        }
        ASSERT_EQ(r.sw() & kStateMask, kOe) << std::hex << r.sw();
    }
    EXPECT_LT(worst, 400);
    r.cycle(200);
    EXPECT_NEAR(r.position(), target, 3);
    EXPECT_NE(r.sw() & 0x0400, 0) << std::hex << r.sw();  // at the last set-point, at rest
    EXPECT_NE(r.sw() & 0x1000, 0);
    EXPECT_EQ(r.d.get<uint16_t>(0x603F, 0), 0u);
    // Bit 4 off: the interpolation stops, the set-points are not followed any more.
    r.cw(0x0F);
    EXPECT_EQ(r.sw() & 0x1000, 0) << std::hex << r.sw();
    r.d.set<int32_t>(0x60C1, 1, target + 5000);
    r.cycle(100);
    EXPECT_NEAR(r.position(), target, 3);
    EXPECT_NE(r.sw() & 0x0400, 0);
    // On again: from where the axis is, to the new set-point.
    r.d.set<int32_t>(0x60C1, 1, target);
    r.cw(0x1F);
    for (int k = 1; k <= 100; ++k) {
        r.d.set<int32_t>(0x60C1, 1, target + 10 * k);
        r.cycle();
    }
    r.cycle(200);
    EXPECT_NEAR(r.position(), target + 1000, 3);
    EXPECT_NE(r.sw() & 0x0400, 0);
}

// Halt (bit 8) in the interpolated position mode: the axis stops on the quick stop ramp, bit 12 clears, bit
// 10 is set once it stands still.
TEST(Vendor402Modes, InterpolatedPositionHalts) {
    ModesRig r;
    r.mode(drive::modes::InterpolatedPosition);
    r.enable();
    int32_t target = r.position();
    r.d.set<int32_t>(0x60C1, 1, target);
    r.cw(0x1F);
    for (int k = 0; k < 200; ++k) {
        target += std::min(k / 10, 20);
        r.d.set<int32_t>(0x60C1, 1, target);
        r.cycle();
    }
    r.cw(0x11F);
    EXPECT_EQ(r.sw() & 0x1000, 0) << std::hex << r.sw();
    for (int k = 0; k < 200; ++k) {
        target += 20;  // the master keeps sending: halted, the axis does not follow
        r.d.set<int32_t>(0x60C1, 1, target);
        r.cycle();
    }
    EXPECT_LT(r.position(), target - 2000);
    EXPECT_NE(r.sw() & 0x0400, 0) << std::hex << r.sw();
    EXPECT_LE(std::abs(r.d.get<int32_t>(0x606C, 0)), 5);
    EXPECT_EQ(r.sw() & kStateMask, kOe);
}

// Only the linear interpolation is served: 0x60C0 reads 0 and refuses any other sub-mode.
TEST(Vendor402Modes, OnlyLinearInterpolation) {
    od::Dictionary d = ModesRig::dictionary(0, 0);
    ASSERT_EQ(d.set<int16_t>(0x60C0, 0, -1), od::Status::Ok);  // a vendor's default of its own sub-mode
    drive::Drive drv(d);
    EXPECT_EQ(d.get<int16_t>(0x60C0, 0), 0);
    EXPECT_EQ(sdo_write(d, 0x60C0, 0, -1, 2), od::Status::InvalidValue);
    EXPECT_EQ(sdo_write(d, 0x60C0, 0, 0, 2), od::Status::Ok);
}

// Profile torque mode: the torque demand (0x6074) ramps to the target torque 0x6071 with the torque slope
// 0x6087 (per mille of the rated torque per second), linearly or as sin^2 (0x6088 = 1); bit 10 is set once
// the demand has reached the target; the motor accelerates on the torque.
TEST(Vendor402Modes, ProfileTorqueRampsToTheTargetWithTheSlope) {
    for (int16_t profile : {0, 1}) {
        SCOPED_TRACE(profile);
        ModesRig r(1000, profile);  // 1000 per mille/s: 200 ms to 200 per mille
        r.mode(drive::modes::ProfileTorque);
        r.enable();
        ASSERT_EQ(r.sw() & kStateMask, kOe) << std::hex << r.sw();
        r.d.set<int16_t>(0x6071, 0, 200);
        r.cycle(100);
        const int16_t half = r.d.get<int16_t>(0x6074, 0);
        EXPECT_NEAR(half, 100, 5);  // half way in time is half way in torque, for both profiles
        EXPECT_EQ(r.sw() & 0x0400, 0);
        if (profile == 0) {
            r.cycle(50);
            EXPECT_NEAR(r.d.get<int16_t>(0x6074, 0), 150, 5);  // linear: 3/4
        } else {
            r.cycle(50);
            EXPECT_NEAR(r.d.get<int16_t>(0x6074, 0), 171, 5);  // 200 sin^2(3 pi / 8)
        }
        r.cycle(60);
        EXPECT_EQ(r.d.get<int16_t>(0x6074, 0), 200);
        EXPECT_NE(r.sw() & 0x0400, 0) << std::hex << r.sw();
        EXPECT_GT(r.d.get<int32_t>(0x606C, 0), 100);  // the torque turns the motor
        EXPECT_NEAR(r.d.get<int16_t>(0x6077, 0), 200, 30);
        // Back to 0: the same slope down.
        r.d.set<int16_t>(0x6071, 0, 0);
        r.cycle(100);
        EXPECT_NEAR(r.d.get<int16_t>(0x6074, 0), 100, 5);
        r.cycle(150);
        EXPECT_EQ(r.d.get<int16_t>(0x6074, 0), 0);
        EXPECT_EQ(r.d.get<uint16_t>(0x603F, 0), 0u);
    }
}

// A torque slope of 0 (as vendors ship it where the device sets its own) or 0xFFFFFFFF: no ramp.
TEST(Vendor402Modes, ProfileTorqueWithoutASlopeStepsToTheTarget) {
    for (uint32_t slope : {0u, 0xFFFFFFFFu}) {
        ModesRig r(slope);
        r.mode(drive::modes::ProfileTorque);
        r.enable();
        r.d.set<int16_t>(0x6071, 0, -150);
        r.cycle();
        EXPECT_EQ(r.d.get<int16_t>(0x6074, 0), -150) << slope;
        EXPECT_NE(r.sw() & 0x0400, 0);
        r.cycle(100);
        EXPECT_LT(r.d.get<int32_t>(0x606C, 0), -50);
    }
}

// Halt in the profile torque mode stops the axis (quick stop ramp) and holds it; released, the torque ramp
// starts from the torque the motor gives then. A quick stop from torque mode ends in Switch On Disabled.
TEST(Vendor402Modes, ProfileTorqueHaltsAndQuickStops) {
    ModesRig r(2000);
    r.mode(drive::modes::ProfileTorque);
    r.enable();
    r.d.set<int16_t>(0x6071, 0, 200);
    r.cycle(300);
    ASSERT_GT(r.d.get<int32_t>(0x606C, 0), 200);
    r.cw(0x10F);
    r.cycle(300);
    EXPECT_LE(std::abs(r.d.get<int32_t>(0x606C, 0)), 5);
    EXPECT_NE(r.sw() & 0x0400, 0) << std::hex << r.sw();
    r.cw(0x0F);
    EXPECT_EQ(r.sw() & 0x0400, 0);
    r.cycle(300);
    EXPECT_EQ(r.d.get<int16_t>(0x6074, 0), 200);
    EXPECT_GT(r.d.get<int32_t>(0x606C, 0), 200);
    const Stop s = quick_stop(r);
    EXPECT_GT(s.rest_ms, 0);
    EXPECT_EQ(s.sw_after & kSodMask, kSod) << std::hex << s.sw_after;
}

}  // namespace

namespace {

// The drive cycles on the slave's clock (dt between two cycles), and a loaded host makes that clock uneven:
// a slave process not scheduled for 6 ms meets the next cycle late, the set-point already six master cycles
// on (the runtime serves the frames that waited before the firmware runs); or the gaps alternate 0.4/1.6 ms.
// The master ramps 10 increments per 1 ms cycle against Ingenia's window (0x6065 = 100 increments, 0x6066 =
// 10 ms): the axis must stay as close as on even cycles. (The interpolation cut the last set-point's segment
// at the next cycle's time, so a short gap after a long one put the demand back by what the axis had
// already run: 0x8611 within 30 cycles.)
TEST(Vendor402Late, UnevenSlaveCyclesKeepACspRampInsideATightWindow) {
    for (int pattern = 0; pattern < 3; ++pattern) {
        SCOPED_TRACE(pattern);
        od::Dictionary d = vendor_dictionary(0x00000380, 0, false);
        ASSERT_EQ(sdo_write(d, 0x6065, 0, 100, 4), od::Status::Ok);
        var(d, 0x6066, DataType::Unsigned16, RW, uint64_t{10}, "Following error time out");
        VendorRig r(std::move(d));
        r.enable();
        ASSERT_EQ(r.sw() & kStateMask, kOe);
        int32_t target = r.position();
        int worst = 0;
        for (int k = 0; k < 1000; ++k) {
            int64_t dt = 1'000'000;
            int32_t step = 10;
            if (pattern == 1 && k % 50 == 10) {  // late by 5 ms: six cycles' set-points on
                dt = 6'000'000;
                step = 60;
            }
            if (pattern == 2) dt = k % 2 ? 400'000 : 1'600'000;  // jitter, the same mean
            target += step;
            r.d.set<int32_t>(0x607A, 0, target);
            r.t += dt;
            r.drv.cycle(r.t, dt);
            worst = std::max(worst, std::abs(r.d.get<int32_t>(0x60F4, 0)));
            ASSERT_EQ(r.sw() & kStateMask, kOe) << k << ": 0x" << std::hex << r.d.get<uint16_t>(0x603F, 0);
        }
        EXPECT_LT(worst, 50);
        EXPECT_FALSE(r.rec.has(drive::error_code::FollowingError));
    }
}

}  // namespace
