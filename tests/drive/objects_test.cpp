// The objects the drive binds are named once (od/drive_objects.hpp): every handle resolves to an entry of the
// drive dictionary with the handle's size, signedness, access and default; the drive binds every one of
// them; Parameters{}/Command{} hold the dictionary's defaults; the value sets (modes, homing methods, 0x1C00,
// SM control bytes) are the ones the validators check and the drive implements.
#include <gtest/gtest.h>

#include <array>
#include <cstring>

#include "drive/drive.hpp"
#include "od/drive_objects.hpp"
#include "od/drive_profile.hpp"

namespace {

od::Dictionary drive_dictionary() {
    return od::make_drive_dictionary(od::default_drive_description());
}

// Writes `v` (little-endian, `size` bytes) as a master would in Pre-Op.
od::Status master_write(od::Dictionary& d, uint16_t index, uint8_t sub, int64_t v, std::size_t size) {
    std::array<uint8_t, 8> b{};
    for (std::size_t k = 0; k < size; ++k)
        b[k] = static_cast<uint8_t>(static_cast<uint64_t>(v) >> (8 * k));
    return d.write(index, sub, od::AlState::PreOp, std::span<const uint8_t>(b.data(), size));
}

}  // namespace

TEST(DriveObjects, EveryHandleResolvesWithItsTypeAccessAndDefault) {
    const od::Dictionary d = drive_dictionary();
    ASSERT_FALSE(od::drive_objects().empty());
    for (const od::ObjInfo& o : od::drive_objects()) {
        SCOPED_TRACE(std::string(o.name));
        const od::Entry* e = d.find(o.index, o.sub);
        ASSERT_NE(e, nullptr);
        EXPECT_EQ(e->byte_size(), o.size);
        EXPECT_EQ(od::is_signed(e->type), o.is_signed);
        EXPECT_EQ(od::bit_size(e->type), 8u * o.size);
        EXPECT_EQ(e->default_value, o.def);
        EXPECT_TRUE(e->readable(od::AlState::Op));
        if (o.role == od::Role::Command) {
            EXPECT_TRUE(e->writable(od::AlState::Op));
            EXPECT_TRUE(e->rx_mappable());
        }
    }
}

TEST(DriveObjects, HandlesAreUnique) {
    const auto all = od::drive_objects();
    for (std::size_t i = 0; i < all.size(); ++i)
        for (std::size_t k = i + 1; k < all.size(); ++k) {
            EXPECT_FALSE(all[i].index == all[k].index && all[i].sub == all[k].sub)
                << all[i].name << " " << all[k].name;
            EXPECT_NE(all[i].name, all[k].name);
        }
}

TEST(DriveObjects, TheDriveBindsEveryHandleAndNothingElse) {
    od::Dictionary d = drive_dictionary();
    drive::Drive drv(d);
    EXPECT_EQ(drv.missing(), 0u);
    EXPECT_EQ(drv.bound(), od::drive_objects().size());
    for (const od::ObjInfo& o : od::drive_objects())
        EXPECT_TRUE(drv.binds(o.index, o.sub)) << o.name;
    EXPECT_FALSE(drv.binds(0x1000, 0));
}

TEST(DriveObjects, ParametersAndCommandHoldTheDictionaryDefaults) {
    od::Dictionary d = drive_dictionary();
    drive::Drive drv(d);
    drv.cycle(0, 0);  // loads every bound input from the dictionary's defaults
    EXPECT_EQ(drv.axis().params, drive::Parameters{});
    EXPECT_EQ(drv.axis().command, drive::Command{});
    // The comparison sees a differing value.
    ASSERT_EQ(d.set<uint8_t>(0x3142, 4, 26), od::Status::Ok);
    drv.cycle(0, 0);
    EXPECT_NE(drv.axis().params, drive::Parameters{});
    EXPECT_EQ(drv.axis().params.input_function[3], 26);
}

TEST(DriveObjects, ModesOfOperationAreOneSet) {
    od::Dictionary d = drive_dictionary();
    for (int m = -128; m <= 127; ++m) {
        const bool listed = od::contains(od::kModesOfOperation, m);
        EXPECT_EQ(drive::mode::supported(static_cast<int8_t>(m)), listed) << m;
        const od::Status s =
            master_write(d, od::obj::ModesOfOperation.index, od::obj::ModesOfOperation.sub, m, 1);
        EXPECT_EQ(s == od::Status::Ok, listed) << m;
    }
    // 0x6502: PP, PV, HM, CSP, CSV, CST (IEC 61800-7-201 bit assignment).
    EXPECT_EQ(d.get<uint32_t>(od::obj::SupportedDriveModes, 0), 0x000003A5u);
}

TEST(DriveObjects, HomingMethodsAreOneSet) {
    od::Dictionary d = drive_dictionary();
    for (std::size_t k = 0; k < od::kHomingMethods.size(); ++k)
        EXPECT_EQ(d.get<int16_t>(od::obj::SupportedHomingMethods, static_cast<uint8_t>(k + 1)),
                  od::kHomingMethods[k]);
    EXPECT_EQ(d.find(od::obj::SupportedHomingMethods, static_cast<uint8_t>(od::kHomingMethods.size() + 1)),
              nullptr);
    for (int m = -128; m <= 127; ++m) {
        const od::Status s = master_write(d, od::obj::HomingMethod.index, od::obj::HomingMethod.sub, m, 1);
        EXPECT_EQ(s == od::Status::Ok, od::contains(od::kHomingMethods, m)) << m;
    }
}

TEST(DriveObjects, SyncManagersFollowTheirCommunicationTypes) {
    const od::DeviceDescription desc = od::default_drive_description();
    const od::Dictionary d = od::make_drive_dictionary(desc);
    ASSERT_EQ(desc.sync_managers.size(), od::kSmCommunicationTypes.size());
    EXPECT_EQ(d.get<uint8_t>(od::obj::SyncManagerCommunicationType, 0), od::kSmCommunicationTypes.size());
    for (std::size_t n = 0; n < desc.sync_managers.size(); ++n) {
        const od::SyncManagerDefault& sm = desc.sync_managers[n];
        EXPECT_EQ(sm.kind, od::kSmCommunicationTypes[n]);
        EXPECT_EQ(d.get<uint8_t>(od::obj::SyncManagerCommunicationType, static_cast<uint8_t>(n + 1)),
                  static_cast<uint8_t>(sm.kind));
        EXPECT_EQ(sm.control, od::default_sm_control(sm.kind));
    }
    // The control bytes themselves (ESC register 0x0804): mailbox write/read, buffered write/read.
    EXPECT_EQ(od::default_sm_control(od::SmKind::MBoxOut), 0x26);
    EXPECT_EQ(od::default_sm_control(od::SmKind::MBoxIn), 0x22);
    EXPECT_EQ(od::default_sm_control(od::SmKind::Outputs), 0x64);
    EXPECT_EQ(od::default_sm_control(od::SmKind::Inputs), 0x20);
}
