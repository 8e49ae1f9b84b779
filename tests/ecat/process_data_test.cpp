// Process data: the copy plan built from 0x1C12/0x1C13 and the mapping objects, bit-exact copies, and the
// SM2 -> dictionary -> application -> dictionary -> SM3 path through LRW frames.
#include <cstring>

#include "fixture.hpp"

namespace ecat::test {
namespace {

using od::AlState;

TEST(ProcessDataBits, CopyBits_ByteAligned) {
    const uint8_t src[4] = {0x11, 0x22, 0x33, 0x44};
    uint8_t dst[6] = {};
    ProcessData::copy_bits(src, 0, dst, 16, 32);
    EXPECT_EQ(dst[0], 0);
    EXPECT_EQ(dst[1], 0);
    EXPECT_EQ(dst[2], 0x11);
    EXPECT_EQ(dst[5], 0x44);
}

TEST(ProcessDataBits, CopyBits_Unaligned_KeepsNeighbours) {
    const uint8_t src[1] = {0b101};
    uint8_t dst[2] = {0xFF, 0xFF};
    ProcessData::copy_bits(src, 0, dst, 6, 3);  // bits 6,7 of byte 0 and bit 0 of byte 1
    EXPECT_EQ(dst[0], 0b01111111);
    EXPECT_EQ(dst[1], 0xFF);
}

TEST(ProcessDataBits, CopyBits_UnalignedSourceRoundTrip) {
    uint8_t buf[3] = {};
    const uint8_t value[2] = {0xCD, 0xAB};
    ProcessData::copy_bits(value, 0, buf, 3, 16);
    uint8_t back[2] = {};
    ProcessData::copy_bits(buf, 3, back, 0, 16);
    EXPECT_EQ(back[0], 0xCD);
    EXPECT_EQ(back[1], 0xAB);
    EXPECT_EQ(buf[0] & 0x07, 0);
}

TEST(ProcessDataPlan, DefaultMapping) {
    od::Dictionary d = make_dictionary();
    ProcessData pd(d);
    ASSERT_EQ(pd.build(), 0);
    EXPECT_EQ(pd.rx_bits(), 48u);
    EXPECT_EQ(pd.tx_bits(), 48u);
    ASSERT_EQ(pd.rx_plan().size(), 2u);
    EXPECT_EQ(pd.rx_plan()[1].bit_offset, 16u);
    EXPECT_EQ(pd.rx_plan()[1].bits, 32u);
}

TEST(ProcessDataPlan, PaddingTakesBitsButIsNotCopied) {
    od::Dictionary d = make_dictionary();
    ASSERT_EQ(d.set<uint8_t>(0x1600, 0, 3), od::Status::Ok);
    ASSERT_EQ(d.set<uint32_t>(0x1600, 2, 0x00000008), od::Status::Ok);  // 8 bits of padding (index 0)
    ASSERT_EQ(d.set<uint32_t>(0x1600, 3, 0x607A0020), od::Status::Ok);
    ProcessData pd(d);
    ASSERT_EQ(pd.build(), 0);
    EXPECT_EQ(pd.rx_bits(), 56u);
    ASSERT_EQ(pd.rx_plan().size(), 2u);
    EXPECT_EQ(pd.rx_plan()[1].bit_offset, 24u);
}

// A vendor's compact PDO maps an integer entry with fewer bits than it has (Beckhoff EJ7047: 0x6000:11,
// UDINT, in a 16-bit TxPDO entry): the entry says so (pdo_bit_length, from the device's own PDOs), the
// plan copies its low-order bits; another length is still an invalid mapping (ETG.1000.6, 0x0024).
TEST(ProcessDataPlan, CompactMappingOfTheDevicesOwnPdosTakesTheLowBits) {
    od::Dictionary d = make_dictionary();
    od::Object o;
    o.index = 0x2100;
    o.code = od::ObjectCode::Var;
    o.type = od::DataType::Unsigned32;
    o.name = "Counter value";
    od::Entry e;
    e.subindex = 0;
    e.type = od::DataType::Unsigned32;
    e.access = od::access::RO | od::access::TxPdo;
    e.default_value = uint64_t{0x12345678};
    e.pdo_bit_length = 16;
    e.name = o.name;
    o.entries.push_back(e);
    d.add(o);
    ASSERT_EQ(d.set<uint8_t>(0x1A00, 0, 2), od::Status::Ok);
    ASSERT_EQ(d.set<uint32_t>(0x1A00, 2, 0x21000010), od::Status::Ok);
    ProcessData pd(d);
    ASSERT_EQ(pd.build(), 0);
    EXPECT_EQ(pd.tx_bits(), 32u);
    std::vector<uint8_t> in(4, 0xEE);
    pd.dictionary_to_inputs(in);
    EXPECT_EQ(in[2], 0x78);
    EXPECT_EQ(in[3], 0x56);
    ASSERT_EQ(d.set<uint32_t>(0x1A00, 2, 0x21000008), od::Status::Ok);  // 8 bits: not a length it has
    EXPECT_EQ(pd.build(), 0x0024);
}

TEST(ProcessDataPlan, MissingObject_0x0025) {
    od::Dictionary d = make_dictionary();
    ASSERT_EQ(d.set<uint32_t>(0x1600, 1, 0x50000010), od::Status::Ok);
    ProcessData pd(d);
    EXPECT_EQ(pd.build(), 0x0025);
    EXPECT_EQ(pd.rx_bytes(), 0u);
}

TEST(ProcessDataPlan, NotTxMappable_0x0024) {
    od::Dictionary d = make_dictionary();
    ASSERT_EQ(d.set<uint32_t>(0x1A00, 1, 0x60400010), od::Status::Ok);
    ProcessData pd(d);
    EXPECT_EQ(pd.build(), 0x0024);
}

TEST(ProcessDataPlan, AssignedMappingObjectMissing_0x0024) {
    od::Dictionary d = make_dictionary();
    ASSERT_EQ(d.set<uint16_t>(0x1C13, 1, 0x1A05), od::Status::Ok);
    ProcessData pd(d);
    EXPECT_EQ(pd.build(), 0x0024);
}

TEST(ProcessDataPlan, EmptyAssignment_NoProcessData) {
    od::Dictionary d = make_dictionary();
    ASSERT_EQ(d.set<uint8_t>(0x1C12, 0, 0), od::Status::Ok);
    ASSERT_EQ(d.set<uint8_t>(0x1C13, 0, 0), od::Status::Ok);
    ProcessData pd(d);
    ASSERT_EQ(pd.build(), 0);
    EXPECT_EQ(pd.rx_bytes(), 0u);
    EXPECT_EQ(pd.tx_bytes(), 0u);
}

using ProcessDataLrw = StackTest;

std::vector<uint8_t> outputs(uint16_t control, int32_t target) {
    std::vector<uint8_t> o(6);
    o[0] = static_cast<uint8_t>(control);
    o[1] = static_cast<uint8_t>(control >> 8);
    for (int i = 0; i < 4; ++i)
        o[2 + i] = static_cast<uint8_t>(static_cast<uint32_t>(target) >> (8 * i));
    return o;
}

TEST_F(ProcessDataLrw, Op_OutputsToDictionaryAndInputsFromIt) {
    go_op();
    app.cycle_hook = [this] {
        // The "drive": statusword = controlword | 0x8000, position = 2 x target.
        dict.set<uint16_t>(0x6041, 0, static_cast<uint16_t>(dict.get<uint16_t>(0x6040, 0) | 0x8000));
        dict.set<int32_t>(0x6064, 0, 2 * dict.get<int32_t>(0x607A, 0));
    };
    std::vector<uint8_t> in(6);
    const auto out = outputs(0x000F, -1000);
    EXPECT_EQ(exchange_pd(out, in), 3);  // read + write
    poll();
    EXPECT_EQ(dict.get<uint16_t>(0x6040, 0), 0x000F);
    EXPECT_EQ(dict.get<int32_t>(0x607A, 0), -1000);
    exchange_pd(out, in);
    EXPECT_EQ(in[0] | (in[1] << 8), 0x800F);
    int32_t pos = 0;
    std::memcpy(&pos, in.data() + 2, 4);
    EXPECT_EQ(pos, -2000);
}

TEST_F(ProcessDataLrw, SafeOp_OutputsIgnoredInputsValid) {
    go_safeop();
    dict.set<uint16_t>(0x6041, 0, 0x0237);
    std::vector<uint8_t> in(6);
    exchange_pd(outputs(0x000F, 5), in);
    poll();
    EXPECT_EQ(dict.get<uint16_t>(0x6040, 0), 0);  // ignored in Safe-Op
    EXPECT_GE(app.cycles, 1);
    exchange_pd(outputs(0x000F, 5), in);
    EXPECT_EQ(in[0] | (in[1] << 8), 0x0237);
}

TEST_F(ProcessDataLrw, SafeOp_InputsValidBeforeFirstCycle) {
    dict.set<int32_t>(0x6064, 0, 0x01020304);
    go_safeop();
    std::vector<uint8_t> in(6);
    exchange_pd(outputs(0, 0), in);
    EXPECT_EQ(in[2], 0x04);
    EXPECT_EQ(in[5], 0x01);
}

TEST_F(ProcessDataLrw, BitLevelMapping_Remapped_InPreOp) {
    go_preop();
    // RxPDO 0x1601: 0x2000:01 (1 bit), 0x2000:02 (1 bit), 6 bits padding, 0x6040 (16 bits) -> 3 bytes.
    // TxPDO 0x1A01: 0x2000:03 (1 bit), 7 bits padding, 0x6041 (16 bits) -> 3 bytes.
    auto w8 = [&](uint16_t i, uint8_t s, uint8_t v) {
        return dict.write(i, s, AlState::PreOp, std::vector<uint8_t>{v});
    };
    auto w16 = [&](uint16_t i, uint8_t s, uint16_t v) {
        return dict.write(i, s, AlState::PreOp,
                          std::vector<uint8_t>{static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8)});
    };
    auto w32 = [&](uint16_t i, uint8_t s, uint32_t v) {
        std::vector<uint8_t> b(4);
        for (int k = 0; k < 4; ++k)
            b[k] = static_cast<uint8_t>(v >> (8 * k));
        return dict.write(i, s, AlState::PreOp, b);
    };
    ASSERT_EQ(w32(0x1601, 1, 0x20000101), od::Status::Ok);
    ASSERT_EQ(w32(0x1601, 2, 0x20000201), od::Status::Ok);
    ASSERT_EQ(w32(0x1601, 3, 0x00000006), od::Status::Ok);
    ASSERT_EQ(w32(0x1601, 4, 0x60400010), od::Status::Ok);
    ASSERT_EQ(w8(0x1601, 0, 4), od::Status::Ok);
    ASSERT_EQ(w32(0x1A01, 1, 0x20000301), od::Status::Ok);
    ASSERT_EQ(w32(0x1A01, 2, 0x00000007), od::Status::Ok);
    ASSERT_EQ(w32(0x1A01, 3, 0x60410010), od::Status::Ok);
    ASSERT_EQ(w8(0x1A01, 0, 3), od::Status::Ok);
    ASSERT_EQ(w8(0x1C12, 0, 0), od::Status::Ok);
    ASSERT_EQ(w16(0x1C12, 1, 0x1601), od::Status::Ok);
    ASSERT_EQ(w8(0x1C12, 0, 1), od::Status::Ok);
    ASSERT_EQ(w8(0x1C13, 0, 0), od::Status::Ok);
    ASSERT_EQ(w16(0x1C13, 1, 0x1A01), od::Status::Ok);
    ASSERT_EQ(w8(0x1C13, 0, 1), od::Status::Ok);

