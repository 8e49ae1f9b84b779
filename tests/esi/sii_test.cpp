// SII image: build_sii against the description and dictionary, parse_sii/decode_sii on our images and on
// hand-made, truncated and garbage ones.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "esc/wire/sii.hpp"
#include "esi/model.hpp"
#include "esi/sii.hpp"
#include "test_device.hpp"

namespace {

using esi_test::Device;

// Declared default of an entry as an unsigned number, whatever alternative od stored it in.
uint64_t dv(const od::Entry* e) {
    if (e == nullptr) return 0;
    if (auto p = std::get_if<uint64_t>(&e->default_value)) return *p;
    if (auto p = std::get_if<int64_t>(&e->default_value)) return static_cast<uint64_t>(*p);
    return 0;
}

uint16_t word(const std::vector<uint8_t>& img, std::size_t w) {
    return static_cast<uint16_t>(img[2 * w] | (img[2 * w + 1] << 8));
}

// ---- CRC ------------------------------------------------------------------------------------------------

TEST(SiiCrc, Crc8Poly07Init0xFFMsbFirst) {
    // Values computed with an independent bit-by-bit implementation (poly 0x07, init 0xFF, no reflection).
    const uint8_t check[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
    EXPECT_EQ(esc::sii::crc8(check, sizeof check), 0xFB);
    const uint8_t zeros[14] = {};
    EXPECT_EQ(esc::sii::crc8(zeros, sizeof zeros), 0x30);
    // EJ7211 ConfigData 050403ccc4090000000000000000
    const uint8_t ej[14] = {0x05, 0x04, 0x03, 0xCC, 0xC4, 0x09, 0, 0, 0, 0, 0, 0, 0, 0};
    EXPECT_EQ(esc::sii::crc8(ej, sizeof ej), 0xD8);
}

// ---- Built image against the description and dictionary ------------------------------------------------

class SiiDevice : public ::testing::TestWithParam<std::string> {
  protected:
    Device dev() const {
        for (auto& [name, make] : esi_test::all_devices())
            if (name == GetParam()) return make();
        throw std::logic_error("no device " + GetParam());
    }
};

TEST_P(SiiDevice, ModelHasNoContradictions) {
    const Device d = dev();
    const auto m = esi::derive_model(d.description, d.dictionary);
    for (const auto& w : m.warnings)
        ADD_FAILURE() << w;
}

TEST_P(SiiDevice, HeaderWordsComeFromTheDescription) {
    const Device d = dev();
    const auto img = esi::build_sii(d.description, d.dictionary);
    const auto& desc = d.description;
    ASSERT_EQ(img.size(), desc.eeprom_bytes);
    EXPECT_EQ(img[0], desc.pdi_control);
    EXPECT_EQ(img[1], desc.esc_config);
    EXPECT_EQ(word(img, 1), desc.pdi_config);
    EXPECT_EQ(word(img, 2), desc.sync_pulse_length);
    EXPECT_EQ(word(img, 4), desc.station_alias);
    EXPECT_EQ(word(img, 7), esc::sii::crc8(img.data(), 14)) << "CRC in the low byte, high byte 0";
    EXPECT_EQ(word(img, 0x14), desc.bootstrap_mailbox.out_start);
    EXPECT_EQ(word(img, 0x15), desc.bootstrap_mailbox.out_size);
    EXPECT_EQ(word(img, 0x16), desc.bootstrap_mailbox.in_start);
    EXPECT_EQ(word(img, 0x17), desc.bootstrap_mailbox.in_size);
    EXPECT_EQ(word(img, 0x1C), desc.mailbox_protocols);
    EXPECT_EQ(word(img, 0x3E), desc.eeprom_bytes * 8 / 1024 - 1);
    EXPECT_EQ(word(img, 0x3F), 1);

    const auto info = esi::parse_sii(img);
    EXPECT_TRUE(info.problems.empty()) << esi::decode_sii(img);
    EXPECT_TRUE(info.crc_ok);
    EXPECT_FALSE(info.crc_disabled);
    EXPECT_TRUE(info.end_found);
    EXPECT_EQ(info.vendor_id, desc.identity.vendor_id);
    EXPECT_EQ(info.product_code, desc.identity.product_code);
    EXPECT_EQ(info.revision, desc.identity.revision);
    EXPECT_EQ(info.serial_number, desc.identity.serial_number);
    EXPECT_EQ(info.standard_mailbox.out_start, desc.standard_mailbox.out_start);
    EXPECT_EQ(info.standard_mailbox.out_size, desc.standard_mailbox.out_size);
    EXPECT_EQ(info.standard_mailbox.in_start, desc.standard_mailbox.in_start);
    EXPECT_EQ(info.standard_mailbox.in_size, desc.standard_mailbox.in_size);
    EXPECT_EQ(info.bootstrap_mailbox.out_size, desc.bootstrap_mailbox.out_size);
    EXPECT_EQ(info.eeprom_bytes(), desc.eeprom_bytes);
}

TEST_P(SiiDevice, IdentityEqualsObject0x1018) {
    const Device d = dev();
    const auto info = esi::parse_sii(esi::build_sii(d.description, d.dictionary));
    if (d.dictionary.find(0x1018) == nullptr) GTEST_SKIP();
    EXPECT_EQ(info.vendor_id, d.dictionary.get<uint32_t>(0x1018, 1));
    EXPECT_EQ(info.product_code, d.dictionary.get<uint32_t>(0x1018, 2));
    EXPECT_EQ(info.revision, d.dictionary.get<uint32_t>(0x1018, 3));
    EXPECT_EQ(info.serial_number, d.dictionary.get<uint32_t>(0x1018, 4));
}

TEST_P(SiiDevice, GeneralCategory) {
    const Device d = dev();
    const auto info = esi::parse_sii(esi::build_sii(d.description, d.dictionary));
    ASSERT_TRUE(info.general.has_value());
    const auto& g = *info.general;
    const auto& id = d.description.identity;
    EXPECT_EQ(g.group, id.group_type);
    EXPECT_EQ(g.name, id.device_name.substr(0, 255));
    EXPECT_EQ(g.order, id.order_code.empty() ? id.device_name : id.order_code);
    EXPECT_EQ(g.group_idx_duplicate, g.group_idx);
    const bool coe = d.description.mailbox_protocols & od::mailbox_protocol::CoE;
    EXPECT_EQ(g.coe_details, coe ? d.description.coe_details : 0);
    EXPECT_EQ((g.foe_details & 1) != 0, (d.description.mailbox_protocols & od::mailbox_protocol::FoE) != 0);
    EXPECT_EQ(g.physical_ports, 0x0011);
    const od::Entry* dt = d.dictionary.find(0x1000, 0);
    const bool ds402 = dt != nullptr && (dv(dt) & 0xFFFF) == 402;
    EXPECT_EQ(g.ds402_channels, ds402 ? 1 : 0);
}

TEST_P(SiiDevice, SyncManagersMatchDescriptionAndMapping) {
    const Device d = dev();
    const auto info = esi::parse_sii(esi::build_sii(d.description, d.dictionary));
    ASSERT_EQ(info.sync_managers.size(), d.description.sync_managers.size());
    for (std::size_t n = 0; n < info.sync_managers.size(); ++n) {
        const auto& s = info.sync_managers[n];
        const auto& want = d.description.sync_managers[n];
        SCOPED_TRACE("SM" + std::to_string(n));
        EXPECT_EQ(s.type, static_cast<uint8_t>(want.kind));
        EXPECT_EQ(s.control, want.control);
        EXPECT_EQ(s.enable & 1, want.enable ? 1 : 0);
        if (want.kind == od::SmKind::MBoxOut) {
            EXPECT_EQ(s.start, info.standard_mailbox.out_start);
            EXPECT_EQ(s.length, info.standard_mailbox.out_size);
        } else if (want.kind == od::SmKind::MBoxIn) {
            EXPECT_EQ(s.start, info.standard_mailbox.in_start);
            EXPECT_EQ(s.length, info.standard_mailbox.in_size);
        } else {
            EXPECT_EQ(s.start, want.start);
            // Length = the default mapping assigned through 0x1C1n, summed from the dictionary here.
            uint32_t bits = 0;
            const auto assign = static_cast<uint16_t>(0x1C10 + n);
            if (d.dictionary.find(assign) != nullptr) {
                const auto count = dv(d.dictionary.find(assign, 0));
                for (uint8_t k = 1; k <= count; ++k) {
                    const auto pdo = static_cast<uint16_t>(dv(d.dictionary.find(assign, k)));
                    const auto n_entries = dv(d.dictionary.find(pdo, 0));
                    for (uint8_t i = 1; i <= n_entries; ++i)
                        bits += dv(d.dictionary.find(pdo, i)) & 0xFF;
                }
            }
            EXPECT_EQ(s.length, (bits + 7) / 8);
            if (want.default_size != 0) {
                EXPECT_EQ(s.length, want.default_size);
            }
        }
    }
    // FMMUs: outputs, inputs, mailbox state.
    std::vector<uint8_t> fmmus(info.fmmus.begin(), info.fmmus.end());
    while (!fmmus.empty() && fmmus.back() == 0xFF)
        fmmus.pop_back();
    EXPECT_EQ(fmmus, (std::vector<uint8_t>{1, 2, 3}));
}

TEST_P(SiiDevice, PdosAreTheDefaultMappingOfTheDictionary) {
    const Device d = dev();
    const auto info = esi::parse_sii(esi::build_sii(d.description, d.dictionary));
    std::size_t rx_seen = 0, tx_seen = 0;
    for (const od::Object& o : d.dictionary.objects()) {
        const bool rx = o.index >= 0x1600 && o.index <= 0x17FF;
        const bool tx = o.index >= 0x1A00 && o.index <= 0x1BFF;
        if (!rx && !tx) continue;
        SCOPED_TRACE(o.name);
        const auto& list = rx ? info.rx_pdos : info.tx_pdos;
        auto it =
            std::find_if(list.begin(), list.end(), [&](const esi::SiiPdo& p) { return p.index == o.index; });
        ASSERT_NE(it, list.end());
        (rx ? rx_seen : tx_seen)++;
        EXPECT_EQ(it->name, o.name.substr(0, 255));
        const auto count = dv(o.entry(0));
        ASSERT_EQ(it->entries.size(), count);
        for (std::size_t i = 0; i < count; ++i) {
            const auto w = static_cast<uint32_t>(dv(o.entry(static_cast<uint8_t>(i + 1))));
            const auto& e = it->entries[i];
            EXPECT_EQ(e.index, w >> 16);
            EXPECT_EQ(e.subindex, static_cast<uint8_t>(w >> 8));
            EXPECT_EQ(e.bit_length, static_cast<uint8_t>(w));
            if (e.index != 0) {
                const od::Entry* target = d.dictionary.find(e.index, e.subindex);
                ASSERT_NE(target, nullptr);
                EXPECT_EQ(e.data_type, static_cast<uint8_t>(target->type));
                EXPECT_FALSE(e.name.empty());
                EXPECT_TRUE(rx ? target->rx_mappable() : target->tx_mappable());
            } else {
                EXPECT_EQ(e.name_idx, 0);
            }
        }
        // SM assignment from 0x1C12/0x1C13 (0x1C10 + SM number).
        int sm = 0xFF;
        for (std::size_t n = 0; n < d.description.sync_managers.size(); ++n) {
            const od::Object* assign = d.dictionary.find(static_cast<uint16_t>(0x1C10 + n));
            if (assign == nullptr || assign->entries.empty()) continue;
            const auto k_max = dv(assign->entry(0));
            for (uint8_t k = 1; k <= k_max; ++k)
                if (dv(assign->entry(k)) == o.index) sm = static_cast<int>(n);
        }
        EXPECT_EQ(it->sm, sm);
        EXPECT_EQ((it->flags & esi::pdo_flags::Default) != 0, sm != 0xFF);
        EXPECT_EQ((it->flags & esi::pdo_flags::FixedContent) != 0,
                  (o.entry(0)->access & od::access::WriteMask) == 0);
    }
    EXPECT_EQ(rx_seen, info.rx_pdos.size());
    EXPECT_EQ(tx_seen, info.tx_pdos.size());
}

TEST_P(SiiDevice, DcModes) {
    const Device d = dev();
    const auto info = esi::parse_sii(esi::build_sii(d.description, d.dictionary));
    ASSERT_EQ(info.dc_modes.size(), d.description.dc_modes.size());
    for (std::size_t i = 0; i < info.dc_modes.size(); ++i) {
        const auto& got = info.dc_modes[i];
        const auto& want = d.description.dc_modes[i];
        EXPECT_EQ(got.name, want.name);
        EXPECT_EQ(got.description, want.description);
        EXPECT_EQ(got.assign_activate, want.assign_activate);
        EXPECT_EQ(got.sync0_cycle_factor, want.cycle_time_sync0_factor);
        EXPECT_EQ(got.sync0_shift_time, want.shift_time_sync0);
    }
}

TEST_P(SiiDevice, DecodeShowsEverything) {
    const Device d = dev();
    const auto img = esi::build_sii(d.description, d.dictionary);
    const std::string text = esi::decode_sii(img);
    EXPECT_NE(text.find("checksum"), std::string::npos);
    EXPECT_NE(text.find(": ok"), std::string::npos);
    EXPECT_NE(text.find("STRINGS"), std::string::npos);
    EXPECT_NE(text.find("GENERAL"), std::string::npos);
    EXPECT_NE(text.find("SYNCM"), std::string::npos);
    EXPECT_NE(text.find("MBoxOut"), std::string::npos);
    EXPECT_NE(text.find("end of categories"), std::string::npos);
    EXPECT_EQ(text.find("PROBLEM"), std::string::npos) << text;
}

TEST_P(SiiDevice, EveryTruncationIsHandled) {
    const Device d = dev();
    const auto img = esi::build_sii(d.description, d.dictionary);
    for (std::size_t len = 0; len <= img.size(); ++len) {
        const std::vector<uint8_t> cut(img.begin(), img.begin() + static_cast<std::ptrdiff_t>(len));
        const auto info = esi::parse_sii(cut);
        const std::string text = esi::decode_sii(cut);
        EXPECT_FALSE(text.empty());
        if (len < 128) {
            EXPECT_FALSE(info.header_complete);
            EXPECT_FALSE(info.problems.empty());
        }
        if (len >= 16) {
            EXPECT_TRUE(info.crc_ok) << len;
        }
        if (len == img.size()) {
            EXPECT_TRUE(info.problems.empty());
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Devices, SiiDevice, ::testing::Values("small", "drive"));

// ---- Hand-made and broken images --------------------------------------------------------------------

struct Image {
    std::vector<uint8_t> b = std::vector<uint8_t>(128, 0);
    void set16(std::size_t off, uint16_t v) {
        if (b.size() < off + 2) b.resize(off + 2, 0);
        b[off] = static_cast<uint8_t>(v);
        b[off + 1] = static_cast<uint8_t>(v >> 8);
    }
    void add16(uint16_t v) { set16(b.size(), v); }
    void category(uint16_t type, std::vector<uint8_t> data) {
        if (data.size() % 2) data.push_back(0);
        add16(type);
        add16(static_cast<uint16_t>(data.size() / 2));
        b.insert(b.end(), data.begin(), data.end());
    }
    void fix_crc() { set16(14, esc::sii::crc8(b.data(), 14)); }
};

TEST(SiiParse, HandMadeImageLikeNi9144) {
    Image img;
    img.b[0] = 0x05;
    img.set16(4, 1000);
    img.fix_crc();
    img.set16(0x08 * 2, 0x00000002);
    img.set16(0x18 * 2, 0x1F00);
    img.set16(0x19 * 2, 256);
    img.set16(0x1C * 2, 0x000C);
    img.set16(0x3E * 2, 0x000F);
    img.set16(0x3F * 2, 1);
    img.category(esi::category::Strings, {2, 3, 'a', 'b', 'c', 1, 'Z'});
    // SyncM as observed on the NI 9144 (reference section 7.3).
    img.category(esi::category::SyncM,
                 {0x00, 0x1F, 0x00, 0x01, 0x26, 0, 1, 1, 0x00, 0x1C, 0x00, 0x03, 0x22, 0, 1, 2,
                  0x00, 0x10, 0x00, 0x02, 0x64, 0, 1, 3, 0x00, 0x16, 0x00, 0x02, 0x20, 0, 1, 4});
    img.category(esi::category::Fmmu, {1, 2});
    img.category(esi::category::FmmuX, {0xFA, 0xFF, 0x02, 0x00, 0xFA, 0xFF, 0x03, 0x00});
    // TxPDO 0x1A00 "Z" with one entry 0x6000:01, 16 bits, name "abc", default-assigned to SM3.
    img.category(esi::category::TxPdo,
                 {0x00, 0x1A, 1, 3, 0, 2, 0x02, 0x00, 0x00, 0x60, 0x01, 1, 0x06, 16, 0, 0});
    // DC: "abc" AssignActivate 0x0300, SYNC0 factor 1.
    std::vector<uint8_t> dc(24, 0);
    dc[14] = 0x00;
    dc[15] = 0x03;
    dc[16] = 1;
    dc[18] = 1;
    img.category(esi::category::Dc, dc);
    img.add16(0xFFFF);

    const auto info = esi::parse_sii(img.b);
    EXPECT_TRUE(info.crc_ok);
    EXPECT_TRUE(info.end_found);
    EXPECT_TRUE(info.problems.empty());
    EXPECT_EQ(info.vendor_id, 2u);
    EXPECT_EQ(info.mailbox_protocols, 0x0C);
    EXPECT_EQ(info.eeprom_bytes(), 2048u);
    ASSERT_EQ(info.strings.size(), 2u);
    EXPECT_EQ(info.string_at(1), "abc");
    EXPECT_EQ(info.string_at(2), "Z");
    EXPECT_EQ(info.string_at(3), "");
    ASSERT_EQ(info.sync_managers.size(), 4u);
    EXPECT_EQ(info.sync_managers[0].start, 0x1F00);
    EXPECT_EQ(info.sync_managers[0].length, 256);
    EXPECT_EQ(info.sync_managers[0].control, 0x26);
    EXPECT_EQ(info.sync_managers[1].length, 768);
    EXPECT_EQ(info.sync_managers[3].type, 4);
    EXPECT_EQ(info.fmmus, (std::vector<uint8_t>{1, 2}));
    ASSERT_EQ(info.tx_pdos.size(), 1u);
    EXPECT_EQ(info.tx_pdos[0].index, 0x1A00);
    EXPECT_EQ(info.tx_pdos[0].sm, 3);
    EXPECT_EQ(info.tx_pdos[0].name, "Z");
    ASSERT_EQ(info.tx_pdos[0].entries.size(), 1u);
    EXPECT_EQ(info.tx_pdos[0].entries[0].index, 0x6000);
    EXPECT_EQ(info.tx_pdos[0].entries[0].subindex, 1);
    EXPECT_EQ(info.tx_pdos[0].entries[0].name, "abc");
    EXPECT_EQ(info.tx_pdos[0].entries[0].bit_length, 16);
    ASSERT_EQ(info.dc_modes.size(), 1u);
    EXPECT_EQ(info.dc_modes[0].assign_activate, 0x0300);
    EXPECT_EQ(info.dc_modes[0].name, "abc");
    ASSERT_EQ(info.categories.size(), 6u);
    EXPECT_EQ(info.categories[3].type, esi::category::FmmuX);

    // The FMMUX category is not interpreted: the decoder shows it as hex.
    const std::string text = esi::decode_sii(img.b);
    EXPECT_NE(text.find("FMMUX"), std::string::npos);
    EXPECT_NE(text.find(" FA FF 02 00 FA FF 03 00"), std::string::npos) << text;
}

TEST(SiiParse, UnknownCategoryShownAsHexAndSkippedByLength) {
    Image img;
    img.fix_crc();
    img.category(0x0801, {0xDE, 0xAD, 0xBE, 0xEF});
    img.category(esi::category::Strings, {1, 2, 'o', 'k'});
    img.add16(0xFFFF);
    const auto info = esi::parse_sii(img.b);
    EXPECT_TRUE(info.problems.empty());
    EXPECT_EQ(info.string_at(1), "ok");
    const std::string text = esi::decode_sii(img.b);
    EXPECT_NE(text.find("category 2049 unknown/vendor specific"), std::string::npos) << text;
    EXPECT_NE(text.find(" DE AD BE EF"), std::string::npos) << text;
}

TEST(SiiParse, ControlCharactersInStringsAreEscapedInTheText) {
    Image img;
    img.fix_crc();
    std::vector<uint8_t> str = {1, 255};
    for (int i = 0; i < 255; ++i)
        str.push_back(i % 2 ? '\n' : 'x');
    img.category(esi::category::Strings, str);
    img.add16(0xFFFF);
    const auto info = esi::parse_sii(img.b);
    ASSERT_EQ(info.strings.size(), 1u);
    EXPECT_EQ(info.strings[0].size(), 255u);
    const std::string text = esi::decode_sii(img.b);
    EXPECT_NE(text.find("x\\x0Ax\\x0Ax"), std::string::npos) << text;
    EXPECT_NE(text.find("x\\x0Ax\"\n"), std::string::npos) << "the whole string is shown";
}

TEST(SiiParse, BadCrcIsReported) {
    Image img;
    img.b[0] = 0x05;
    img.fix_crc();
    img.b[2] ^= 0x01;
    img.add16(0xFFFF);
    const auto info = esi::parse_sii(img.b);
    EXPECT_FALSE(info.crc_ok);
    ASSERT_FALSE(info.problems.empty());
    EXPECT_NE(esi::decode_sii(img.b).find("BAD"), std::string::npos);
}

TEST(SiiParse, ChecksumDisableValueIsAccepted) {
    Image img;
    img.b[0] = 0x05;
    img.set16(14, 0x88A4);
    img.add16(0xFFFF);
    const auto info = esi::parse_sii(img.b);
    EXPECT_TRUE(info.crc_ok);
    EXPECT_TRUE(info.crc_disabled);
    EXPECT_NE(esi::decode_sii(img.b).find("0x88A4"), std::string::npos);
}

TEST(SiiParse, LengthsPastTheEndAreReportedNotRead) {
    {
        Image img;  // category claims 0xFFFF words
        img.fix_crc();
        img.add16(esi::category::TxPdo);
        img.add16(0xFFFF);
        img.b.insert(img.b.end(), {0x00, 0x1A, 200, 3, 0, 0, 0, 0});  // PDO with 200 entries, none present
        const auto info = esi::parse_sii(img.b);
        ASSERT_EQ(info.categories.size(), 1u);
        EXPECT_TRUE(info.categories[0].truncated);
        ASSERT_EQ(info.tx_pdos.size(), 1u);
        EXPECT_TRUE(info.tx_pdos[0].entries.empty());
        EXPECT_GE(info.problems.size(), 2u);
        (void)esi::decode_sii(img.b);
    }
    {
        Image img;  // strings: 5 declared, one present; string length past the category; bad index used
        img.fix_crc();
        img.category(esi::category::Strings, {5, 1, 'x', 200, 'y'});
        img.category(esi::category::General, std::vector<uint8_t>(32, 9));
        img.add16(0xFFFF);
        const auto info = esi::parse_sii(img.b);
        EXPECT_EQ(info.strings.size(), 1u);
        ASSERT_TRUE(info.general.has_value());
        EXPECT_EQ(info.general->name, "");
        EXPECT_GE(info.problems.size(), 2u);
    }
    {
        Image img;  // short General, odd SyncM, no end marker
        img.fix_crc();
        img.category(esi::category::General, {1, 2, 3});
        img.category(esi::category::SyncM, {1, 2, 3, 4, 5, 6});
        const auto info = esi::parse_sii(img.b);
        EXPECT_FALSE(info.end_found);
        EXPECT_TRUE(info.sync_managers.empty());
        EXPECT_GE(info.problems.size(), 3u);
    }
}

TEST(SiiParse, GarbageNeverCrashes) {
    std::mt19937 rng(1234);
    for (int round = 0; round < 300; ++round) {
        std::vector<uint8_t> img(rng() % 600);
        for (auto& b : img)
            b = static_cast<uint8_t>(rng());
        // Make the category walk start with plausible types half of the time.
        if (img.size() > 140 && round % 2) {
            const uint16_t types[] = {10, 30, 40, 41, 50, 51, 60};
            img[128] = static_cast<uint8_t>(types[rng() % 7]);
            img[129] = 0;
            img[130] = static_cast<uint8_t>(rng() % 8);
            img[131] = 0;
        }
        const auto info = esi::parse_sii(img);
        EXPECT_EQ(info.image_bytes, img.size());
        EXPECT_FALSE(esi::decode_sii(img).empty());
    }
}

// Every category kind (known, FMMUX, vendor range), then every truncation and every single-byte corruption
// of the image: the parser must stay inside the span (ASan in CI) and the decoder must always answer.
TEST(SiiParse, EveryTruncationAndByteFlipOfAFullImage) {
    Image img;
    img.b[0] = 0x05;
    img.fix_crc();
    img.category(esi::category::Strings, {2, 3, 'a', 'b', 'c', 1, 'Z'});
    img.category(esi::category::General, std::vector<uint8_t>(32, 1));
    img.category(esi::category::Fmmu, {1, 2, 3});
    img.category(esi::category::SyncM, std::vector<uint8_t>(16, 0x10));
    img.category(esi::category::FmmuX, {0xFA, 0xFF, 0x02, 0x00});
    img.category(0x1234, {1, 2, 3, 4, 5, 6});
    img.category(esi::category::TxPdo, {0x00, 0x1A, 2, 3, 0,    2,    0,    0, 0x00, 0x60, 0x01, 1,
                                        0x06, 16,   0, 0, 0x00, 0x00, 0x00, 0, 0,    8,    0,    0});
    img.category(esi::category::RxPdo, {0x00, 0x16, 1, 2, 0, 1, 0, 0, 0x00, 0x70, 0x00, 2, 0x07, 32, 0, 0});
    img.category(esi::category::Dc, std::vector<uint8_t>(48, 2));
    img.add16(0xFFFF);
    const auto whole = esi::parse_sii(img.b);
    ASSERT_TRUE(whole.end_found);
    EXPECT_EQ(whole.categories.size(), 9u);
    for (std::size_t len = 0; len <= img.b.size(); ++len) {
        const std::vector<uint8_t> cut(img.b.begin(), img.b.begin() + static_cast<std::ptrdiff_t>(len));
        const auto info = esi::parse_sii(cut);
        EXPECT_FALSE(esi::decode_sii(cut).empty());
        if (len < img.b.size()) {
            EXPECT_FALSE(info.problems.empty()) << len;
        }
    }
    for (std::size_t i = 0; i < img.b.size(); ++i)
        for (uint8_t v : {uint8_t{0x00}, uint8_t{0xFF}, static_cast<uint8_t>(img.b[i] ^ 0x80)}) {
            std::vector<uint8_t> bad = img.b;
            bad[i] = v;
            (void)esi::parse_sii(bad);
            EXPECT_FALSE(esi::decode_sii(bad).empty());
        }
}

// Contradictions between description and dictionary are reported; the dictionary wins in the output.
TEST(SiiModel, ContradictionsAreReportedAndTheDictionaryWins) {
    using esi_test::entry;
    namespace a = od::access;
    od::DeviceDescription desc = esi_test::small_description();
    desc.sync_managers[2].default_size = 99;  // the default mapping has 6 bytes
    desc.sync_managers[0].start = 0x1800;     // the standard mailbox says 0x1000
    od::Dictionary dict;
    od::Object map;
    map.index = 0x1600;
    map.code = od::ObjectCode::Record;
    map.name = "RxPDO";
    map.type = od::DataType::PdoMapping;
    map.entries = {
        entry(0x1600, 0, "n", od::DataType::Unsigned8, a::RW_PreOp, uint64_t{3}),
        entry(0x1600, 1, "e1", od::DataType::Unsigned32, a::RW_PreOp, uint64_t{0x99990010}),   // missing
        entry(0x1600, 2, "e2", od::DataType::Unsigned32, a::RW_PreOp, uint64_t{0x60410010})};  // not Rx
    dict.add(std::move(map));
    dict.add(esi_test::var(0x6041, "Statusword", od::DataType::Unsigned16, a::RO | a::TxPdo, uint64_t{0}));
    od::Object assign;
    assign.index = 0x1C12;
    assign.code = od::ObjectCode::Array;
    assign.name = "RxPDO assign";
    assign.type = od::DataType::Unsigned16;
    assign.entries = {
        entry(0x1C12, 0, "n", od::DataType::Unsigned8, a::RW_PreOp, uint64_t{2}),
        entry(0x1C12, 1, "p1", od::DataType::Unsigned16, a::RW_PreOp, uint64_t{0x1600}),
        entry(0x1C12, 2, "p2", od::DataType::Unsigned16, a::RW_PreOp, uint64_t{0x1A07})};  // no such
    dict.add(std::move(assign));

    const auto m = esi::derive_model(desc, dict);
    auto said = [&](const std::string& what) {
        for (const auto& w : m.warnings)
            if (w.find(what) != std::string::npos) return true;
        return false;
    };
    EXPECT_TRUE(said("0x9999:00 which does not exist"));
    EXPECT_TRUE(said("0x6041:00 which is not RxPDO mappable"));
    EXPECT_TRUE(said("counts 3 entries but subindex 3 does not exist"));
    EXPECT_TRUE(said("assigns 0x1A07"));
    EXPECT_TRUE(said("SM2 declares default size 99"));
    EXPECT_TRUE(said("SM0 declares 0x1800"));

    const auto info = esi::parse_sii(esi::build_sii(desc, dict));
    EXPECT_TRUE(info.problems.empty());
    ASSERT_EQ(info.sync_managers.size(), 4u);
    EXPECT_EQ(info.sync_managers[0].start, desc.standard_mailbox.out_start);
    EXPECT_EQ(info.sync_managers[2].length, 4);  // 16 + 16 bits actually mapped
    ASSERT_EQ(info.rx_pdos.size(), 1u);
    EXPECT_EQ(info.rx_pdos[0].entries.size(), 2u);
    EXPECT_EQ(info.rx_pdos[0].sm, 2);
}

TEST(SiiBuild, ContentThatDoesNotFitThrows) {
    const Device d = esi_test::small_device();
    od::DeviceDescription tiny = d.description;
    tiny.eeprom_bytes = 128;
    EXPECT_THROW(esi::build_sii(tiny, d.dictionary), std::length_error);
    tiny.eeprom_bytes = 1000;  // not a whole KiBit
    EXPECT_THROW(esi::build_sii(tiny, d.dictionary), std::invalid_argument);
}

// A vendor's SII fits the EEPROM its ESI declares. When softecat's full content does not, it leaves out, in
// this order, the PDO entry names, the PDO names, the DC op modes' descriptions, the PDOs not assigned by
// default, (a CoE device only) the PDO categories, and last the long device name (General then names the
// order number's string); FMMU, SyncM and DC with their mode names stay. Only when even that does not fit is
// the content refused (load_product then warns and emulates a larger EEPROM). Each size is checked against
// the level it shows: what a level leaves out, every later level leaves out too, and a larger EEPROM never
// holds less.
namespace compaction {
void check_sizes(Device& d) {
    const esi::DeviceModel m = esi::derive_model(d.description, d.dictionary);
    const bool coe = d.description.mailbox_protocols & od::mailbox_protocol::CoE;
    std::size_t assigned = 0, entries = 0, named_pdos = 0, described_modes = 0;
    for (const esi::PdoInfo& p : m.pdos) {
        assigned += p.sm >= 0;
        for (const esi::PdoEntryInfo& e : p.entries)
            entries += !e.name.empty();
        named_pdos += !p.name.empty();
    }
    for (const od::DcOpMode& mode : d.description.dc_modes)
        described_modes += !mode.description.empty();
    const std::string& order = d.description.identity.order_code.empty() ? d.description.identity.device_name
                                                                         : d.description.identity.order_code;
    int last_level = -1, refused = 0;
    for (uint16_t bytes = 128; bytes <= 4096; bytes = static_cast<uint16_t>(bytes + 128)) {
        SCOPED_TRACE(bytes);
        d.description.eeprom_bytes = bytes;
        std::vector<uint8_t> img;
        try {
            img = esi::build_sii(d.description, d.dictionary);
        } catch (const std::length_error&) {
            EXPECT_EQ(last_level, -1) << "a smaller EEPROM held it";
            ++refused;
            continue;
        }
        ASSERT_EQ(img.size(), bytes);
        const esi::SiiInfo info = esi::parse_sii(img);
        EXPECT_TRUE(info.crc_ok);
        EXPECT_TRUE(info.problems.empty()) << ::testing::PrintToString(info.problems);
        ASSERT_TRUE(info.general);
        EXPECT_EQ(info.general->order, order);
        EXPECT_EQ(info.sync_managers.size(), m.sync_managers.size());
        EXPECT_GE(info.fmmus.size(), m.fmmus.size());  // padded to whole words with 0xFF (unused)
        ASSERT_EQ(info.dc_modes.size(), d.description.dc_modes.size());
        for (std::size_t i = 0; i < info.dc_modes.size(); ++i)
            EXPECT_EQ(info.dc_modes[i].name, d.description.dc_modes[i].name);  // names always stay
        std::size_t pdos = 0, entry_names = 0, pdo_names = 0, descriptions = 0;
        for (const auto* list : {&info.rx_pdos, &info.tx_pdos})
            for (const esi::SiiPdo& p : *list) {
                ++pdos;
                pdo_names += p.name_idx != 0;
                for (const esi::SiiPdoEntry& e : p.entries)
                    entry_names += e.name_idx != 0;
            }
        for (const esi::SiiDcMode& mode : info.dc_modes)
            descriptions += mode.description_idx != 0;
        // The level this image shows, from the last thing left out: 0 full, 1 entry names, 2 PDO names, 3 DC
        // descriptions, 4 non-default PDOs, 5 PDO categories, 6 the long name.
        int level = 0;
        if (info.general->name != d.description.identity.device_name)
            level = 6;
        else if (pdos == 0 && !m.pdos.empty())
            level = 5;
        else if (pdos < m.pdos.size())
            level = 4;
        else if (descriptions < described_modes)
            level = 3;
        else if (pdo_names < named_pdos)
            level = 2;
        else if (entry_names < entries)
            level = 1;
        if (level == 6) {
            EXPECT_EQ(info.general->name, order);
        }
        if (level >= 1) {
            EXPECT_EQ(entry_names, 0u);
        }
        if (level >= 2) {
            EXPECT_EQ(pdo_names, 0u);
        }
        if (level >= 3) {
            EXPECT_EQ(descriptions, 0u);
        }
        if (level >= 4) {
            EXPECT_GE(pdos, level >= 5 ? 0u : assigned);
        }
        if (level >= 5) {
            EXPECT_TRUE(coe) << "a device without CoE keeps the PDOs of its default assignment";
            EXPECT_EQ(pdos, 0u);
        }
        if (last_level >= 0) {
            EXPECT_LE(level, last_level) << "a larger EEPROM holds less";
        }
        last_level = level;
    }
    EXPECT_EQ(last_level, 0) << "4 KiB hold everything";
    EXPECT_GT(refused, 0);  // 128 bytes: the header alone
}
}  // namespace compaction

TEST(SiiBuild, ContentThatDoesNotFitIsCompactedInTheDocumentedOrder) {
    for (const auto& [name, make] : esi_test::all_devices()) {
        SCOPED_TRACE(name);
        Device d = make();
        compaction::check_sizes(d);
    }
}

// A small CoE coupler with a long name and DC modes described at length, as old couplers are declared (256
// bytes of EEPROM): every level down to the device name shown as the order number is reached at some size.
TEST(SiiBuild, DcDescriptionsAndTheLongNameGoLast) {
    Device d = esi_test::small_device();
    d.description.identity.order_code = "CPL100";
    // A name long enough that leaving it out makes the content fit one 128-byte step smaller.
    d.description.identity.device_name = "CPL100 EtherCAT fieldbus coupler " + std::string(160, 'x');
    d.description.dc_modes.clear();
    for (int i = 0; i < 3; ++i) {
        od::DcOpMode mode;
        mode.name = "DcSync" + std::to_string(i);
        mode.description = "Channel " + std::to_string(i) + " synchronised to SYNC0, described at length";
        mode.assign_activate = 0x0300;
        d.description.dc_modes.push_back(mode);
    }
    compaction::check_sizes(d);
    // The sizes at which descriptions go and at which the name goes are both reached.
    bool saw_descriptions_gone = false, saw_name_as_order = false;
    for (uint16_t bytes = 128; bytes <= 1024; bytes = static_cast<uint16_t>(bytes + 128)) {
        d.description.eeprom_bytes = bytes;
        try {
            const esi::SiiInfo info = esi::parse_sii(esi::build_sii(d.description, d.dictionary));
            saw_name_as_order = saw_name_as_order || info.general->name == "CPL100";
            for (const esi::SiiDcMode& mode : info.dc_modes)
                saw_descriptions_gone = saw_descriptions_gone || mode.description_idx == 0;
        } catch (const std::length_error&) {
        }
    }
    EXPECT_TRUE(saw_descriptions_gone);
    EXPECT_TRUE(saw_name_as_order);
}

TEST(SiiBuild, PaddedWithErasedBytesAndAliasInWord4) {
    Device d = esi_test::small_device();
    d.description.station_alias = 0x1234;
    d.description.eeprom_bytes = 4096;
    const auto img = esi::build_sii(d.description, d.dictionary);
    ASSERT_EQ(img.size(), 4096u);
    EXPECT_EQ(word(img, 4), 0x1234);
    EXPECT_EQ(word(img, 0x3E), 31);  // 32 KiBit - 1
    EXPECT_EQ(img.back(), 0xFF);
    const auto info = esi::parse_sii(img);
    EXPECT_TRUE(info.problems.empty());
    EXPECT_EQ(info.station_alias, 0x1234);
}

}  // namespace
