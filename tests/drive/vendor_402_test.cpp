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
#include "vendor_dictionary.hpp"

namespace {

using namespace drive::test::vendor;

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