    configure_process_data(3, 3);
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << std::hex << al_code();
    // PDO configuration is Pre-Op only.
    EXPECT_EQ(dict.write(0x1C12, 0, stack->state(), std::vector<uint8_t>{0}), od::Status::WrongState);

    app.cycle_hook = [this] {
        dict.set<uint8_t>(0x2000, 3, dict.get<uint8_t>(0x2000, 2));
        dict.set<uint16_t>(0x6041, 0, dict.get<uint16_t>(0x6040, 0));
    };
    std::vector<uint8_t> in(3);
    const std::vector<uint8_t> out{0b00000010, 0x34, 0x12};
    exchange_pd(out, in);
    poll();
    request(0x08);
    ASSERT_EQ(al_status(), 0x08);
    exchange_pd(out, in);
    poll();
    EXPECT_EQ(dict.get<uint8_t>(0x2000, 1), 0);
    EXPECT_EQ(dict.get<uint8_t>(0x2000, 2), 1);
    EXPECT_EQ(dict.get<uint16_t>(0x6040, 0), 0x1234);
    exchange_pd(out, in);
    EXPECT_EQ(in[0], 0x01);  // 0x2000:03 in bit 0, padding zero
    EXPECT_EQ(in[1], 0x34);
    EXPECT_EQ(in[2], 0x12);
}

TEST_F(ProcessDataLrw, InputsOnly_SmSyncOnSm3Read) {
    go_preop();
    ASSERT_EQ(dict.write(0x1C12, 0, AlState::PreOp, std::vector<uint8_t>{0}), od::Status::Ok);
    configure_process_data(0, 6);
    // FMMU1 maps the inputs at kLogical + 0.
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << std::hex << al_code();
    EXPECT_EQ(stack->sync_mode(), SyncMode::SmSync);
    const int before = app.cycles;
    std::vector<uint8_t> in(6);
    exchange_pd({}, in);
    poll();
    EXPECT_GT(app.cycles, before);
    request(0x08);
    EXPECT_EQ(al_status(), 0x08);  // no outputs to wait for
}

TEST_F(ProcessDataLrw, CycleAllocatesNothing_PlanStable) {
    go_op();
    const auto* plan = stack->process_data().rx_plan().data();
    std::vector<uint8_t> in(6);
    for (int i = 0; i < 100; ++i) {
        exchange_pd(outputs(static_cast<uint16_t>(i), i), in);
        poll();
    }
    EXPECT_EQ(stack->process_data().rx_plan().data(), plan);
    EXPECT_EQ(dict.get<int32_t>(0x607A, 0), 99);
    EXPECT_GE(stack->stats().cycles, 100u);
}

}  // namespace
}  // namespace ecat::test
