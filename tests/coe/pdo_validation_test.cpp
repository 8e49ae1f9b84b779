// PDO mapping and assignment checks (MAXPOS firmware specification §7.2.6-16; ETG.1000.6 mapping entry
// format).
#include <gtest/gtest.h>

#include "coe/pdo_validation.hpp"
#include "coe/sdo_server.hpp"
#include "coe_test_support.hpp"
#include "maxpos/maxpos.hpp"
#include "support/pdo_objects.hpp"

using namespace coe_test;

namespace {

// An expedited download of `bytes` (1..4) bytes through the server: 0 for a download response, the abort code
// otherwise.
uint32_t expedited_download(coe::CoeServer& server, RecordingSender& out, uint16_t index, uint8_t sub,
                            uint32_t value, uint8_t bytes) {
    static const uint8_t cmd[] = {0, 0x2F, 0x2B, 0x27, 0x23};
    server.handle(sdo(cmd[bytes], index, sub, value), out);
    EXPECT_EQ(out.messages.size(), 1u);
    Bytes r = out.take().payload;
    return r[2] == 0x80 ? le32(r, 6) : 0;
}

class PdoChecks : public ::testing::Test {
  protected:
    od::Dictionary dict = make_test_dictionary();
    od::AlState state = od::AlState::PreOp;
    coe::CoeServer server{dict, [this] { return state; }};
    RecordingSender out;

    void SetUp() override { coe::install_pdo_validators(dict, coe::PdoLimits{16}); }

