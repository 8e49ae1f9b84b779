// Process data: the copy plan built from 0x1C12/0x1C13 (0x1C10 + n of every process-data SM) and the mapping
// objects, bit-exact copies, and the SM2 -> dictionary -> application -> dictionary -> SM3 path through LRW
// frames (every SM of a direction where a device has several).
#include <cstring>

#include "fixture.hpp"
#include "support/pdo_objects.hpp"

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

// ---- Several SMs of one direction, PDOs at any index ----------------------------------------------------
// A device with two output SMs (SM2, SM4) and two input SMs (SM3, SM5), each with its own assignment
// (0x1C10 + n) and PDOs whose direction the object model declares wherever their index lies (RxPDO 0x1800,
// TxPDO 0x1C00; EL2262, EL1262): each SM is checked against its own length, and outputs and inputs flow
// through every SM.
using test_support::pdo_array;
using test_support::pdo_var;

class SeveralSms : public StackTest {
  protected:
    void SetUp() override {
        using od::PdoDirection;
        const uint16_t rx = od::access::RW | od::access::RxPdo, tx = od::access::RO | od::access::TxPdo;
        dict = od::Dictionary();
        dict.add(pdo_var(0x7000, od::DataType::Unsigned16, 16, rx));
        dict.add(pdo_var(0x7010, od::DataType::Unsigned8, 8, rx));
        dict.add(pdo_var(0x6000, od::DataType::Unsigned16, 16, tx));
        dict.add(pdo_var(0x6010, od::DataType::Unsigned8, 8, tx));
        dict.add(pdo_array(0x1600, PdoDirection::Rx, od::DataType::Unsigned32, {0x70000010}));
        dict.add(pdo_array(0x1800, PdoDirection::Rx, od::DataType::Unsigned32, {0x70100008}));
        dict.add(pdo_array(0x1A00, PdoDirection::Tx, od::DataType::Unsigned32, {0x60000010}));
        dict.add(pdo_array(0x1C00, PdoDirection::Tx, od::DataType::Unsigned32, {0x60100008}));
        dict.add(pdo_array(0x1C12, PdoDirection::Rx, od::DataType::Unsigned16, {0x1600}));
        dict.add(pdo_array(0x1C13, PdoDirection::Tx, od::DataType::Unsigned16, {0x1A00}));
        dict.add(pdo_array(0x1C14, PdoDirection::Rx, od::DataType::Unsigned16, {0x1800}));
        dict.add(pdo_array(0x1C15, PdoDirection::Tx, od::DataType::Unsigned16, {0x1C00}));
        desc.sync_managers.resize(6);
        const od::SmKind kinds[6] = {od::SmKind::MBoxOut, od::SmKind::MBoxIn,  od::SmKind::Outputs,
                                     od::SmKind::Inputs,  od::SmKind::Outputs, od::SmKind::Inputs};
        const uint16_t starts[6] = {0x1000, 0x1080, 0x1100, 0x1200, 0x1300, 0x1400};
        for (unsigned n = 0; n < 6; ++n) {
            desc.sync_managers[n].kind = kinds[n];
            desc.sync_managers[n].start = starts[n];
            desc.sync_managers[n].control = od::default_sm_control(kinds[n]);
        }
        start();
    }
    // SM2 2 bytes + SM4 1 byte of outputs at kLogical, SM3 2 bytes + SM5 1 byte of inputs behind them.
    void configure_all(uint16_t sm4_length = 1) {
        configure_sm(2, 0x1100, 2, 0x64, true);
        configure_sm(3, 0x1200, 2, 0x20, true);
        configure_sm(4, 0x1300, sm4_length, 0x64, true);
        configure_sm(5, 0x1400, 1, 0x20, true);
        configure_fmmu(0, kLogical, 2, 0x1100, 2);
        configure_fmmu(1, kLogical + 2, 1, 0x1300, 2);
        configure_fmmu(2, kLogical + 3, 2, 0x1200, 1);
        configure_fmmu(3, kLogical + 5, 1, 0x1400, 1);
        rx_bytes = 3;
        tx_bytes = 3;
    }
};

