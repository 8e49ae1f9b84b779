// The objects the drive binds are named once (drive/objects.hpp): every CiA 402 handle resolves to an entry
// of the MAXPOS dictionary with the handle's size, signedness, access and default, and so does every vendor
// parameter the MAXPOS binds; the drive binds every one of them; Parameters{}/Command{} hold the MAXPOS
// dictionary's defaults; the value sets (modes, homing methods, 0x1C00, SM control bytes) are the ones the
// validators check and the drive implements.
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <type_traits>

#include "drive/drive.hpp"
#include "drive/objects.hpp"
#include "maxpos/maxpos.hpp"
#include "od/dictionary.hpp"

namespace {

od::Dictionary drive_dictionary() {
    return maxpos::dictionary(maxpos::description());
}

// Writes `v` (little-endian, `size` bytes) as a master would in Pre-Op.
od::Status master_write(od::Dictionary& d, uint16_t index, uint8_t sub, int64_t v, std::size_t size) {
    std::array<uint8_t, 8> b{};
    for (std::size_t k = 0; k < size; ++k)
        b[k] = static_cast<uint8_t>(static_cast<uint64_t>(v) >> (8 * k));
    return d.write(index, sub, od::AlState::PreOp, std::span<const uint8_t>(b.data(), size));
}

// The CiA 402 objects the drive knows that the MAXPOS has not got (MAXPOS firmware specification chapter 7:
// no 0x608F, its resolution is 0x3000:05 from the encoder's pulses; no gear ratio 0x6091 or feed constant
// 0x6092, its positions are increments; no profile torque mode (0x6087, 0x6088) or interpolated position
// mode (0x60C0, 0x60C1), no torque demand 0x6074).
bool maxpos_lacks(uint16_t index, uint8_t) {
    using namespace drive::obj;
    for (uint16_t i : {PositionEncoderIncrements.index, GearMotorRevolutions.index, FeedConstantFeed.index,
                       TorqueSlope.index, TorqueProfileType.index, InterpolationSubMode.index,
                       InterpolationDataPosition.index, TorqueDemand.index})
        if (index == i) return true;
    return false;
}
std::size_t maxpos_lacks_count() {
    std::size_t n = 0;
    for (const drive::ObjInfo& o : drive::cia402_objects())
        if (maxpos_lacks(o.index, o.sub)) ++n;
    return n;
}

// The MAXPOS's 0x6502 (MAXPOS firmware specification Table 7-140): PP, PV, HM, CSP, CSV, CST.
constexpr uint32_t kMaxposModes = 0x000003A5;

}  // namespace

TEST(DriveObjects, EveryHandleResolvesWithItsTypeAccessAndDefault) {
    const od::Dictionary d = drive_dictionary();
    ASSERT_FALSE(drive::cia402_objects().empty());
    for (const drive::ObjInfo& o : drive::cia402_objects()) {
        SCOPED_TRACE(std::string(o.name));
        const od::Entry* e = d.find(o.index, o.sub);
        if (maxpos_lacks(o.index, o.sub)) {
            EXPECT_EQ(e, nullptr);
            continue;
        }
        ASSERT_NE(e, nullptr);
        EXPECT_EQ(e->byte_size(), o.size);
        EXPECT_EQ(od::is_signed(e->type), o.is_signed);
        EXPECT_EQ(od::bit_size(e->type), 8u * o.size);
        // 0x6502: the drive's default announces every mode it implements, the MAXPOS's the six it has.
        const int64_t def = o.index == drive::obj::SupportedDriveModes.index ? kMaxposModes : o.def;
        EXPECT_EQ(e->default_value, o.is_signed ? od::Number{def} : od::Number{static_cast<uint64_t>(def)});
        EXPECT_TRUE(e->readable(od::AlState::Op));
        if (o.role == drive::Role::Command) {
            EXPECT_TRUE(e->writable(od::AlState::Op));
            EXPECT_TRUE(e->rx_mappable());
        }
    }
}

