// AL control/status handshake and events (ESC datasheet section II, 0x0120-0x0134, 0x0200-0x0220), SII EEPROM
// interface and power-on load (ESC datasheet section I, SII EEPROM interface; SII header words: ETG.2010).
#include <gtest/gtest.h>

#include <optional>

#include "esc_fixture.hpp"

using namespace esc_test;

namespace {

struct EscBasics : EscFixture<> {};

// A valid SII image: header with CRC, identity, a string category.
std::vector<uint8_t> make_image(uint16_t w0, uint16_t w1, uint16_t w2, uint16_t w3, uint16_t alias,
                                bool good_crc = true) {
    std::vector<uint8_t> img(256, 0xFF);
    std::fill(img.begin(), img.begin() + 0x80, 0);
    auto put = [&](unsigned w, uint16_t v) { util::put16(img.data() + 2 * w, v); };
    put(0, w0);
    put(1, w1);
    put(2, w2);
    put(3, w3);
    put(4, alias);
    const uint8_t crc = esc::sii::crc8(img.data(), 14);
    put(7, good_crc ? crc : static_cast<uint8_t>(crc ^ 0x5A));
    put(8, 0x1234);  // vendor id low word
    put(0x0A, 0x5678);
    put(0x3E, 0x0001);
    put(0x3F, 0x0001);
    put(0x40, 0xFFFF);
    return img;
}

// ------------------------------------------------------------------------------------------------ AL

TEST_F(EscBasics, AlControlRaisesEventClearedByPdiRead) {
    EXPECT_FALSE(e->irq());
    EXPECT_EQ(fpwr(*e, 0x0120, {0x02, 0x00}).wkc, 1);
    EXPECT_TRUE(e->irq());
    EXPECT_EQ(e->read_reg<uint32_t>(0x0220) & 1, 1u);  // reading the request register does not clear it
    EXPECT_EQ(e->read_reg<uint16_t>(0x0120), 0x0002);  // reading AL control does
    EXPECT_EQ(e->read_reg<uint32_t>(0x0220) & 1, 0u);
    EXPECT_FALSE(e->irq());
    EXPECT_EQ(fprd(*e, 0x0220, 4).u32() & 1, 0u);
}

TEST_F(EscBasics, AlControlIsAMailboxUntilPdiRead) {
    fpwr(*e, 0x0120, {0x02, 0x00});
    EXPECT_EQ(fpwr(*e, 0x0120, {0x04, 0x00}).wkc, 1);  // accepted on the wire, value not taken
    EXPECT_EQ(fprd(*e, 0x0120, 2).u16(), 0x0002);
    EXPECT_EQ(e->read_reg<uint16_t>(0x0120), 0x0002);
    fpwr(*e, 0x0120, {0x04, 0x00});
    EXPECT_EQ(e->read_reg<uint16_t>(0x0120), 0x0004);
}

TEST_F(EscBasics, AlStatusWrittenByPdiOnly) {
    e->write_reg<uint16_t>(0x0130, 0x0012);
    e->write_reg<uint16_t>(0x0134, 0x0011);
    Datagram d = fprd(*e, 0x0130, 6);
    EXPECT_EQ(d.u16(0), 0x0012);
    EXPECT_EQ(d.u16(4), 0x0011);
    fpwr(*e, 0x0134, {0, 0});
    EXPECT_EQ(fprd(*e, 0x0134, 2).u16(), 0x0011);
}

TEST_F(EscBasics, AlStatusEventForMasterClearedByEcatRead) {
    fpwr(*e, 0x0200, {0x08, 0x00});
    e->write_reg<uint16_t>(0x0130, 0x0002);
    EXPECT_EQ(fprd(*e, 0x0210, 2).u16() & 0x08, 0x08);
    fprd(*e, 0x0130, 2);
    EXPECT_EQ(fprd(*e, 0x0210, 2).u16() & 0x08, 0x00);
}

TEST_F(EscBasics, DeviceEmulationMirrorsAlControl) {
    e->load_eeprom(make_image(0x0105, 0, 0, 0, 0));  // 0x0141 bit 0
    fpwr(*e, 0x0120, {0x02, 0x00});
    EXPECT_EQ(fprd(*e, 0x0130, 2).u16(), 0x0002);
    fpwr(*e, 0x0120, {0x04, 0x00});  // not blocked with emulation
    EXPECT_EQ(fprd(*e, 0x0130, 2).u16(), 0x0004);
    e->write_reg<uint16_t>(0x0130, 0x0008);  // PDI cannot write AL status
    EXPECT_EQ(fprd(*e, 0x0130, 2).u16(), 0x0004);
}

TEST_F(EscBasics, IrqFollowsAlEventMask) {
    fpwr(*e, 0x0120, {0x02, 0x00});
    EXPECT_TRUE(e->irq());
    e->write_reg<uint32_t>(0x0204, 0x00000000);
    EXPECT_FALSE(e->irq());
    EXPECT_EQ(fprd(*e, 0x0204, 4).u32(), 0u);
    fpwr(*e, 0x0204, {0xFF, 0xFF, 0xFF, 0xFF});  // ECAT cannot write the AL event mask
    EXPECT_FALSE(e->irq());
}

// ------------------------------------------------------------------------------------------------ SII

TEST_F(EscBasics, BareEscHasValidBuiltInImage) {
    Datagram d = fprd(*e, 0x0502, 2);
    EXPECT_EQ(d.u16() & 0x1800, 0);       // no checksum error, loaded
    EXPECT_EQ(d.u16() & 0x0060, 0x0060);  // emulated EEPROM, 8-byte reads
    EXPECT_EQ(fprd(*e, 0x0110, 2).u16() & 1, 1);
    auto img = e->eeprom();
    ASSERT_GE(img.size(), 0x82u);
    EXPECT_EQ(img[0x80], 0xFF);
    EXPECT_EQ(img[0x81], 0xFF);
    EXPECT_EQ(fprd(*e, 0x0141, 1).data[0] & 0x0C, 0x0C);
}

TEST_F(EscBasics, SoemStyleRead) {
    e->load_eeprom(make_image(0x0C08, 0xCC00, 0x03E8, 0, 0x0007));
    // Clear errors, then one 6-byte write: control 0x0100 + 32-bit word address 8.
    fpwr(*e, 0x0502, {0x00, 0x00});
    EXPECT_EQ(fpwr(*e, 0x0502, {0x00, 0x01, 0x08, 0x00, 0x00, 0x00}).wkc, 1);
    Datagram st = fprd(*e, 0x0502, 2);
    EXPECT_EQ(st.u16() & 0x8000, 0);  // done
    EXPECT_EQ(st.u16() & 0x7800, 0);
    Datagram d = fprd(*e, 0x0508, 8);
    EXPECT_EQ(d.u16(0), 0x1234);
    EXPECT_EQ(d.u16(2), 0x0000);
    EXPECT_EQ(d.u16(4), 0x5678);
}

TEST_F(EscBasics, IghStyleReadWithReadOnlyBits) {
    e->load_eeprom(make_image(0x0C08, 0xCC00, 0x03E8, 0, 0x0007));
    EXPECT_EQ(fpwr(*e, 0x0502, {0x80, 0x01, 0x04, 0x00}).wkc, 1);  // 0x0180, word address 4
    Datagram d = fprd(*e, 0x0502, 10);
    EXPECT_EQ(d.u16(0) & 0x8700, 0);  // neither busy nor command bits
    EXPECT_EQ(d.u16(0) & 0x0080, 0);  // bit 7 read-only (small EEPROM)
    EXPECT_EQ(d.u16(6), 0x0007);      // word 4: alias
}

TEST_F(EscBasics, BusyUntilEndOfFrame) {
    auto r = run(*e, {dg(FPWR, 0x1001, 0x0502, {0x00, 0x01, 0x00, 0x00, 0x00, 0x00}),
                      dg_len(FPRD, 0x1001, 0x0502, 2)});
    EXPECT_EQ(r[1].u16() & 0x8000, 0x8000);
    EXPECT_EQ(fprd(*e, 0x0502, 2).u16() & 0x8000, 0);
}

TEST_F(EscBasics, ReadBeyondImageGivesFfff) {
    e->load_eeprom(make_image(0x0C08, 0, 0, 0, 0));  // 256 bytes = 128 words
    fpwr(*e, 0x0502, {0x00, 0x01, 0x7E, 0x00, 0x00, 0x00});
    Datagram d = fprd(*e, 0x0508, 8);
    EXPECT_EQ(d.u16(0), 0xFFFF);  // image content (padding 0xFF)
    EXPECT_EQ(d.u16(4), 0xFFFF);  // beyond
    EXPECT_EQ(d.u16(6), 0xFFFF);
    fpwr(*e, 0x0502, {0x00, 0x01, 0x00, 0x10, 0x00, 0x00});
    EXPECT_EQ(fprd(*e, 0x0508, 8).u64(), 0xFFFFFFFFFFFFFFFFull);
}

// Issue 14, finding 5: a read at word 0xFFFFFFFE returned words 0 and 1 in its last two words (the word
// address wrapped). Past the end every word reads 0xFFFF and the missing acknowledge sets bit 13.
TEST_F(EscBasics, ReadAtTheTopWordAddressDoesNotWrap) {
    fpwr(*e, 0x0502, {0x00, 0x01, 0xFE, 0xFF, 0xFF, 0xFF});
    const uint16_t st = fprd(*e, 0x0502, 2).u16();
    EXPECT_EQ(st & 0x8000, 0);       // done
    EXPECT_EQ(st & 0x2000, 0x2000);  // not acknowledged
    EXPECT_EQ(fprd(*e, 0x0508, 8).u64(), 0xFFFFFFFFFFFFFFFFull);
    // The next command clears the error; a read inside the image works and is acknowledged.
    fpwr(*e, 0x0502, {0x00, 0x01, 0x00, 0x00, 0x00, 0x00});
    EXPECT_EQ(fprd(*e, 0x0502, 2).u16() & 0x6000, 0);
    EXPECT_EQ(fprd(*e, 0x0508, 2).u16(), e->eeprom()[0] | (e->eeprom()[1] << 8));
    // A read that starts on the last word is acknowledged; the words after it read 0xFFFF.
    const uint32_t last = static_cast<uint32_t>(e->eeprom().size() / 2 - 1);
    auto cmd = le(0x0100, 2);
    auto addr = le(last, 4);
    cmd.insert(cmd.end(), addr.begin(), addr.end());
    fpwr(*e, 0x0502, cmd);
    EXPECT_EQ(fprd(*e, 0x0502, 2).u16() & 0x2000, 0);
    EXPECT_EQ(fprd(*e, 0x0508, 8).u64() >> 16, 0xFFFFFFFFFFFFull);
    // The PDI gets the same answer.
    fpwr(*e, 0x0500, {0x01});
    e->write_reg<uint8_t>(0x0501, 0x01);
    e->write(0x0502, std::vector<uint8_t>{0x00, 0x01, 0xFF, 0xFF, 0xFF, 0xFF});
    EXPECT_EQ(e->read_reg<uint16_t>(0x0502) & 0x2000, 0x2000);
    EXPECT_EQ(e->read_reg<uint64_t>(0x0508), 0xFFFFFFFFFFFFFFFFull);
}

TEST_F(EscBasics, IghStyleWriteWithEnable) {
    std::vector<std::pair<uint16_t, uint16_t>> seen;
    e->on_eeprom_write([&](uint16_t a, uint16_t v) { seen.emplace_back(a, v); });
    EXPECT_EQ(fpwr(*e, 0x0502, {0x81, 0x02, 0x10, 0x00, 0x00, 0x00, 0xEF, 0xBE}).wkc, 1);
    Datagram st = fprd(*e, 0x0502, 2);
    EXPECT_EQ(st.u16() & 0xE701, 0);
    ASSERT_EQ(seen.size(), 1u);
    EXPECT_EQ(seen[0].first, 0x0010);
    EXPECT_EQ(seen[0].second, 0xBEEF);
    EXPECT_EQ(e->eeprom()[0x20], 0xEF);
    EXPECT_EQ(e->eeprom()[0x21], 0xBE);
}

TEST_F(EscBasics, WriteWithoutEnableIsAnError) {
    bool called = false;
    e->on_eeprom_write([&](uint16_t, uint16_t) { called = true; });
    fpwr(*e, 0x0508, {0x11, 0x22});                          // SOEM: data first
    fpwr(*e, 0x0502, {0x00, 0x02, 0x10, 0x00, 0x00, 0x00});  // no write enable
    EXPECT_EQ(fprd(*e, 0x0502, 2).u16() & 0x4000, 0x4000);
    EXPECT_FALSE(called);
    EXPECT_NE(e->eeprom()[0x20], 0x11);
    fpwr(*e, 0x0502, {0x00, 0x00});  // command 000 clears the errors
    EXPECT_EQ(fprd(*e, 0x0502, 2).u16() & 0x6000, 0);
    fpwr(*e, 0x0502, {0x01, 0x02, 0x10, 0x00, 0x00, 0x00});  // SOEM write: 0x0201
    EXPECT_TRUE(called);
    EXPECT_EQ(e->eeprom()[0x20], 0x11);
    EXPECT_EQ(fprd(*e, 0x0502, 2).u16() & 0x0001, 0);  // write enable consumed
}

TEST_F(EscBasics, PdiOwnedInterfaceAndForcedEcatAccess) {
    fpwr(*e, 0x0500, {0x01});             // offer the interface to the PDI
    e->write_reg<uint8_t>(0x0501, 0x01);  // the PDI takes it
    fpwr(*e, 0x0502, {0x00, 0x01, 0x08, 0x00, 0x00, 0x00});
    EXPECT_EQ(fprd(*e, 0x0504, 4).u32(), 0u);  // ECAT command and address ignored
    // The PDI reads word 0 itself (command runs at once).
    e->write(0x0502, std::vector<uint8_t>{0x00, 0x01, 0x00, 0x00, 0x00, 0x00});
    EXPECT_EQ(e->read_reg<uint16_t>(0x0508), e->eeprom()[0] | (e->eeprom()[1] << 8));
    fpwr(*e, 0x0500, {0x03});  // force ECAT access
    EXPECT_EQ(e->read_reg<uint8_t>(0x0501) & 0x01, 0);
    fpwr(*e, 0x0500, {0x00});
    fpwr(*e, 0x0502, {0x00, 0x01, 0x3E, 0x00, 0x00, 0x00});
    EXPECT_EQ(fprd(*e, 0x0508, 2).u16(), 0x000F);
}

TEST_F(EscBasics, InvalidCommandSetsError) {
    fpwr(*e, 0x0502, {0x00, 0x07});
    EXPECT_EQ(fprd(*e, 0x0502, 2).u16() & 0x2000, 0x2000);
}

TEST_F(EscBasics, ReloadAppliesWordsButNotAlias) {
    e->load_eeprom(make_image(0x0C08, 0x0000, 0x03E8, 0, 0x0007));
    EXPECT_EQ(e->read_reg<uint16_t>(0x0012), 0x0007);
    EXPECT_EQ(fprd(*e, 0x0150, 2).u16(), 0x0000);
    // Change word 1 and word 4 via writes, fix the CRC (word 7), then reload with 0x0400.
    auto img = make_image(0x0C08, 0xCC11, 0x03E8, 0, 0x0009);
    auto wr = [&](uint16_t w) {
        const uint16_t v = util::get16(img.data() + 2 * w);
        fpwr(*e, 0x0502,
             {0x01, 0x02, static_cast<uint8_t>(w), 0x00, 0x00, 0x00, static_cast<uint8_t>(v),
              static_cast<uint8_t>(v >> 8)});
    };
    wr(1);
    wr(4);
    wr(7);
    fpwr(*e, 0x0502, {0x00, 0x04});
    EXPECT_EQ(fprd(*e, 0x0502, 2).u16() & 0x9800, 0);
    EXPECT_EQ(fprd(*e, 0x0150, 2).u16(), 0xCC11);
    EXPECT_EQ(e->read_reg<uint16_t>(0x0012), 0x0007);  // alias only at power-on
    // SOEM's 0x0300 reload is tolerated too.
    wr(1);
    fpwr(*e, 0x0502, {0x00, 0x03});
    EXPECT_EQ(fprd(*e, 0x0502, 2).u16() & 0xA000, 0);
}

TEST_F(EscBasics, ReloadDetectsChecksumError) {
    fpwr(*e, 0x0502, {0x01, 0x02, 0x01, 0x00, 0x00, 0x00, 0x55, 0x55});  // word 1 changed, CRC not
    fpwr(*e, 0x0502, {0x00, 0x04});
    EXPECT_EQ(fprd(*e, 0x0502, 2).u16() & 0x0800, 0x0800);
    EXPECT_EQ(fprd(*e, 0x0110, 2).u16() & 0x0001, 0);
}

TEST_F(EscBasics, PowerOnLoadAndCrc) {
    e->load_eeprom(make_image(0x0C05, 0x8800, 0x0064, 0x1234, 0x0BAD));
    EXPECT_EQ(fprd(*e, 0x0140, 2).u16(), 0x0C05);
    EXPECT_EQ(fprd(*e, 0x0150, 2).u16(), 0x8800);
    EXPECT_EQ(fprd(*e, 0x0152, 2).u16(), 0x1234);
    EXPECT_EQ(fprd(*e, 0x0982, 2).u16(), 0x0064);
    EXPECT_EQ(fprd(*e, 0x0012, 2).u16(), 0x0BAD);
    EXPECT_EQ(fprd(*e, 0x0502, 2).u16() & 0x1800, 0);

    esc::Esc bad({}, clk);
    bad.load_eeprom(make_image(0x0C05, 0x8800, 0x0064, 0x1234, 0x0BAD, false));
    EXPECT_EQ(bad.read_reg<uint16_t>(0x0502) & 0x0800, 0x0800);
    EXPECT_EQ(bad.read_reg<uint16_t>(0x0110) & 0x0001, 0);
    EXPECT_EQ(bad.read_reg<uint16_t>(0x0012), 0);

    auto dbg = make_image(0x0C05, 0, 0, 0, 0x0001, false);
    dbg[14] = 0xA4;
    dbg[15] = 0x88;  // checksum check disabled
    bad.load_eeprom(dbg);
    EXPECT_EQ(bad.read_reg<uint16_t>(0x0502) & 0x0800, 0);
    EXPECT_EQ(bad.read_reg<uint16_t>(0x0012), 0x0001);
}

}  // namespace