TEST_F(SeveralSms, EachSmCarriesItsOwnPdosBothWays) {
    go_preop();
    configure_all();
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << "code " << std::hex << al_code();
    const ProcessData& pd = stack->process_data();
    ASSERT_EQ(pd.rx_sms().size(), 2u);
    EXPECT_EQ(pd.rx_sms()[1].sm, 4u);
    EXPECT_EQ(pd.rx_sms()[1].offset, 2u);
    EXPECT_EQ(pd.rx_sms()[1].bytes, 1u);
    ASSERT_EQ(pd.tx_sms().size(), 2u);
    EXPECT_EQ(pd.tx_sms()[1].sm, 5u);
    EXPECT_EQ(pd.rx_bytes(), 3u);
    EXPECT_EQ(pd.tx_bytes(), 3u);
    std::vector<uint8_t> in(3);
    const std::vector<uint8_t> out{0x34, 0x12, 0x56};
    exchange_pd(out, in);
    poll();
    request(0x08);
    ASSERT_EQ(al_status(), 0x08) << "code " << std::hex << al_code();
    app.cycle_hook = [this] {
        // Each input follows its output: the second pair travels through SM4 and SM5 only.
        dict.set<uint16_t>(0x6000, 0, static_cast<uint16_t>(dict.get<uint16_t>(0x7000, 0) + 1));
        dict.set<uint8_t>(0x6010, 0, static_cast<uint8_t>(dict.get<uint8_t>(0x7010, 0) + 1));
    };
    EXPECT_EQ(exchange_pd(out, in), 3);  // read + write
    poll();
    EXPECT_EQ(dict.get<uint16_t>(0x7000, 0), 0x1234);
    EXPECT_EQ(dict.get<uint8_t>(0x7010, 0), 0x56);
    exchange_pd(out, in);
    poll();
    exchange_pd(out, in);
    EXPECT_EQ(in[0] | (in[1] << 8), 0x1235);
    EXPECT_EQ(in[2], 0x57);
    // The SM type object is not written over the TxPDO 0x1C00 (a device without CoE names PDOs so).
    EXPECT_EQ(dict.get<uint32_t>(0x1C00, 1), 0x60100008u);
}

TEST_F(SeveralSms, EachSmIsCheckedAgainstTheLengthOfItsOwnAssignment) {
    go_preop();
    configure_all(2);  // SM4 carries 1 byte, not 2
    request(0x04);
    EXPECT_EQ(al_status(), 0x12);  // Pre-Op with error
    EXPECT_EQ(al_code(), 0x001D);  // invalid output configuration
}

// A master that handles one SM per direction leaves SM4/SM5 off: the first SMs' PDOs are exchanged, the
// others' not, as an unused SM's.
TEST_F(SeveralSms, AFurtherSmTheMasterLeavesOffIsNotExchanged) {
    go_preop();
    configure_all();
    configure_sm(4, 0x1300, 1, 0x64, false);
    configure_sm(5, 0x1400, 1, 0x20, false);
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << "code " << std::hex << al_code();
}

// The first output SM without PDOs (EL4732 assigns none to its first input SM): the next one that carries
// PDOs drives the cycle, so its outputs are seen and taken and Op is reached.
TEST_F(SeveralSms, TheFirstSmThatCarriesPdosDrivesTheCycle) {
    ASSERT_EQ(dict.set<uint8_t>(0x1C12, 0, 0), od::Status::Ok);
    go_preop();
    configure_all();
    configure_sm(2, 0x1100, 2, 0x64, false);  // no PDOs: off
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << "code " << std::hex << al_code();
    std::vector<uint8_t> in(3);
    const std::vector<uint8_t> out{0, 0, 0x56};
    exchange_pd(out, in);
    poll();
    request(0x08);
    for (int i = 0; i < 3 && al_status() != 0x08; ++i) {
        exchange_pd(out, in);
        advance(1'000'000);
    }
    ASSERT_EQ(al_status(), 0x08) << "code " << std::hex << al_code();
    exchange_pd(out, in);
    poll();
    EXPECT_EQ(dict.get<uint8_t>(0x7010, 0), 0x56);
}

