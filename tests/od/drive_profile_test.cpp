// The drive's dictionary against the MAXPOS firmware specification chapter 7, and the device description.
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <vector>

#include "maxpos/maxpos.hpp"

using namespace od;

namespace {

struct Expected {
    uint16_t index;
    std::vector<uint8_t>
        subs;  // every subindex the specification's object table lists (besides sub 0 of ARRAY/RECORD)
};

// Copied by hand from the specification's object table (chapter 7), so the test is hermetic.
const std::vector<Expected> kSeedTable = {
    {0x1000, {0}},
    {0x1001, {0}},
    {0x1008, {0}},
    {0x1018, {1, 2, 3, 4}},
    {0x10F3, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15}},
    {0x1600, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10}},
    {0x1601, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10}},
    {0x1602, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10}},
    {0x1603, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10}},
    {0x1A00, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10}},
    {0x1A01, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10}},
    {0x1A02, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10}},
    {0x1A03, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10}},
    {0x1C00, {1, 2, 3, 4}},
    {0x1C12, {1, 2, 3, 4}},
    {0x1C13, {1, 2, 3, 4}},
    {0x1C32, {1, 2, 3, 4, 5}},
    {0x1C33, {1, 2, 3, 4, 5}},
    {0x2100, {0}},
    {0x2110, {1, 2, 6}},
    {0x2111, {1, 2, 6}},
    {0x3000, {1, 2, 3, 4, 5}},
    {0x3001, {1, 2, 3, 4, 5}},
    {0x3010, {1, 2, 4}},
    {0x3011, {1, 2, 3}},
    {0x3012, {1, 2, 3, 4, 5, 6, 7, 8}},
    {0x3014, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14}},
    {0x301A, {1, 2}},
    {0x3020, {1, 2, 4}},
    {0x30A0, {1, 2, 3}},
    {0x30A1, {1, 2, 3, 4, 5}},
    {0x30B0, {0}},
    {0x30B1, {0}},
    {0x30B2, {0}},
    {0x30D0, {0}},
    {0x30D1, {0}},
    {0x30D5, {0}},
    {0x30E0, {1, 2, 3}},
    {0x3141, {1, 2}},
    {0x3142, {1, 2, 3, 4, 5, 6}},
    {0x3150, {1, 2}},
    {0x3151, {1, 2, 3}},
    {0x3158, {1, 2}},
    {0x6007, {0}},
    {0x603F, {0}},
    {0x6040, {0}},
    {0x6041, {0}},
    {0x605A, {0}},
    {0x605B, {0}},
    {0x605C, {0}},
    {0x605D, {0}},
    {0x605E, {0}},
    {0x6060, {0}},
    {0x6061, {0}},
    {0x6062, {0}},
    {0x6064, {0}},
    {0x6065, {0}},
    {0x6066, {0}},
    {0x606B, {0}},
    {0x606C, {0}},
    {0x6071, {0}},
    {0x6076, {0}},
    {0x6077, {0}},
    {0x6078, {0}},
    {0x607A, {0}},
    {0x607B, {1, 2}},
    {0x607D, {1, 2}},
    {0x607F, {0}},
    {0x6080, {0}},
    {0x6081, {0}},
    {0x6083, {0}},
    {0x6084, {0}},
    {0x6085, {0}},
    {0x6086, {0}},
    {0x6098, {0}},
    {0x6099, {1, 2}},
    {0x609A, {0}},
    {0x60A8, {0}},
    {0x60A9, {0}},
    {0x60AA, {0}},
    {0x60B0, {0}},
    {0x60B1, {0}},
    {0x60B2, {0}},
    {0x60B8, {0}},
    {0x60B9, {0}},
    {0x60BA, {0}},
    {0x60BB, {0}},
    {0x60C2, {1, 2}},
    {0x60C5, {0}},
    {0x60D0, {1}},
    {0x60D5, {0}},
    {0x60D6, {0}},
    {0x60E3, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15}},
    {0x60E4, {1, 2, 3}},
    {0x60E5, {1, 2, 3, 9, 10, 11}},
    {0x60F4, {0}},
    {0x60FD, {0}},
    {0x60FE, {1}},
    {0x60FF, {0}},
    {0x6402, {0}},
    {0x6502, {0}},
    {0xF000, {1, 2}},
    {0xF010, {1, 2, 3, 4}},
    {0xF050, {1}},
};