    uint32_t write(uint16_t index, uint8_t sub, uint32_t value, uint8_t bytes) {
        return expedited_download(server, out, index, sub, value, bytes);
    }
};

TEST_F(PdoChecks, MasterRemapSequenceIsAccepted) {
    // zub MACS sequence (EPOS4 Application Notes §6.4.3), in Pre-Op.
    EXPECT_EQ(write(0x1C12, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1C13, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1A00, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1A00, 1, 0x60410010, 4), 0u);
    EXPECT_EQ(write(0x1A00, 2, 0x60640020, 4), 0u);
    EXPECT_EQ(write(0x1A00, 0, 2, 1), 0u);
    EXPECT_EQ(write(0x1600, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1600, 1, 0x60400010, 4), 0u);
    EXPECT_EQ(write(0x1600, 2, 0x607A0020, 4), 0u);
    EXPECT_EQ(write(0x1600, 3, 0x60600008, 4), 0u);
    EXPECT_EQ(write(0x1600, 0, 3, 1), 0u);
    EXPECT_EQ(write(0x1C12, 1, 0x1600, 2), 0u);
    EXPECT_EQ(write(0x1C12, 0, 1, 1), 0u);
    EXPECT_EQ(write(0x1C13, 1, 0x1A00, 2), 0u);
    EXPECT_EQ(write(0x1C13, 0, 1, 1), 0u);
    EXPECT_EQ(coe::mapped_bits(dict, 0x1600), 56u);
    EXPECT_EQ(coe::mapped_bits(dict, 0x1A00), 48u);
}

TEST_F(PdoChecks, MappingEntriesMustBeMappableInTheirDirectionWithTheirLength) {
    EXPECT_EQ(write(0x1600, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1A00, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1600, 1, 0x60410010, 4), 0x06040041u);  // TxPDO-only object in an RxPDO
    EXPECT_EQ(write(0x1A00, 1, 0x60400010, 4), 0x06040041u);  // RxPDO-only object in a TxPDO
    EXPECT_EQ(write(0x1600, 1, 0x60400020, 4), 0x06040041u);  // wrong bit length
    EXPECT_EQ(write(0x1600, 1, 0x70000010, 4), 0x06040041u);  // no such object
    EXPECT_EQ(write(0x1600, 1, 0x60400110, 4), 0x06040041u);  // no such subindex
    EXPECT_EQ(write(0x1600, 1, 0x10000020, 4), 0x06040041u);  // exists, not mappable
    EXPECT_EQ(write(0x1600, 1, 0x60400000, 4), 0x06040041u);  // zero length
    EXPECT_EQ(write(0x1600, 1, 0x00000008, 4), 0u);           // an 8-bit gap
    EXPECT_EQ(write(0x1600, 1, 0, 4), 0u);                    // cleared entry
    EXPECT_EQ(dict.get<uint32_t>(0x1600, 1), 0u);
}

TEST_F(PdoChecks, CountCoveringAnInvalidEntryIsRefused) {
    // Entry 1 cleared while the count still says 2: setting the count again must find it invalid.
    EXPECT_EQ(write(0x1600, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1600, 1, 0x60400000 | 0, 4), 0x06040041u);
    ASSERT_EQ(dict.set<uint32_t>(0x1600, 1, 0x12345678), od::Status::Ok);  // device-side garbage
    EXPECT_EQ(write(0x1600, 0, 2, 1), 0x06040041u);
}

TEST_F(PdoChecks, CountAboveTheDeclaredEntriesIsTooHigh) {
    EXPECT_EQ(write(0x1600, 0, 5, 1), 0x06090031u);
}

TEST_F(PdoChecks, PdoLongerThanTheSyncManagerIsRefused) {
    // Limit 16 bytes: 0x1600 with 4 x 32 bits = 16 bytes fits, with 0x1601 assigned too it does not.
    EXPECT_EQ(write(0x1600, 0, 0, 1), 0u);
    for (uint8_t s = 1; s <= 4; ++s)
        EXPECT_EQ(write(0x1600, s, 0x607A0020, 4), 0u);
    EXPECT_EQ(write(0x1600, 0, 4, 1), 0u);
    EXPECT_EQ(write(0x1C12, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1C12, 2, 0x1601, 2), 0u);
    EXPECT_EQ(write(0x1C12, 0, 2, 1), 0x06040042u);
    EXPECT_EQ(write(0x1C12, 0, 1, 1), 0u);
    // Growing an assigned PDO beyond the SyncManager's room is refused at its count too.
    coe::install_pdo_validators(dict, coe::PdoLimits{8});
    EXPECT_EQ(write(0x1600, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1600, 0, 3, 1), 0x06040042u);
}

TEST_F(PdoChecks, AssignmentOnlyTakesMappingObjectsOfItsDirection) {
    EXPECT_EQ(write(0x1C12, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1C13, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1C12, 1, 0x1A00, 2), 0x06090030u);
    EXPECT_EQ(write(0x1C12, 1, 0x1602, 2), 0x06090030u);  // not declared
    EXPECT_EQ(write(0x1C13, 1, 0x1600, 2), 0x06090030u);
    EXPECT_EQ(write(0x1C12, 1, 0x2000, 2), 0x06090030u);
    EXPECT_EQ(write(0x1C12, 1, 0x1601, 2), 0u);
}

TEST_F(PdoChecks, AssignmentCountChecksEveryCountedEntry) {
    EXPECT_EQ(write(0x1C12, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1C12, 0, 2, 1), 0x06090030u);  // :02 is 0
    EXPECT_EQ(write(0x1C12, 2, 0x1600, 2), 0u);
    EXPECT_EQ(write(0x1C12, 0, 2, 1), 0x06090030u);  // 0x1600 twice
    EXPECT_EQ(write(0x1C12, 2, 0x1601, 2), 0u);
    EXPECT_EQ(write(0x1C12, 0, 2, 1), 0u);
}

TEST_F(PdoChecks, ConfigurationIsWritableInPreOpOnly) {
    state = od::AlState::SafeOp;
    EXPECT_EQ(write(0x1C12, 0, 0, 1), 0x08000022u);
    EXPECT_EQ(write(0x1600, 1, 0x60400010, 4), 0x08000022u);
    state = od::AlState::Op;
    EXPECT_EQ(write(0x1A00, 0, 0, 1), 0x08000022u);
}

TEST(PdoMappingEntry, Checks) {
    od::Dictionary dict = make_test_dictionary();
    EXPECT_EQ(coe::check_mapping_entry(dict, true, 0x60400010), od::Status::Ok);
    EXPECT_EQ(coe::check_mapping_entry(dict, false, 0x60400010), od::Status::NotMappable);
    EXPECT_EQ(coe::check_mapping_entry(dict, false, 0x10F30401), od::Status::Ok);  // BOOLEAN, 1 bit
    EXPECT_EQ(coe::check_mapping_entry(dict, true, 0x00000110),
              od::Status::NotMappable);  // gap with a subindex
    EXPECT_EQ(coe::mapped_bits(dict, 0x1600), 48u);
    EXPECT_EQ(coe::mapped_bits(dict, 0x1602), 0u);
}

}  // namespace

// The drive's PDO rules (maxpos::description().pdo_rules, the ESI's Exclude): one RxPDO and one
// TxPDO at a time, since each maps the controlword / statusword and the mode.
class DrivePdoRules : public ::testing::Test {
  protected:
    od::DeviceDescription desc = maxpos::description();
    od::Dictionary dict = maxpos::dictionary(desc);
    coe::CoeServer server{dict, [] { return od::AlState::PreOp; }};
    RecordingSender out;

    void SetUp() override { coe::install_pdo_validators(dict, {}, desc.pdo_rules); }

    uint32_t write(uint16_t index, uint8_t sub, uint32_t value, uint8_t bytes) {
        return expedited_download(server, out, index, sub, value, bytes);
    }
};