// An input SM after the first on the register space (EL1252's Virtual SM over the DC system time 0x0910): the
// device writes nothing there (the master reads the register by an FMMU alone), and the entry its PDO maps
// shows the register's value.
TEST_F(SeveralSms, AnInputSmOnTheRegisterSpaceShowsTheEscsRegisters) {
    const uint16_t tx = od::access::RO | od::access::TxPdo;
    dict.add(pdo_var(0x2000, od::DataType::Unsigned64, 64, tx));
    dict.add(pdo_array(0x1B00, od::PdoDirection::Tx, od::DataType::Unsigned32, {0x20000040}));
    ASSERT_EQ(dict.set<uint16_t>(0x1C15, 1, 0x1B00), od::Status::Ok);
    desc.sync_managers[5].start = 0x0910;
    start();
    go_preop();
    configure_all();
    configure_sm(5, 0x0910, 8, 0x20, false);  // not configured: only an FMMU over the register
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << "code " << std::hex << al_code();
    const uint64_t shown = dict.get<uint64_t>(0x2000, 0);
    EXPECT_NE(shown, 0u);
    EXPECT_EQ(shown, master.rd<uint64_t>(0x0910));
}

// The PDO of an input SM on the register space maps the ESC register itself the way Beckhoff writes it
// (0x1Dxx:yy for register 0xxxyy: EL1202-0100's 0x1D09:90 over 0x0990), an object no dictionary has: the
// device's own process data still runs (the first input SM's data is exchanged, Safe-Op and the inputs as
// without that SM), instead of refusing the mapping (0x0024) or, with device emulation, running without data.
TEST_F(SeveralSms, AnInputSmOnTheRegisterSpaceWhosePdoMapsNoObjectLeavesTheRestRunning) {
    dict.add(pdo_array(0x1B00, od::PdoDirection::Tx, od::DataType::Unsigned32, {0x1D090940}));
    ASSERT_EQ(dict.set<uint16_t>(0x1C15, 1, 0x1B00), od::Status::Ok);
    desc.sync_managers[5].start = 0x0990;
    start();
    go_preop();
    configure_all();
    configure_sm(5, 0x0990, 8, 0x20, false);  // only the first input SM is set up, as a one-SM master does
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << "code " << std::hex << al_code();
    ASSERT_EQ(dict.set<uint16_t>(0x6000, 0, 0x4321), od::Status::Ok);
    std::vector<uint8_t> in(3);
    const std::vector<uint8_t> out(3, 0);
    exchange_pd(out, in);
    poll();
    exchange_pd(out, in);
    EXPECT_EQ(in[0] | (in[1] << 8), 0x4321) << "the first input SM's data";
    EXPECT_EQ(master.rd<uint8_t>(0x0807 + 8 * 3) & 0x01, 0) << "SM3 not deactivated by the PDI";
}

TEST_F(SeveralSms, APdoOfTheOtherDirectionIsRefusedWhereverItsIndexLies) {
    // 0x1C14 (SM4, outputs) assigning the TxPDO 0x1C00: an invalid output mapping.
    ASSERT_EQ(dict.set<uint16_t>(0x1C14, 1, 0x1C00), od::Status::Ok);
    go_preop();
    configure_all();
    request(0x04);
    EXPECT_EQ(al_status(), 0x12);
    EXPECT_EQ(al_code(), 0x0025);
}

}  // namespace
}  // namespace ecat::test
