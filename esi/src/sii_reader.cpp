// Parsing and decoding any SII image (ours or one read from a real device), od-free: ecatctl, the master
// tools and the conformance suite use it without the slave's object model (ETG.2010, ETG.1000.6).
#include "esi/sii_reader.hpp"

#include <algorithm>
#include <cstdio>

#include "type_names.hpp"
#include "util/strfmt.hpp"

namespace esi {
// ---------------------------------------------------------------------------------------------------
// Parsing
// ---------------------------------------------------------------------------------------------------

namespace {

// Bounds-checked little-endian reader over one span; reads past the end give 0 and set short_read.
struct Reader {
    std::span<const uint8_t> s;
    bool short_read = false;
    bool has(std::size_t off, std::size_t n) const { return off <= s.size() && n <= s.size() - off; }
    uint8_t u8(std::size_t off) {
        if (!has(off, 1)) {
            short_read = true;
            return 0;
        }
        return s[off];
    }
    uint16_t u16(std::size_t off) { return static_cast<uint16_t>(u8(off) | (u8(off + 1) << 8)); }
    uint32_t u32(std::size_t off) { return u16(off) | (static_cast<uint32_t>(u16(off + 2)) << 16); }
};

using util::strprintf;

void parse_strings(std::span<const uint8_t> body, SiiInfo& info) {
    Reader r{body};
    const uint8_t count = r.u8(0);
    std::size_t off = 1;
    for (unsigned i = 0; i < count; ++i) {
        if (!r.has(off, 1)) {
            info.problems.push_back(strprintf("STRINGS: %u strings declared, data ends after %u", count, i));
            return;
        }
        const uint8_t len = r.u8(off);
        if (!r.has(off + 1, len)) {
            info.problems.push_back(strprintf("STRINGS: string %u runs past the category", i + 1));
            return;
        }
        info.strings.emplace_back(reinterpret_cast<const char*>(body.data() + off + 1), len);
        off += 1u + len;
    }
}

void parse_general(std::span<const uint8_t> body, SiiInfo& info) {
    if (body.size() < 32) info.problems.push_back(strprintf("GENERAL: %zu bytes, expected 32", body.size()));
    Reader r{body};
    SiiGeneral g;
    g.group_idx = r.u8(0);
    g.image_idx = r.u8(1);
    g.order_idx = r.u8(2);
    g.name_idx = r.u8(3);
    g.coe_details = r.u8(5);
    g.foe_details = r.u8(6);
    g.eoe_details = r.u8(7);
    g.soe_channels = r.u8(8);
    g.ds402_channels = r.u8(9);
    g.sysman_class = r.u8(10);
    g.flags = r.u8(11);
    g.ebus_current_ma = static_cast<int16_t>(r.u16(12));
    g.group_idx_duplicate = r.u8(14);
    g.physical_ports = r.u16(16);
    g.physical_memory_address = r.u16(18);
    info.general = g;
}

void parse_syncm(std::span<const uint8_t> body, SiiInfo& info) {
    if (body.size() % 8)
        info.problems.push_back(strprintf("SYNCM: %zu bytes, not a multiple of 8", body.size()));
    Reader r{body};
    for (std::size_t off = 0; r.has(off, 8); off += 8) {
        SiiSyncManager sm;
        sm.start = r.u16(off);
        sm.length = r.u16(off + 2);
        sm.control = r.u8(off + 4);
        sm.status = r.u8(off + 5);
        sm.enable = r.u8(off + 6);
        sm.type = r.u8(off + 7);
        info.sync_managers.push_back(sm);
    }
}

void parse_pdos(std::span<const uint8_t> body, std::vector<SiiPdo>& out, const char* what, SiiInfo& info) {
    Reader r{body};
    std::size_t off = 0;
    while (off < body.size()) {
        if (!r.has(off, 8)) {
            info.problems.push_back(strprintf("%s: %zu stray bytes at the end", what, body.size() - off));
            return;
        }
        SiiPdo p;
        p.index = r.u16(off);
        const uint8_t n = r.u8(off + 2);
        p.sm = r.u8(off + 3);
        p.dc_sync = r.u8(off + 4);
        p.name_idx = r.u8(off + 5);
        p.flags = r.u16(off + 6);
        off += 8;
        for (unsigned i = 0; i < n; ++i) {
            if (!r.has(off, 8)) {
                info.problems.push_back(strprintf(
                    "%s: PDO 0x%04X declares %u entries, the category ends after %u", what, p.index, n, i));
                out.push_back(std::move(p));
                return;
            }
            SiiPdoEntry e;
            e.index = r.u16(off);
            e.subindex = r.u8(off + 2);
            e.name_idx = r.u8(off + 3);
            e.data_type = r.u8(off + 4);
            e.bit_length = r.u8(off + 5);
            e.flags = r.u16(off + 6);
            p.entries.push_back(e);
            off += 8;
        }
        out.push_back(std::move(p));
    }
}

void parse_dc(std::span<const uint8_t> body, SiiInfo& info) {
    if (body.size() % 24)
        info.problems.push_back(strprintf("DC: %zu bytes, not a multiple of 24", body.size()));
    Reader r{body};
    for (std::size_t off = 0; r.has(off, 24); off += 24) {
        SiiDcMode m;
        m.sync0_cycle_time = r.u32(off);
        m.sync0_shift_time = static_cast<int32_t>(r.u32(off + 4));
        m.sync1_shift_time = static_cast<int32_t>(r.u32(off + 8));
        m.sync1_cycle_factor = static_cast<int16_t>(r.u16(off + 12));
        m.assign_activate = r.u16(off + 14);
        m.sync0_cycle_factor = static_cast<int16_t>(r.u16(off + 16));
        m.name_idx = r.u8(off + 18);
        m.description_idx = r.u8(off + 19);
        info.dc_modes.push_back(m);
    }
}

}  // namespace

std::string SiiInfo::string_at(uint8_t index) const {
    if (index == 0 || index > strings.size()) return {};
    return strings[index - 1u];
}

SiiInfo parse_sii(std::span<const uint8_t> image) {
    SiiInfo info;
    info.image_bytes = image.size();
    Reader r{image};
    info.header_complete = image.size() >= kSiiFirstCategoryWord * 2;
    if (!info.header_complete)
        info.problems.push_back(strprintf("image has %zu bytes, the header alone needs 128", image.size()));

    info.pdi_control = r.u8(0);
    info.esc_config = r.u8(1);
    info.pdi_config = r.u16(2);
    info.sync_pulse_length = r.u16(4);
    info.extended_pdi_config = r.u16(6);
    info.station_alias = r.u16(8);
    info.checksum_word = r.u16(14);
    if (r.has(0, sii::kCrcBytes)) info.crc_computed = sii::crc8(image.data(), sii::kCrcBytes);
    info.crc_disabled = r.has(14, 2) && info.checksum_word == kSiiChecksumDisabled;
    info.crc_ok = r.has(14, 2) && (info.crc_disabled || (info.checksum_word & 0xFF) == info.crc_computed);
    if (r.has(14, 2) && !info.crc_ok)
        info.problems.push_back(strprintf("checksum word 7 = 0x%04X, CRC-8 of words 0-6 is 0x%02X",
                                          info.checksum_word, info.crc_computed));
    info.vendor_id = r.u32(0x08 * 2);
    info.product_code = r.u32(0x0A * 2);
    info.revision = r.u32(0x0C * 2);
    info.serial_number = r.u32(0x0E * 2);
    info.bootstrap_mailbox = {r.u16(0x14 * 2), r.u16(0x15 * 2), r.u16(0x16 * 2), r.u16(0x17 * 2)};
    info.standard_mailbox = {r.u16(0x18 * 2), r.u16(0x19 * 2), r.u16(0x1A * 2), r.u16(0x1B * 2)};
    info.mailbox_protocols = r.u16(0x1C * 2);
    info.eeprom_size_word = r.u16(0x3E * 2);
    info.version = r.u16(0x3F * 2);
    if (!info.header_complete) return info;

    std::size_t word = kSiiFirstCategoryWord;
    const std::size_t words = image.size() / 2;
    while (word < words) {
        const uint16_t type = r.u16(word * 2);
        if (type == category::End) {
            info.end_found = true;
            break;
        }
        if (word + 1 >= words) {
            info.problems.push_back(
                strprintf("category %u at word 0x%04zX: the image ends inside its header", type, word));
            break;
        }
        SiiCategory c;
        c.type = type;
        c.word_offset = word;
        c.word_length = r.u16(word * 2 + 2);
        const std::size_t start = (word + 2) * 2;
        std::size_t bytes = std::size_t{c.word_length} * 2;
        if (start + bytes > image.size()) {
            c.truncated = true;
            bytes = image.size() > start ? image.size() - start : 0;
            info.problems.push_back(
                strprintf("category %u at word 0x%04zX: %u words declared, the image ends after %zu", type,
                          word, c.word_length, bytes / 2));
        }
        info.categories.push_back(c);
        const auto body = image.subspan(std::min(start, image.size()), bytes);
        switch (type) {
            case category::Strings:
                parse_strings(body, info);
                break;
            case category::General:
                parse_general(body, info);
                break;
            case category::Fmmu:
                info.fmmus.assign(body.begin(), body.end());
                break;
            case category::SyncM:
                parse_syncm(body, info);
                break;
            case category::TxPdo:
                parse_pdos(body, info.tx_pdos, "TXPDO", info);
                break;
            case category::RxPdo:
                parse_pdos(body, info.rx_pdos, "RXPDO", info);
                break;
            case category::Dc:
                parse_dc(body, info);
                break;
            default:
                break;  // NOP, device/vendor specific, FMMUX, SyncUnit: kept as raw categories
        }
        if (c.truncated) break;
        word += 2 + std::size_t{c.word_length};
    }
    if (!info.end_found) info.problems.push_back("no end category (0xFFFF) inside the image");

    // Resolve string indices.
    auto check = [&](uint8_t idx, const char* what) {
        if (idx > info.strings.size())
            info.problems.push_back(
                strprintf("%s refers to string %u, the table has %zu", what, idx, info.strings.size()));
        return info.string_at(idx);
    };
    if (info.general) {
        auto& g = *info.general;
        g.group = check(g.group_idx, "GENERAL group");
        g.image = check(g.image_idx, "GENERAL image");
        g.order = check(g.order_idx, "GENERAL order");
        g.name = check(g.name_idx, "GENERAL name");
    }
    for (auto* list : {&info.tx_pdos, &info.rx_pdos})
        for (auto& p : *list) {
            p.name = check(p.name_idx, "PDO name");
            for (auto& e : p.entries)
                e.name = check(e.name_idx, "PDO entry name");
        }
    for (auto& m : info.dc_modes) {
        m.name = check(m.name_idx, "DC name");
        m.description = check(m.description_idx, "DC description");
    }
    return info;
}

// ---------------------------------------------------------------------------------------------------
// Decoding to text
// ---------------------------------------------------------------------------------------------------

namespace {

// A string from the image, with control characters shown as \xNN so the text stays one line per item.
std::string printable(const std::string& in) {
    std::string out;
    for (char ch : in) {
        const auto c = static_cast<unsigned char>(ch);
        if (c < 0x20 || c == 0x7F || c == '"' || c == '\\')
            out += strprintf("\\x%02X", c);
        else
            out += ch;
    }
    return out;
}

const char* category_name(uint16_t t) {
    switch (t) {
        case category::Nop:
            return "NOP";
        case category::Strings:
            return "STRINGS";
        case category::DataTypes:
            return "DATATYPES";
        case category::General:
            return "GENERAL";
        case category::Fmmu:
            return "FMMU";
        case category::SyncM:
            return "SYNCM";
        case category::FmmuX:
            return "FMMUX";
        case category::SyncUnit:
            return "SYNCUNIT";
        case category::TxPdo:
            return "TXPDO";
        case category::RxPdo:
            return "RXPDO";
        case category::Dc:
            return "DC";
        default:
            break;
    }
    if (t >= 1 && t <= 9) return "device specific";
    return "unknown/vendor specific";
}

const char* sm_type_name(uint8_t t) {
    switch (t) {
        case 0:
            return "unused";
        case 1:
            return "MBoxOut";
        case 2:
            return "MBoxIn";
        case 3:
            return "Outputs";
        case 4:
            return "Inputs";
        default:
            return "?";
    }
}

const char* fmmu_name(uint8_t t) {
    switch (t) {
        case 0x00:
        case 0xFF:
            return "unused";
        case 0x01:
            return "Outputs";
        case 0x02:
            return "Inputs";
        case 0x03:
            return "MBoxState";
        default:
            return "?";
    }
}

std::string bit_names(uint16_t bits, std::initializer_list<std::pair<uint16_t, const char*>> names) {
    std::string s;
    for (const auto& [bit, name] : names)
        if (bits & bit) {
            if (!s.empty()) s += ' ';
            s += name;
        }
    return s.empty() ? "-" : s;
}

void hexdump(std::string& out, std::span<const uint8_t> bytes, std::size_t base) {
    for (std::size_t i = 0; i < bytes.size(); i += 16) {
        out += strprintf("    %04zX:", base + i);
        for (std::size_t j = i; j < std::min(i + 16, bytes.size()); ++j)
            out += strprintf(" %02X", bytes[j]);
        out += '\n';
    }
}

void decode_pdos(std::string& out, const std::vector<SiiPdo>& pdos) {
    for (const auto& p : pdos) {
        out += strprintf("    PDO 0x%04X \"%s\" entries %zu, SM %s, flags 0x%04X (%s)\n", p.index,
                         printable(p.name).c_str(), p.entries.size(),
                         p.sm == 0xFF ? "none" : std::to_string(p.sm).c_str(), p.flags,
                         bit_names(p.flags, {{pdo_flags::Mandatory, "mandatory"},
                                             {pdo_flags::Default, "default"},
                                             {pdo_flags::FixedContent, "fixed"},
                                             {pdo_flags::VirtualContent, "virtual"},
                                             {pdo_flags::OverwrittenByModule, "overwritten-by-module"}})
                             .c_str());
        for (const auto& e : p.entries) {
            const char* tn = detail::base_type_name(e.data_type);
            if (e.index == 0)
                out += strprintf("      gap %u bits\n", e.bit_length);
            else
                out +=
                    strprintf("      0x%04X:%02X %2u bits %-6s \"%s\"\n", e.index, e.subindex, e.bit_length,
                              tn ? tn : strprintf("0x%02X", e.data_type).c_str(), printable(e.name).c_str());
        }
    }
}

}  // namespace

std::string decode_sii(std::span<const uint8_t> image) {
    const SiiInfo info = parse_sii(image);
    std::string out;
    out += strprintf("SII image: %zu bytes\n", image.size());
    out += strprintf("  PDI control 0x%02X, ESC configuration 0x%02X, PDI configuration 0x%04X\n",
                     info.pdi_control, info.esc_config, info.pdi_config);
    out += strprintf("  SYNC pulse length %u (x10 ns), extended PDI configuration 0x%04X, station alias %u\n",
                     info.sync_pulse_length, info.extended_pdi_config, info.station_alias);
    out +=
        strprintf("  checksum 0x%04X: %s\n", info.checksum_word,
                  info.crc_disabled ? "check disabled (0x88A4)"
                  : info.crc_ok     ? "ok"
                                : strprintf("BAD (CRC-8 of words 0-6 is 0x%02X)", info.crc_computed).c_str());
    out += strprintf("  vendor 0x%08X, product 0x%08X, revision 0x%08X, serial 0x%08X\n", info.vendor_id,
                     info.product_code, info.revision, info.serial_number);
    out += strprintf("  bootstrap mailbox: out 0x%04X/%u, in 0x%04X/%u\n", info.bootstrap_mailbox.out_start,
                     info.bootstrap_mailbox.out_size, info.bootstrap_mailbox.in_start,
                     info.bootstrap_mailbox.in_size);
    out += strprintf("  standard mailbox:  out 0x%04X/%u, in 0x%04X/%u\n", info.standard_mailbox.out_start,
                     info.standard_mailbox.out_size, info.standard_mailbox.in_start,
                     info.standard_mailbox.in_size);
    out += strprintf("  mailbox protocols 0x%04X (%s)\n", info.mailbox_protocols,
                     bit_names(info.mailbox_protocols, {{mailbox_protocol::AoE, "AoE"},
                                                        {mailbox_protocol::EoE, "EoE"},
                                                        {mailbox_protocol::CoE, "CoE"},
                                                        {mailbox_protocol::FoE, "FoE"},
                                                        {mailbox_protocol::SoE, "SoE"},
                                                        {mailbox_protocol::VoE, "VoE"}})
                         .c_str());
    out += strprintf("  EEPROM size word 0x%04X (%zu bytes), version %u\n", info.eeprom_size_word,
                     info.eeprom_bytes(), info.version);

    for (const SiiCategory& c : info.categories) {
        out += strprintf("category %u %s at word 0x%04zX, %u words%s\n", c.type, category_name(c.type),
                         c.word_offset, c.word_length, c.truncated ? " (TRUNCATED)" : "");
        switch (c.type) {
            case category::Strings:
                for (std::size_t i = 0; i < info.strings.size(); ++i)
                    out += strprintf("    %3zu \"%s\"\n", i + 1, printable(info.strings[i]).c_str());
                break;
            case category::General:
                if (info.general) {
                    const auto& g = *info.general;
                    out += strprintf(
                        "    group %u \"%s\", image %u \"%s\", order %u \"%s\", name %u \"%s\"\n",
                        g.group_idx, printable(g.group).c_str(), g.image_idx, printable(g.image).c_str(),
                        g.order_idx, printable(g.order).c_str(), g.name_idx, printable(g.name).c_str());
                    out += strprintf(
                        "    CoE details 0x%02X (%s), FoE 0x%02X, EoE 0x%02X, SoE channels %u, DS402 "
                        "channels %u\n",
                        g.coe_details,
                        bit_names(g.coe_details, {{coe_details::Sdo, "SDO"},
                                                  {coe_details::SdoInfo, "SDOInfo"},
                                                  {coe_details::PdoAssign, "PDOAssign"},
                                                  {coe_details::PdoConfig, "PDOConfig"},
                                                  {coe_details::PdoUpload, "PDOUpload"},
                                                  {coe_details::CompleteAccess, "CompleteAccess"}})
                            .c_str(),
                        g.foe_details, g.eoe_details, g.soe_channels, g.ds402_channels);
                    out += strprintf(
                        "    SysmanClass %u, flags 0x%02X, EBus current %d mA, ports 0x%04X, "
                        "identification address 0x%04X\n",
                        g.sysman_class, g.flags, g.ebus_current_ma, g.physical_ports,
                        g.physical_memory_address);
                }
                break;
            case category::Fmmu:
                for (std::size_t i = 0; i < info.fmmus.size(); ++i)
                    out += strprintf("    FMMU%zu 0x%02X %s\n", i, info.fmmus[i], fmmu_name(info.fmmus[i]));
                break;
            case category::SyncM:
                for (std::size_t i = 0; i < info.sync_managers.size(); ++i) {
                    const auto& s = info.sync_managers[i];
                    out += strprintf(
                        "    SM%zu start 0x%04X length %u control 0x%02X enable 0x%02X type %u %s\n", i,
                        s.start, s.length, s.control, s.enable, s.type, sm_type_name(s.type));
                }
                break;
            case category::TxPdo:
                decode_pdos(out, info.tx_pdos);
                break;
            case category::RxPdo:
                decode_pdos(out, info.rx_pdos);
                break;
            case category::Dc:
                for (const auto& m : info.dc_modes)
                    out += strprintf(
                        "    \"%s\" (%s): AssignActivate 0x%04X, SYNC0 cycle %u factor %d shift %d, "
                        "SYNC1 factor %d shift %d\n",
                        printable(m.name).c_str(), printable(m.description).c_str(), m.assign_activate,
                        m.sync0_cycle_time, m.sync0_cycle_factor, m.sync0_shift_time, m.sync1_cycle_factor,
                        m.sync1_shift_time);
                break;
            default: {
                const std::size_t start = (c.word_offset + 2) * 2;
                const std::size_t len = std::min<std::size_t>(
                    std::size_t{c.word_length} * 2, image.size() > start ? image.size() - start : 0);
                hexdump(out, image.subspan(std::min(start, image.size()), len), start);
                break;
            }
        }
    }
    if (info.end_found) out += "end of categories\n";
    for (const auto& p : info.problems)
        out += "PROBLEM: " + p + "\n";
    return out;
}

}  // namespace esi