class DriveDictionary : public ::testing::Test {
  protected:
    DeviceDescription desc = maxpos::description();
    Dictionary d = maxpos::dictionary(desc);
};

}  // namespace

TEST_F(DriveDictionary, EveryObjectAndSubindexOfTheSeedTableIsPresent) {
    for (const Expected& x : kSeedTable) {
        const Object* o = d.find(x.index);
        ASSERT_NE(o, nullptr) << std::hex << x.index;
        for (uint8_t s : x.subs)
            EXPECT_NE(o->entry(s), nullptr) << std::hex << x.index << ":" << int(s);
        if (o->code != ObjectCode::Var) {
            ASSERT_NE(o->entry(0), nullptr);
            EXPECT_EQ(o->entry(0)->type, DataType::Unsigned8);
        }
    }
}

TEST_F(DriveDictionary, OnlyTheDeclaredExtrasBeyondTheSeed) {
    std::set<uint16_t> seed;
    for (const Expected& x : kSeedTable)
        seed.insert(x.index);
    std::set<uint16_t> extra;
    for (const Object& o : d.objects())
        if (!seed.count(o.index)) extra.insert(o.index);
    EXPECT_EQ(extra, (std::set<uint16_t>{0x1009, 0x100A, 0x1010, 0x1011}));
}

TEST_F(DriveDictionary, ObjectCodesAsTheSeed) {
    for (uint16_t i :
         {0x1018, 0x10F3, 0x1600, 0x1A03, 0x1C32, 0x1C33, 0x3001, 0x3010, 0x3014, 0x30E0, 0x60C2, 0xF000})
        EXPECT_EQ(d.find(i)->code, ObjectCode::Record) << std::hex << i;
    for (uint16_t i : {0x1C00, 0x1C12, 0x1C13, 0x2110, 0x2111, 0x3000, 0x30A0, 0x30A1, 0x3141, 0x3158,
                       0x607B, 0x607D, 0x6099, 0x60D0, 0x60E3, 0x60E4, 0x60E5, 0x60FE, 0xF010, 0xF050})
        EXPECT_EQ(d.find(i)->code, ObjectCode::Array) << std::hex << i;
    EXPECT_EQ(d.find(0x6040)->code, ObjectCode::Var);
    EXPECT_EQ(d.find(0x1018)->type, DataType::Identity);
    EXPECT_EQ(d.find(0x1600)->type, DataType::PdoMapping);
    EXPECT_EQ(d.find(0x1C12)->type, DataType::Unsigned16);
}

TEST_F(DriveDictionary, SubindexZeroIsTheHighestSubindex) {
    for (const Object& o : d.objects()) {
        if (o.code == ObjectCode::Var) continue;
        const bool count_object = (o.index >= 0x1600 && o.index <= 0x1603) ||
                                  (o.index >= 0x1A00 && o.index <= 0x1A03) || o.index == 0x1C12 ||
                                  o.index == 0x1C13;
        if (count_object) continue;  // "number of mapped / assigned objects"
        EXPECT_EQ(d.get<uint8_t>(o.index, 0), o.max_subindex()) << std::hex << o.index;
    }
    EXPECT_EQ(d.get<uint8_t>(0x60E5, 0), 11);
    EXPECT_EQ(d.get<uint8_t>(0x3010, 0), 4);
    EXPECT_EQ(d.get<uint8_t>(0x3012, 0), 8);
    EXPECT_EQ(d.get<uint8_t>(0x10F3, 0), 15);
}