TEST_F(DrivePdoRules, TwoRxPdosThatExcludeEachOtherAreRefusedWithIncompatible) {
    // 0x1C12 = {0x1600, 0x1601}: the controlword twice (42 output bytes). The declared default of :02 is
    // 0x1601, so writing the count alone tries exactly that.
    EXPECT_EQ(write(0x1C12, 0, 2, 1), 0x06040043u);
    EXPECT_EQ(dict.get<uint8_t>(0x1C12, 0), 1u);  // unchanged
    EXPECT_EQ(write(0x1C12, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1C12, 1, 0x1602, 2), 0u);
    EXPECT_EQ(write(0x1C12, 2, 0x1603, 2), 0u);  // beyond the count: not in force yet
    EXPECT_EQ(write(0x1C12, 0, 2, 1), 0x06040043u);
    EXPECT_EQ(write(0x1C12, 0, 1, 1), 0u);
    // Within the count, an entry cannot replace the PDO in force (subindex 0 must be 0 first).
    EXPECT_EQ(write(0x1C12, 1, 0x1601, 2), 0x06010003u);
    EXPECT_EQ(dict.get<uint16_t>(0x1C12, 1), 0x1602u);
}

// ETG.1000.6 / ETG.1020: the entries of a PDO mapping or assignment object can be written only while its
// subindex 0 is 0 (abort 0x06010003); the class, over every such object the drive declares.
TEST_F(DrivePdoRules, EntriesOfEveryMappingAndAssignmentObjectNeedSubindexZeroAtZero) {
    unsigned checked = 0;
    for (const od::Object& o : dict.objects()) {
        const bool mapping =
            (o.index >= 0x1600 && o.index <= 0x17FF) || (o.index >= 0x1A00 && o.index <= 0x1BFF);
        const bool assign = o.index == 0x1C12 || o.index == 0x1C13;
        if (!mapping && !assign) continue;
        SCOPED_TRACE(o.index);
        const uint8_t bytes = mapping ? 4 : 2;
        const uint8_t count = dict.get<uint8_t>(o.index, 0);
        ASSERT_NE(count, 0u) << "the drive's default mappings and assignments are not empty";
        const uint32_t value = mapping ? dict.get<uint32_t>(o.index, 1) : dict.get<uint16_t>(o.index, 1);
        // The same value as it holds, within and beyond the count: refused while subindex 0 is not 0.
        EXPECT_EQ(write(o.index, 1, value, bytes), 0x06010003u);
        EXPECT_EQ(write(o.index, o.max_subindex(), value, bytes), 0x06010003u);
        EXPECT_EQ(dict.get<uint8_t>(o.index, 0), count);
        // With subindex 0 at 0 the same writes are taken, and the count can be set back.
        EXPECT_EQ(write(o.index, 0, 0, 1), 0u);
        EXPECT_EQ(write(o.index, 1, value, bytes), 0u);
        EXPECT_EQ(write(o.index, 0, count, 1), 0u);
        ++checked;
    }
    EXPECT_EQ(checked, 10u);  // 0x1600-0x1603, 0x1A00-0x1A03, 0x1C12, 0x1C13
}

TEST_F(DrivePdoRules, TxPdosFollowTheSameRule) {
    EXPECT_EQ(write(0x1C13, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1C13, 1, 0x1A00, 2), 0u);
    EXPECT_EQ(write(0x1C13, 2, 0x1A03, 2), 0u);
    EXPECT_EQ(write(0x1C13, 0, 2, 1), 0x06040043u);
    EXPECT_EQ(write(0x1C13, 0, 1, 1), 0u);
    // Count 0 (PDO disabled) is allowed: no PDO of the drive is Mandatory.
    EXPECT_EQ(write(0x1C13, 0, 0, 1), 0u);
}

// A master reassigns as ETG.1000.6 says: count 0, the PDOs, the count. With a Mandatory PDO the first step
// must be taken (an ENI's CoE init commands begin with it); the count that leaves the Mandatory PDO out is
// refused.
class MandatoryPdoRules : public DrivePdoRules {
  protected:
    void SetUp() override {
        desc.pdo_rules = {od::PdoRule{0x1A00, true, {}, std::nullopt}};
        coe::install_pdo_validators(dict, {}, desc.pdo_rules);
    }
};

TEST_F(MandatoryPdoRules, CountZeroOpensTheAssignmentTheCountIsChecked) {
    EXPECT_EQ(write(0x1C13, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1C13, 1, 0x1A01, 2), 0u);
    EXPECT_EQ(write(0x1C13, 0, 1, 1), 0x06040043u);  // 0x1A00 is Mandatory
    EXPECT_EQ(write(0x1C13, 1, 0x1A00, 2), 0u);
    EXPECT_EQ(write(0x1C13, 0, 1, 1), 0u);
}

