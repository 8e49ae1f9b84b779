// The drive's diagnosis texts (ETG.1020 text ids; ETG.2000 DiagMessages) end to end: every error the drive's
// table holds, raised by the drive core inside the composed device, is stored in 0x10F3 with the text id of
// the device description's text for that code, and the ESI written from the same description lists that id
// with that text, so a master (TwinCAT, ecatctl diag --esi) shows it. One test over the whole table, for the
// built-in MAXPOS and for the MAXPOS served from its own ESI.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <sstream>
#include <string>

#include "device/device.hpp"
#include "drive/drive.hpp"
#include "drive/wire/diag_texts.hpp"
#include "drive/wire/error_codes.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "esi/device/product.hpp"
#include "esi/esi.hpp"
#include "esi/esi_reader.hpp"
#include "maxpos/maxpos.hpp"

#include "support/temp_dir.hpp"

namespace {

uint32_t le32(std::span<const uint8_t> b, std::size_t at) {
    return static_cast<uint32_t>(b[at] | b[at + 1] << 8 | b[at + 2] << 16 | uint32_t{b[at + 3]} << 24);
}

// The text id of the newest stored 0x10F3 message whose diag code is the error's (ETG.1020: 0xE800 |
// code << 16); nullopt if none is stored.
std::optional<uint16_t> stored_text_id(od::Dictionary& dict, uint16_t code) {
    const uint32_t diag_code = 0xE800u | uint32_t{code} << 16;
    const uint8_t newest = static_cast<uint8_t>(dict.raw(0x10F3, 2)[0]);
    const uint8_t max = static_cast<uint8_t>(dict.raw(0x10F3, 1)[0]);
    for (uint8_t k = 0; k < max; ++k) {  // newest first, through the ring 6..5+max
        const uint8_t sub = static_cast<uint8_t>(6 + (newest - 6 + max - k) % max);
        auto m = dict.raw(0x10F3, sub);
        if (m.size() >= 8 && le32(m, 0) == diag_code) return static_cast<uint16_t>(m[6] | m[7] << 8);
    }
    return std::nullopt;
}

// The MAXPOS as the built-in product (its description binds each text to its error code), and as a device
// read from its own generated ESI (`ecat-slave --esi`): the ESI carries no binding, the error's name finds
// the text. Both must give every fault the same text id.
std::shared_ptr<const od::Product> product(const std::string& which) {
    if (which == "built-in") return nullptr;
    const od::DeviceDescription d = maxpos::description();
    return std::make_shared<const od::Product>(
        esi::load_product(esi::read_esi_text(esi::build_esi(d, maxpos::dictionary(d)), "maxpos.xml"), ""));
}

class DriveDiagTexts : public ::testing::TestWithParam<std::string> {};

TEST_P(DriveDiagTexts, EveryErrorTheDriveRaisesCarriesTheTextIdOfItsTextInTheEsi) {
    const auto dir = test_support::make_temp_dir("softecat-diag-texts-");
    esc::ManualClock clock;
    clock.set(1'000'000'000);
    device::DeviceOptions options;
    options.state_dir = dir;
    options.product = product(GetParam());
    std::ostringstream log;
    options.log = &log;
    esc::Esc esc(esc::EscConfig{}, clock);
    device::Device dev(esc, options);
    ASSERT_TRUE(dev.has_drive());

    // The built-in description binds the texts to the codes; the ESI lists them.
    const od::DeviceDescription desc = maxpos::description();
    const esi::EsiDevice esi = esi::read_esi(esi::build_esi(desc, dev.dictionary()));

    std::size_t checked = 0;
    for (const drive::ErrorInfo& e : drive::kErrorTable) {
        SCOPED_TRACE(::testing::Message() << "error 0x" << std::hex << e.code << " " << e.name);
        // The description has one text for the code: its name, an error.
        const od::DiagMessageText* text = nullptr;
        for (const od::DiagMessageText& t : desc.diag_messages)
            if (t.error_code == e.code) {
                EXPECT_EQ(text, nullptr) << "two texts for one code";
                text = &t;
            }
        ASSERT_NE(text, nullptr);
        EXPECT_NE(text->text_id, 0u);
        EXPECT_EQ(text->text, e.name);
        EXPECT_EQ(text->diag_class, "error");
        // The drive raises it (an error, or a warning where its reaction is "signal only"): the message
        // carries the id.
        dev.drive().axis().raise_error(e.code);
        EXPECT_EQ(stored_text_id(dev.dictionary(), e.code), text->text_id);
        // The ESI lists the id with the whole text, and no other text under it.
        std::size_t listed = 0;
        for (const esi::EsiDiagMessage& m : esi.diag_messages)
            if (m.text_id == text->text_id) {
                ++listed;
                EXPECT_EQ(m.text, e.name);
            }
        EXPECT_EQ(listed, 1u);
        // A master with no ESI (ecatctl diag) names the id from the built-in drive's table alike.
        EXPECT_EQ(drive::diag_text_of(text->text_id), e.name);
        ++checked;
    }
    EXPECT_EQ(checked, std::size(drive::kErrorTable));
}

INSTANTIATE_TEST_SUITE_P(Maxpos, DriveDiagTexts, ::testing::Values("built-in", "from-its-esi"),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                             std::string n = p.param;
                             std::replace(n.begin(), n.end(), '-', '_');
                             return n;
                         });

TEST(DriveDiagTextIds, AreUniqueAcrossTheDrivesOwnTextsAndItsErrors) {
    const od::DeviceDescription desc = maxpos::description();
    std::set<uint16_t> ids;
    for (const od::DiagMessageText& t : desc.diag_messages) {
        EXPECT_NE(t.text_id, 0u) << t.text;
        EXPECT_TRUE(ids.insert(t.text_id).second) << "text id 0x" << std::hex << t.text_id << " twice";
    }
    EXPECT_EQ(ids.size(), drive::kDiagTexts.size() + std::size(drive::kErrorTable));
}

}  // namespace