TEST_F(DriveDictionary, SampleDefaultsMatchTheSeed) {
    EXPECT_EQ(d.get<uint32_t>(0x1000, 0), 0x00020192u);
    EXPECT_EQ(d.get<uint8_t>(0x1C00, 1), 1);
    EXPECT_EQ(d.get<uint8_t>(0x1C00, 4), 4);
    EXPECT_EQ(d.get<uint16_t>(0x1C12, 1), 0x1600);
    EXPECT_EQ(d.get<uint16_t>(0x1C13, 4), 0x1A03);
    EXPECT_EQ(d.get<uint8_t>(0x1C12, 0), 1);
    EXPECT_EQ(d.get<uint32_t>(0x1C32, 2), 1000000u);
    EXPECT_EQ(d.get<uint32_t>(0x1C33, 3), 50000u);
    EXPECT_EQ(d.get<uint16_t>(0x1C32, 4), 0x0006);
    EXPECT_EQ(d.get<uint32_t>(0x1C33, 5), 100000u);
    EXPECT_EQ(d.get<uint32_t>(0x3000, 1), 0x00100001u);
    EXPECT_EQ(d.get<uint16_t>(0x3001, 2), 15000);
    EXPECT_EQ(d.get<uint32_t>(0x3012, 2), 0x000C0D00u);
    EXPECT_EQ(d.get<uint16_t>(0x3014, 3), 4687);
    EXPECT_EQ(d.get<uint32_t>(0x3014, 9), 0x00430010u);
    EXPECT_EQ(d.get<uint32_t>(0x30A1, 3), 1000000u);
    EXPECT_EQ(d.get<uint8_t>(0x3142, 4), 19);
    EXPECT_EQ(d.get<uint8_t>(0x3151, 3), 18);
    EXPECT_EQ(d.get<int16_t>(0x6007, 0), 3);
    EXPECT_EQ(d.get<int16_t>(0x605E, 0), 2);
    EXPECT_EQ(d.get<int8_t>(0x6060, 0), 8);
    EXPECT_EQ(d.get<int8_t>(0x6061, 0), 1);
    EXPECT_EQ(d.get<uint32_t>(0x6065, 0), 2000u);
    EXPECT_EQ(d.get<int32_t>(0x607B, 1), INT32_MIN);
    EXPECT_EQ(d.get<int32_t>(0x607D, 2), INT32_MAX);
    EXPECT_EQ(d.get<uint32_t>(0x6085, 0), 15000u);
    EXPECT_EQ(d.get<int8_t>(0x6098, 0), 37);
    EXPECT_EQ(d.get<uint32_t>(0x60A8, 0), 0x00B50000u);
    EXPECT_EQ(d.get<int8_t>(0x60C2, 2), -3);
    EXPECT_EQ(d.get<uint32_t>(0x60C5, 0), 4294967295u);
    EXPECT_EQ(d.get<int16_t>(0x60E3, 8), 27);
    EXPECT_EQ(d.get<int16_t>(0x60E3, 15), -4);
    EXPECT_EQ(d.get<uint16_t>(0x6402, 0), 10);
    EXPECT_EQ(d.get<uint32_t>(0x6502, 0), 0x000003A5u);
    EXPECT_EQ(d.get<uint16_t>(0xF000, 1), 0x10);
    EXPECT_EQ(d.get<uint32_t>(0xF010, 3), 0x003002E6u);
    EXPECT_EQ(d.get<uint32_t>(0xF050, 1), 0x001002E6u);
    EXPECT_EQ(d.get<uint32_t>(0x1010, 1), 1u);
}