TEST(PdoRules, MandatoryAndExcludeChecks) {
    const od::Dictionary dict = maxpos::dictionary(maxpos::description());
    std::vector<od::PdoRule> rules(3);
    rules[0].pdo = 0x1600;
    rules[0].mandatory = true;
    rules[1].pdo = 0x1601;
    rules[1].exclude = {0x1602};
    rules[2].pdo = 0x1A00;
    rules[2].mandatory = true;
    const std::vector<uint16_t> ok{0x1600, 0x1601}, no_mandatory{0x1601}, excluded{0x1600, 0x1602, 0x1601};
    EXPECT_EQ(coe::check_pdo_rules(dict, 0x1C12, ok, rules), od::Status::Ok);
    EXPECT_EQ(coe::check_pdo_rules(dict, 0x1C12, no_mandatory, rules), od::Status::Incompatible);
    EXPECT_EQ(coe::check_pdo_rules(dict, 0x1C12, {}, rules), od::Status::Incompatible);
    EXPECT_EQ(coe::check_pdo_rules(dict, 0x1C12, excluded, rules), od::Status::Incompatible);
    // 0x1C13's rules do not apply to 0x1C12 and the other way round.
    const std::vector<uint16_t> tx{0x1A00};
    EXPECT_EQ(coe::check_pdo_rules(dict, 0x1C13, tx, rules), od::Status::Ok);
    EXPECT_EQ(coe::check_pdo_rules(dict, 0x1C13, {}, rules), od::Status::Incompatible);
}

// A PDO's direction is what the object model declares (od::Object::direction), not its index range: the
// evaluation boards' ESIs name an RxPdo 0x1A00 and a TxPdo 0x1600 (from the controller's side), EL1262 a
// TxPdo 0x1C00. The assignment of SM2 takes the RxPDO 0x1A00 and refuses the TxPDO 0x1600, and the mapping
// objects check their entries in their own direction.
TEST(PdoDirection, ComesFromTheObjectModelWhereverTheIndexLies) {
    od::Dictionary dict;
    const uint16_t rx = od::access::RW | od::access::RxPdo, tx = od::access::RO | od::access::TxPdo;
    dict.add(test_support::pdo_var(0x7000, od::DataType::Unsigned16, 16, rx));
    dict.add(test_support::pdo_var(0x6000, od::DataType::Unsigned16, 16, tx));
    auto object = [&](uint16_t index, od::PdoDirection dir, od::DataType type, std::vector<uint64_t> values) {
        dict.add(test_support::pdo_array(index, dir, type, values));
    };
    object(0x1A00, od::PdoDirection::Rx, od::DataType::Unsigned32, {0x70000010});
    object(0x1600, od::PdoDirection::Tx, od::DataType::Unsigned32, {0x60000010});
    object(0x1C00, od::PdoDirection::Tx, od::DataType::Unsigned32, {0x60000010});
    object(0x1C12, od::PdoDirection::Rx, od::DataType::Unsigned16, {0x1A00});
    object(0x1C13, od::PdoDirection::Tx, od::DataType::Unsigned16, {0x1600, 0x1C00});
    EXPECT_TRUE(dict.find(0x1C00)->is_pdo_mapping());
    EXPECT_TRUE(dict.find(0x1C12)->is_pdo_assignment());
    coe::install_pdo_validators(dict);
    coe::CoeServer server{dict, [] { return od::AlState::PreOp; }};
    RecordingSender out;
    auto write = [&](uint16_t index, uint8_t sub, uint32_t value, uint8_t bytes) {
        return expedited_download(server, out, index, sub, value, bytes);
    };
    EXPECT_EQ(write(0x1C12, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1C12, 1, 0x1600, 2), 0x06090030u);  // a TxPDO: not for an outputs SM
    EXPECT_EQ(write(0x1C12, 1, 0x1A00, 2), 0u);           // the RxPDO at 0x1A00
    EXPECT_EQ(write(0x1C12, 0, 1, 1), 0u);
    EXPECT_EQ(write(0x1C13, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1C13, 1, 0x1A00, 2), 0x06090030u);
    EXPECT_EQ(write(0x1C13, 1, 0x1C00, 2), 0u);  // the TxPDO at 0x1C00
    EXPECT_EQ(write(0x1C13, 0, 1, 1), 0u);
    // The RxPDO 0x1A00 maps outputs, not inputs; the TxPDO 0x1600 the other way round.
    EXPECT_EQ(write(0x1A00, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1A00, 1, 0x60000010, 4), 0x06040041u);
    EXPECT_EQ(write(0x1A00, 1, 0x70000010, 4), 0u);
    EXPECT_EQ(write(0x1600, 0, 0, 1), 0u);
    EXPECT_EQ(write(0x1600, 1, 0x70000010, 4), 0x06040041u);
    EXPECT_EQ(write(0x1600, 1, 0x60000010, 4), 0u);
}