TEST(DriveObjects, TheMaxposBindsEveryVendorParameterWithItsTypeAndTheDriveDefault) {
    const od::Dictionary d = drive_dictionary();
    const drive::VendorObjects& v = maxpos::drive_objects();
    std::size_t count = 0;
#define CHECK_PARAM(name, T, dflt, role)                                            \
    {                                                                               \
        SCOPED_TRACE(#name);                                                        \
        const drive::Binding* b = v.find(drive::Param::name);                       \
        ASSERT_NE(b, nullptr);                                                      \
        const od::Entry* e = d.find(b->index, b->sub);                              \
        ASSERT_NE(e, nullptr);                                                      \
        EXPECT_EQ(e->byte_size(), sizeof(T));                                       \
        EXPECT_EQ(od::is_signed(e->type), std::is_signed_v<T>);                     \
        if (drive::Role::role == drive::Role::Parameter) {                          \
            const T dv = drive::vendor::name.def;                                   \
            if constexpr (std::is_signed_v<T>)                                      \
                EXPECT_EQ(e->default_value, od::Number{static_cast<int64_t>(dv)});  \
            else                                                                    \
                EXPECT_EQ(e->default_value, od::Number{static_cast<uint64_t>(dv)}); \
        }                                                                           \
        ++count;                                                                    \
    }
    DRIVE_VENDOR_PARAMETERS(CHECK_PARAM)
#undef CHECK_PARAM
    EXPECT_EQ(v.bindings.size(), count);
}

TEST(DriveObjects, HandlesAreUnique) {
    const auto all = drive::cia402_objects();
    for (std::size_t i = 0; i < all.size(); ++i)
        for (std::size_t k = i + 1; k < all.size(); ++k) {
            EXPECT_FALSE(all[i].index == all[k].index && all[i].sub == all[k].sub)
                << all[i].name << " " << all[k].name;
            EXPECT_NE(all[i].name, all[k].name);
        }
}

TEST(DriveObjects, TheDriveBindsEveryHandleAndNothingElse) {
    od::Dictionary d = drive_dictionary();
    drive::Drive drv(d, nullptr, maxpos::drive_objects());
    EXPECT_EQ(drv.missing(), maxpos_lacks_count());
    EXPECT_EQ(drv.bound(), drive::cia402_objects().size() - maxpos_lacks_count() +
                               maxpos::drive_objects().bindings.size());
    for (const drive::ObjInfo& o : drive::cia402_objects())
        EXPECT_EQ(drv.binds(o.index, o.sub), !maxpos_lacks(o.index, o.sub)) << o.name;
    for (const drive::Binding& b : maxpos::drive_objects().bindings)
        EXPECT_TRUE(drv.binds(b.index, b.sub)) << drive::param_name(b.param);
    EXPECT_FALSE(drv.binds(0x1000, 0));
}

TEST(DriveObjects, ParametersAndCommandHoldTheDictionaryDefaults) {
    od::Dictionary d = drive_dictionary();
    drive::Drive drv(d, nullptr, maxpos::drive_objects());
    drv.cycle(0, 0);  // loads every bound input from the dictionary's defaults
    drive::Parameters expected;
    expected.supported_modes = kMaxposModes;
    EXPECT_EQ(drv.axis().params, expected);
    EXPECT_EQ(drv.axis().command, drive::Command{});
    // The comparison sees a differing value.
    ASSERT_EQ(d.set<uint8_t>(0x3142, 4, 26), od::Status::Ok);
    drv.cycle(0, 0);
    EXPECT_NE(drv.axis().params, drive::Parameters{});
    EXPECT_EQ(drv.axis().params.input_function[3], 26);
}

// 0x6502 = 0 (an ESI default of a device that reports its modes itself) announces nothing: the modes the
// drive implements are taken; a 0x6502 that announces some restricts to those.
TEST(DriveObjects, SupportedDriveModesZeroStatesNothing) {
    EXPECT_TRUE(drive::mode::supported(8, 0));
    EXPECT_TRUE(drive::mode::supported(1, 0));
    EXPECT_FALSE(drive::mode::supported(8, 0x00000001));  // PP only
    EXPECT_FALSE(drive::mode::supported(42, 0));
}

TEST(DriveObjects, ModesOfOperationAreOneSet) {
    od::Dictionary d = drive_dictionary();
    for (int m = -128; m <= 127; ++m) {
        const bool listed = drive::contains(drive::kModesOfOperation, m);
        EXPECT_EQ(drive::mode::supported(static_cast<int8_t>(m)), listed) << m;
        // The MAXPOS's own set: the drive's without profile torque and interpolated position.
        const bool maxpos = drive::contains(maxpos::kModesOfOperation, m);
        EXPECT_TRUE(listed || !maxpos) << m;
        EXPECT_EQ(maxpos,
                  listed && m != drive::modes::ProfileTorque && m != drive::modes::InterpolatedPosition)
            << m;
        const od::Status s =
            master_write(d, drive::obj::ModesOfOperation.index, drive::obj::ModesOfOperation.sub, m, 1);
        EXPECT_EQ(s == od::Status::Ok, maxpos) << m;
    }
    // 0x6502: PP, PV, HM, CSP, CSV, CST (IEC 61800-7-201 bit assignment), with the drive on it as well.
    EXPECT_EQ(d.get<uint32_t>(drive::obj::SupportedDriveModes.index, 0), 0x000003A5u);
    drive::Drive drv(d, nullptr, maxpos::drive_objects());
    EXPECT_EQ(d.get<uint32_t>(drive::obj::SupportedDriveModes.index, 0), 0x000003A5u);
    EXPECT_EQ(drv.withheld_modes(), 0u);
}

TEST(DriveObjects, HomingMethodsAreOneSet) {
    od::Dictionary d = drive_dictionary();
    for (std::size_t k = 0; k < drive::kHomingMethods.size(); ++k)
        EXPECT_EQ(d.get<int16_t>(maxpos::obj::SupportedHomingMethods, static_cast<uint8_t>(k + 1)),
                  drive::kHomingMethods[k]);
    EXPECT_EQ(
        d.find(maxpos::obj::SupportedHomingMethods, static_cast<uint8_t>(drive::kHomingMethods.size() + 1)),
        nullptr);
    for (int m = -128; m <= 127; ++m) {
        const od::Status s =
            master_write(d, drive::obj::HomingMethod.index, drive::obj::HomingMethod.sub, m, 1);
        EXPECT_EQ(s == od::Status::Ok, drive::contains(drive::kHomingMethods, m)) << m;
    }
}

TEST(DriveObjects, SyncManagersFollowTheirCommunicationTypes) {
    const od::DeviceDescription desc = maxpos::description();
    const od::Dictionary d = maxpos::dictionary(desc);
    ASSERT_EQ(desc.sync_managers.size(), maxpos::kSmCommunicationTypes.size());
    EXPECT_EQ(d.get<uint8_t>(maxpos::obj::SyncManagerCommunicationType, 0),
              maxpos::kSmCommunicationTypes.size());
    for (std::size_t n = 0; n < desc.sync_managers.size(); ++n) {
        const od::SyncManagerDefault& sm = desc.sync_managers[n];
        EXPECT_EQ(sm.kind, maxpos::kSmCommunicationTypes[n]);
        EXPECT_EQ(d.get<uint8_t>(maxpos::obj::SyncManagerCommunicationType, static_cast<uint8_t>(n + 1)),
                  static_cast<uint8_t>(sm.kind));
        EXPECT_EQ(sm.control, od::default_sm_control(sm.kind));
    }
    // The control bytes themselves (ESC register 0x0804): mailbox write/read, buffered write/read.
    EXPECT_EQ(od::default_sm_control(od::SmKind::MBoxOut), 0x26);
    EXPECT_EQ(od::default_sm_control(od::SmKind::MBoxIn), 0x22);
    EXPECT_EQ(od::default_sm_control(od::SmKind::Outputs), 0x64);
    EXPECT_EQ(od::default_sm_control(od::SmKind::Inputs), 0x20);
}