TEST_F(DriveDictionary, AccessAndFlagsAsTheSeed) {
    const Entry* cw = d.find(0x6040, 0);
    EXPECT_TRUE(cw->rx_mappable());
    EXPECT_FALSE(cw->backup());
    EXPECT_TRUE(d.find(0x6041, 0)->tx_mappable());
    EXPECT_FALSE(d.find(0x6041, 0)->rx_mappable());
    EXPECT_TRUE(d.find(0x6065, 0)->backup());
    EXPECT_EQ(d.find(0x6076, 0)->access & access::WriteMask, 0);  // decisions: RO
    EXPECT_EQ(d.find(0x6077, 0)->access & access::WriteMask, 0);
    EXPECT_EQ(d.find(0x1000, 0)->access, access::RO);
    EXPECT_TRUE(d.find(0x10F3, 4)->tx_mappable());
    EXPECT_EQ(d.find(0x6080, 0)->access & (access::RxPdo | access::TxPdo), 0);
    // PDO mapping and assignment: writable only in Pre-Op, stored
    for (uint16_t i : {0x1600, 0x1601, 0x1602, 0x1603, 0x1A00, 0x1A01, 0x1A02, 0x1A03, 0x1C12, 0x1C13}) {
        for (const Entry& e : d.find(i)->entries) {
            EXPECT_EQ(e.access, access::RW_PreOp | access::Backup) << std::hex << i << ":" << int(e.subindex);
        }
    }
    const uint8_t zero[1] = {0};
    EXPECT_EQ(d.write(0x1600, 0, AlState::SafeOp, zero), Status::WrongState);
    EXPECT_EQ(d.write(0x1600, 0, AlState::Op, zero), Status::WrongState);
    EXPECT_EQ(d.write(0x1600, 0, AlState::PreOp, zero), Status::Ok);
    const uint8_t eleven[1] = {11};
    EXPECT_EQ(d.write(0x1600, 0, AlState::PreOp, eleven), Status::ValueTooHigh);
    const uint8_t five[1] = {5};
    EXPECT_EQ(d.write(0x1C12, 0, AlState::PreOp, five), Status::ValueTooHigh);
    const uint8_t pdo_1A00[2] = {0x00, 0x1A};
    EXPECT_EQ(d.write(0x1C12, 1, AlState::PreOp, pdo_1A00), Status::ValueTooHigh);
    const uint8_t pdo_1500[2] = {0x00, 0x15};
    EXPECT_EQ(d.write(0x1C12, 1, AlState::PreOp, pdo_1500), Status::ValueTooLow);
    const uint8_t pdo_1603[2] = {0x03, 0x16};
    EXPECT_EQ(d.write(0x1C12, 1, AlState::PreOp, pdo_1603), Status::Ok);
}

TEST_F(DriveDictionary, DefaultMappingsReferenceMappableObjectsWithTheirLengths) {
    for (uint16_t pdo : {0x1600, 0x1601, 0x1602, 0x1603, 0x1A00, 0x1A01, 0x1A02, 0x1A03}) {
        const bool rx = pdo < 0x1A00;
        const uint8_t n = d.get<uint8_t>(pdo, 0);
        ASSERT_GE(n, 1);
        for (uint8_t s = 1; s <= 10; ++s) {
            const uint32_t m = d.get<uint32_t>(pdo, s);
            if (s > n) {
                EXPECT_EQ(m, 0u) << std::hex << pdo << ":" << int(s);  // nothing listed past the count
                continue;
            }
            const Entry* e = d.find(static_cast<uint16_t>(m >> 16), static_cast<uint8_t>(m >> 8));
            ASSERT_NE(e, nullptr) << std::hex << m;
            EXPECT_EQ(e->bit_length, m & 0xFF) << std::hex << m;
            EXPECT_TRUE(rx ? e->rx_mappable() : e->tx_mappable()) << std::hex << m;
        }
    }
    EXPECT_EQ(d.get<uint8_t>(0x1600, 0), 8);
    EXPECT_EQ(d.get<uint8_t>(0x1601, 0), 7);
    EXPECT_EQ(d.get<uint8_t>(0x1602, 0), 6);
    EXPECT_EQ(d.get<uint8_t>(0x1603, 0), 8);
    EXPECT_EQ(d.get<uint8_t>(0x1A00, 0), 9);
    EXPECT_EQ(d.get<uint8_t>(0x1A03, 0), 7);
    EXPECT_EQ(d.get<uint32_t>(0x1600, 8), 0x60B80010u);
    EXPECT_EQ(d.get<uint32_t>(0x1A03, 5), 0x60F40020u);
}

