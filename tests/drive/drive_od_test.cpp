// Drive on the real drive dictionary: commands in through 0x6040/0x607A..., feedback out through 0x6041...
#include <gtest/gtest.h>

#include "drive/drive.hpp"
#include "maxpos/maxpos.hpp"
#include "rig.hpp"

using namespace drive;

namespace {

// Controlwords 0x06, 0x07, 0x0F, one 1 ms cycle each from time 0 (shutdown, switch on, enable operation);
// returns the time of the next cycle.
int64_t enable(od::Dictionary& d, Drive& drv) {
    int64_t t = 0;
    for (uint16_t cw : {0x06, 0x07, 0x0F}) {
        d.set<uint16_t>(0x6040, 0, cw);
        drv.cycle(t, 1'000'000);
        t += 1'000'000;
    }
    return t;
}

}  // namespace

TEST(DriveOd, RunsCspThroughTheDictionary) {
    od::Dictionary d = maxpos::dictionary(maxpos::description());
    test::Recorder rec;
    Drive drv(d, &rec, maxpos::drive_objects());
    EXPECT_GT(drv.bound(), 80u);
    ASSERT_EQ(d.set<uint32_t>(0x3001, 5, 25500), od::Status::Ok);
    ASSERT_EQ(d.set<uint32_t>(0x30A1, 1, 20000), od::Status::Ok);   // 20 Hz
    ASSERT_EQ(d.set<uint32_t>(0x30A1, 3, 50000), od::Status::Ok);   // 50 ms reset time
    ASSERT_EQ(d.set<uint32_t>(0x30A1, 4, 188300), od::Status::Ok);  // the simulated inertia
    ASSERT_EQ(d.set<uint32_t>(0x30A1, 5, 46670), od::Status::Ok);   // and viscous friction
    int64_t t = 0;
    auto cycle = [&](uint16_t cw, int n = 1) {
        d.set<uint16_t>(0x6040, 0, cw);
        for (int i = 0; i < n; ++i, t += 1'000'000)
            drv.cycle(t, 1'000'000);
    };
    cycle(0x00);
    EXPECT_EQ(d.get<uint16_t>(0x6041, 0) & 0x6F, 0x40);
    EXPECT_EQ(d.get<int8_t>(0x6061, 0), 8);  // follows 0x6060 = 8 (default)
    d.set<int32_t>(0x607A, 0, d.get<int32_t>(0x6064, 0));
    cycle(0x06);
    cycle(0x07);
    cycle(0x0F);
    EXPECT_EQ(d.get<uint16_t>(0x6041, 0) & 0x6F, 0x27);
    int32_t target = d.get<int32_t>(0x6064, 0);
    for (int k = 0; k < 500; ++k) {
        target += std::min(k, 30);
        d.set<int32_t>(0x607A, 0, target);
        cycle(0x0F);
    }
    cycle(0x0F, 100);
    EXPECT_NEAR(d.get<int32_t>(0x6064, 0), target, 5);
    EXPECT_EQ(d.get<uint16_t>(0x603F, 0), 0);
    EXPECT_EQ(d.get<uint32_t>(0x6076, 0), 127500u);
    EXPECT_EQ(d.get<uint32_t>(0x3000, 5), 2000u);
}

TEST(DriveOd, ConnectionLostWritesTheErrorIntoTheDictionary) {
    od::Dictionary d = maxpos::dictionary(maxpos::description());
    Drive drv(d, nullptr, maxpos::drive_objects());
    d.set<uint32_t>(0x3001, 5, 25500);
    enable(d, drv);
    drv.connection_lost();
    EXPECT_EQ(d.get<uint16_t>(0x603F, 0), 0x8180);
    EXPECT_EQ(d.get<uint8_t>(0x1001, 0), 0x11);  // communication, and generic as at any error (CiA 301)
    EXPECT_EQ(d.get<uint16_t>(0x6041, 0) & 0x4F, 0x0F);  // fault reaction active
}

TEST(DriveOd, CommissionWritesAMatchedTuningSoTheDriveEnables) {
    od::Dictionary d = maxpos::dictionary(maxpos::description());
    ASSERT_EQ(commission(d, maxpos::drive_objects()), od::Status::Ok);
    EXPECT_EQ(d.get<uint32_t>(0x3001, 5), 25500u);
    EXPECT_EQ(d.get<uint32_t>(0x30A1, 4), 188300u);
    EXPECT_EQ(d.get<uint32_t>(0x30A1, 5), 46674u);  // 445.7 uNm/(rad/s) in nNm/rpm
    Drive drv(d, nullptr, maxpos::drive_objects());
    enable(d, drv);
    EXPECT_EQ(d.get<uint16_t>(0x6041, 0) & 0x6F, 0x27);
    EXPECT_EQ(d.get<uint16_t>(0x603F, 0), 0);
}

TEST(DriveOd, SeedDefaultsRefuseToEnableWith8331) {
    od::Dictionary d = maxpos::dictionary(maxpos::description());
    Drive drv(d, nullptr, maxpos::drive_objects());
    enable(d, drv);
    EXPECT_EQ(d.get<uint16_t>(0x603F, 0), 0x8331);
    EXPECT_EQ(d.get<uint16_t>(0x6041, 0) & 0x4F, 0x08);
}

TEST(DriveOd, PowerDisableOnlyObjectsRefuseMasterWritesWhileEnabled) {
    od::Dictionary d = maxpos::dictionary(maxpos::description());
    ASSERT_EQ(commission(d, maxpos::drive_objects()), od::Status::Ok);
    Drive drv(d, nullptr, maxpos::drive_objects());
    const uint8_t pulses[4] = {0x00, 0x04, 0x00, 0x00};  // 1024
    EXPECT_EQ(d.write(0x3010, 1, od::AlState::PreOp, pulses), od::Status::Ok);
    int64_t t = enable(d, drv);
    EXPECT_EQ(drv.axis().increments_per_rev(), 4096);
    EXPECT_EQ(d.write(0x3010, 1, od::AlState::Op, pulses), od::Status::WrongState);
    const uint8_t pp[1] = {2};
    EXPECT_EQ(d.write(0x3001, 3, od::AlState::Op, pp), od::Status::WrongState);
    const uint8_t nominal[2] = {0x88, 0x13};  // 5000 mA: allowed while enabled
    EXPECT_EQ(d.write(0x3001, 1, od::AlState::Op, nominal), od::Status::Ok);
    d.set<uint16_t>(0x6040, 0, 0x06);
    for (int i = 0; i < 200; ++i, t += 1'000'000)
        drv.cycle(t, 1'000'000);
    EXPECT_EQ(d.write(0x3001, 3, od::AlState::Op, pp), od::Status::Ok);
}