TEST_F(DriveDictionary, SeedValueListsAreEnforced) {
    const uint8_t mode5[1] = {5};
    EXPECT_EQ(d.write(0x6060, 0, AlState::Op, mode5), Status::InvalidValue);
    const uint8_t mode9[1] = {9};
    EXPECT_EQ(d.write(0x6060, 0, AlState::Op, mode9), Status::Ok);
    const uint8_t hm_minus4[1] = {0xFC};
    EXPECT_EQ(d.write(0x6098, 0, AlState::Op, hm_minus4), Status::Ok);
    const uint8_t hm_3[1] = {3};
    EXPECT_EQ(d.write(0x6098, 0, AlState::Op, hm_3), Status::InvalidValue);
    const uint8_t sm_34[2] = {34, 0};
    EXPECT_EQ(d.write(0x1C33, 1, AlState::PreOp, sm_34), Status::Ok);
    EXPECT_EQ(d.write(0x1C32, 1, AlState::PreOp, sm_34), Status::ValueTooHigh);
    const uint8_t sm_0[2] = {0, 0};
    EXPECT_EQ(d.write(0x1C32, 1, AlState::PreOp, sm_0), Status::ValueTooLow);  // free run not supported
    const uint8_t sm_1[2] = {1, 0};
    EXPECT_EQ(d.write(0x1C32, 1, AlState::SafeOp, sm_1), Status::WrongState);
    const uint8_t ctrl_0x41[4] = {0x41, 0, 0, 0};
    EXPECT_EQ(d.write(0x3000, 2, AlState::PreOp, ctrl_0x41), Status::InvalidValue);
    const uint8_t motor_2[2] = {2, 0};
    EXPECT_EQ(d.write(0x6402, 0, AlState::PreOp, motor_2), Status::InvalidValue);
    const uint8_t qs_5[2] = {5, 0};
    EXPECT_EQ(d.write(0x605A, 0, AlState::PreOp, qs_5), Status::ValueTooLow);
    const uint8_t tv[4] = {0x41, 0x0D, 0x03, 0x00};  // 200'001
    EXPECT_EQ(d.write(0x60FF, 0, AlState::Op, tv), Status::ValueTooHigh);
}

TEST_F(DriveDictionary, IdentityObjectsComeFromTheDescription) {
    EXPECT_EQ(d.get<uint32_t>(0x1018, 1), desc.identity.vendor_id);
    EXPECT_EQ(d.get<uint32_t>(0x1018, 2), desc.identity.product_code);
    EXPECT_EQ(d.get<uint32_t>(0x1018, 3), desc.identity.revision);
    EXPECT_EQ(d.get<uint32_t>(0x1018, 4), desc.identity.serial_number);
    auto name = d.raw(0x1008, 0);
    EXPECT_EQ(std::string(name.begin(), name.end()), "MAXPOS");

    DeviceDescription other = desc;
    other.identity.vendor_id = 0x12345678;
    other.identity.product_code = 0x30020001;
    other.identity.revision = 0x01300002;
    other.identity.serial_number = 0x00C0FFEE;
    other.identity.device_name = "MAXPOS 50/5 soft";
    other.identity.hardware_version = "HW 3002h";
    other.identity.software_version = "FW 0130h";
    Dictionary o = maxpos::dictionary(other);
    EXPECT_EQ(o.get<uint32_t>(0x1018, 1), 0x12345678u);
    EXPECT_EQ(o.get<uint32_t>(0x1018, 2), 0x30020001u);
    EXPECT_EQ(o.get<uint32_t>(0x1018, 3), 0x01300002u);
    EXPECT_EQ(o.get<uint32_t>(0x1018, 4), 0x00C0FFEEu);
    EXPECT_EQ(o.get<uint64_t>(0x2100, 0), 0x00C0FFEEu);
    auto n = o.raw(0x1008, 0);
    EXPECT_EQ(std::string(n.begin(), n.end()), "MAXPOS 50/5 soft");
    auto hw = o.raw(0x1009, 0);
    EXPECT_EQ(std::string(hw.begin(), hw.end()), "HW 3002h");
    auto sw = o.raw(0x100A, 0);
    EXPECT_EQ(std::string(sw.begin(), sw.end()), "FW 0130h");
}

TEST_F(DriveDictionary, DiagnosisHistoryMessages) {
    EXPECT_EQ(d.get<uint8_t>(0x10F3, 1), maxpos::kDiagMaxMessages);
    for (uint8_t s = 6; s < 6 + maxpos::kDiagMaxMessages; ++s) {
        const Entry* e = d.find(0x10F3, s);
        ASSERT_NE(e, nullptr);
        EXPECT_EQ(e->type, DataType::OctetString);
        EXPECT_EQ(e->byte_size(), maxpos::kDiagMessageBytes);
        EXPECT_TRUE(d.raw(0x10F3, s).empty());
    }
    uint8_t msg[20] = {0x31, 0x83, 0, 0};
    EXPECT_EQ(d.set_raw(0x10F3, 6, msg), Status::Ok);
    EXPECT_EQ(d.raw(0x10F3, 6).size(), 20u);
    const uint8_t flags16[2] = {16, 0};
    EXPECT_EQ(d.write(0x10F3, 5, AlState::PreOp, flags16), Status::ValueTooHigh);
}

TEST(DriveDescription, DefaultsAsDecided) {
    const DeviceDescription d = maxpos::description();
    EXPECT_EQ(d.identity.vendor_id, 0xFBu);
    EXPECT_EQ(d.identity.product_code, 0x30010000u);
    EXPECT_EQ(d.identity.revision, 0x01200000u);
    EXPECT_EQ(d.identity.device_name, "MAXPOS");
    EXPECT_EQ(d.mailbox_protocols, mailbox_protocol::CoE | mailbox_protocol::FoE);
    ASSERT_EQ(d.sync_managers.size(), 4u);
    const uint8_t control[4] = {0x26, 0x22, 0x64, 0x20};
    const SmKind kind[4] = {SmKind::MBoxOut, SmKind::MBoxIn, SmKind::Outputs, SmKind::Inputs};
    for (int i = 0; i < 4; ++i) {
        EXPECT_EQ(d.sync_managers[i].control, control[i]);
        EXPECT_EQ(d.sync_managers[i].kind, kind[i]);
    }
    EXPECT_EQ(d.sync_managers[0].start, d.standard_mailbox.out_start);
    EXPECT_EQ(d.sync_managers[0].default_size, 128);
    EXPECT_EQ(d.sync_managers[1].start, d.standard_mailbox.in_start);
    EXPECT_EQ(d.sync_managers[2].default_size, 23);  // RxPDO1: 184 bits
    EXPECT_EQ(d.sync_managers[3].default_size, 27);  // TxPDO1: 216 bits
    // process-data areas (3 buffers of the largest image) do not overlap the mailboxes or each other
    EXPECT_GE(d.sync_managers[2].start, d.standard_mailbox.in_start + d.standard_mailbox.in_size);
    EXPECT_GE(d.sync_managers[3].start, d.sync_managers[2].start + 3 * 160);
    ASSERT_EQ(d.dc_modes.size(), 2u);
    EXPECT_EQ(d.dc_modes[0].assign_activate, 0x0000);
    EXPECT_EQ(d.dc_modes[1].assign_activate, 0x0300);
    EXPECT_EQ(d.eeprom_bytes, 2048);
}
