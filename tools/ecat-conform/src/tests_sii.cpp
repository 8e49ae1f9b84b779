// Group sii: the EEPROM read back whole, its header, every category well-formed, and the SII compared with
// the ESI (ETG.2000 describes how an ESI becomes the SII image).
#include <map>
#include <set>

#include "esc/wire/sii.hpp"
#include "testkit.hpp"

namespace conform {

// Each PDO entry's data type (ETG.2010 PDO entry byte 4, the CoE base type's index) against its bit length
// (byte 5): a type of fixed size names that size (BIT1-BIT8 their bits; 0, padding, BOOLEAN, which ESIs map
// as 1 or 8 bits, or a type of no fixed size, is not judged). "" or the first entry that disagrees.
std::string sii_pdo_entry_types(std::span<const uint8_t> d) {
    auto bits_of = [](uint8_t t) -> unsigned {
        switch (t) {
            case 0x02:
            case 0x05:
                return 8;  // INTEGER8, UNSIGNED8
            case 0x03:
            case 0x06:
                return 16;  // INTEGER16, UNSIGNED16
            case 0x04:
            case 0x07:
            case 0x08:
                return 32;  // INTEGER32, UNSIGNED32, REAL32
            case 0x10:
            case 0x16:
                return 24;  // INTEGER24, UNSIGNED24
            case 0x11:
            case 0x15:
            case 0x1B:
                return 64;  // REAL64, INTEGER64, UNSIGNED64
            default:
                return (t >= 0x30 && t <= 0x37) ? t - 0x2Fu : 0;  // BIT1..BIT8
        }
    };
    std::size_t p = 0;
    while (p + 8 <= d.size()) {
        const uint16_t pdo = get16(&d[p]);
        const uint8_t n = d[p + 2];
        p += 8;
        for (uint8_t i = 0; i < n && p + 8 <= d.size(); ++i, p += 8) {
            const unsigned want = bits_of(d[p + 4]);
            if (get16(&d[p]) != 0 && want && d[p + 5] != want)
                return "PDO " + hex(pdo) + " entry " + hex(get16(&d[p])) + ":" + dec(d[p + 2]) +
                       " data type " + hex(d[p + 4], 2) + " (" + dec(want) + " bits) with bit length " +
                       dec(d[p + 5]);
        }
    }
    return {};
}

namespace {

constexpr const char* kSii = "ETG.1000.6 Slave Information Interface (SII) content";
constexpr const char* kSiiEsi = "ETG.2000 ESI to SII mapping; ETG.1000.6 SII content";
constexpr uint16_t kStrings = 10, kGeneral = 30, kFmmu = 40, kSyncM = 41, kTxPdo = 50, kRxPdo = 51, kDc = 60;

std::string esi_sm(const EsiSm& s) {
    return hex(s.start) + "/" + dec(s.default_size) + "/" + hex(s.control, 2) + "/" + (s.enable ? "1" : "0");
}

// What an Sm is: its text where it is one of the four ETG.2000 names; an Sm without such a text (a master's
// export of the device writes none: IgH's `ethercat xml`, TwinCAT's online description) is what its
// ControlByte makes of it in the ESC (datasheet 0x0804: bits 0-1 10 mailbox, 00 buffered; bits 2-3 01 the
// master writes, 00 it reads), as the slave and a master reading the SII take it. "" if neither says.
std::string sm_kind(const EsiSm& s) {
    for (const char* t : {"MBoxOut", "MBoxIn", "Outputs", "Inputs"})
        if (s.type == t) return t;
    if (!s.has_control) return {};
    const bool write = ((s.control >> 2) & 0x03) == 0x01;
    if ((s.control & 0x03) == 0x02) return write ? "MBoxOut" : "MBoxIn";
    return write ? "Outputs" : "Inputs";
}

struct SiiPdo {
    uint16_t index = 0;
    uint8_t sm = 0;
    uint16_t flags = 0;                // ETG.2010 PDO flags (bytes 6-7)
    std::vector<std::string> entries;  // "idx:sub/bits"
};

// Walks a PDO category; "" or why it is malformed.
std::string parse_pdos(std::span<const uint8_t> d, std::vector<SiiPdo>& out) {
    std::size_t p = 0;
    while (p + 8 <= d.size()) {
        SiiPdo pdo;
        pdo.index = get16(&d[p]);
        const uint8_t n = d[p + 2];
        pdo.sm = d[p + 3];
        pdo.flags = get16(&d[p + 6]);
        p += 8;
        if (p + 8u * n > d.size())
            return "PDO " + hex(pdo.index) + " announces " + dec(n) + " entries past the category end";
        for (uint8_t i = 0; i < n; ++i, p += 8)
            pdo.entries.push_back(hex(get16(&d[p])) + ":" + dec(d[p + 2]) + "/" + dec(d[p + 5]));
        out.push_back(pdo);
    }
    if (p != d.size() && !(d.size() - p < 8 && std::all_of(d.begin() + static_cast<std::ptrdiff_t>(p),
                                                           d.end(), [](uint8_t b) { return b == 0; })))
        return "trailing " + dec(static_cast<long long>(d.size() - p)) + " bytes";
    return {};
}

// One PDO as "index[entry:sub/bits ...]", the form both sides are compared in.
std::string esi_pdo_text(const EsiPdo& p) {
    std::string s = hex(p.index) + "[";
    for (std::size_t i = 0; i < p.entries.size(); ++i)
        s.append(i ? " " : "")
            .append(hex(p.entries[i].index))
            .append(":")
            .append(dec(p.entries[i].subindex))
            .append("/")
            .append(dec(p.entries[i].bit_len));
    return s + "]";
}
std::string sii_pdo_text(const SiiPdo& p) {
    std::string s = hex(p.index) + "[";
    for (std::size_t i = 0; i < p.entries.size(); ++i)
        s.append(i ? " " : "").append(p.entries[i]);
    return s + "]";
}

Outcome category_present(Context& ctx, uint16_t type, const char* name) {
    CONFORM_NEED(ctx.need_sii());
    if (!ctx.sii->error.empty()) return fail("category chain broken: " + ctx.sii->error);
    if (!ctx.sii->find(type)) return skip(std::string("no ") + name + " category");
    return pass();
}

// Every category of a PDO type (ETG.2010: TxPDO/RxPDO categories may repeat, one per PDO or a few PDOs
// each; a reader that takes the first only misses the rest): their PDOs in order, or the first parse error.
std::string parse_pdo_categories(const Context& ctx, uint16_t type, std::vector<SiiPdo>& pdos) {
    for (const auto& k : ctx.sii->categories)
        if (k.type == type)
            if (auto e = parse_pdos(ctx.sii->data(k), pdos); !e.empty()) return e;
    return {};
}

Outcome pdo_category(Context& ctx, uint16_t type) {
    Outcome o = category_present(ctx, type, type == kTxPdo ? "TXPDO" : "RXPDO");
    if (o.status != Status::Pass) return o;
    std::vector<SiiPdo> pdos;
    if (auto e = parse_pdo_categories(ctx, type, pdos); !e.empty()) return fail(e);
    const SiiCategory* sm = ctx.sii->find(kSyncM);
    const std::size_t sms = sm ? sm->length / 8 : 0;
    for (const auto& p : pdos)
        if (p.sm != 0xFF && p.sm >= sms && sms)
            return fail("PDO " + hex(p.index) + " names SM " + dec(p.sm), dec(p.sm),
                        "< " + dec(static_cast<long long>(sms)));
    for (const auto& k : ctx.sii->categories)
        if (k.type == type)
            if (auto e = sii_pdo_entry_types(ctx.sii->data(k)); !e.empty()) return fail(e);
    return pass(dec(static_cast<long long>(pdos.size())) + " PDOs");
}

// The SII's PDOs against the ESI's (ETG.2010 TxPDO/RxPDO categories, ETG.2000 TxPdo/RxPdo): every PDO of the
// SII is one of the ESI with the same entries, and every PDO the ESI assigns by default (Sm attribute) or
// marks mandatory is in the SII. The ESI's other PDOs (alternatives a master may assign over CoE) may be left
// out of the SII: the device's object dictionary describes them.
Outcome pdo_vs_esi(Context& ctx, uint16_t type) {
    CONFORM_NEED(ctx.need_esi());
    CONFORM_NEED(ctx.need_sii());
    const auto& esi = type == kTxPdo ? ctx.esi->txpdos : ctx.esi->rxpdos;
    std::vector<SiiPdo> pdos;
    const SiiCategory* category = ctx.sii->find(type);
    if (category) parse_pdo_categories(ctx, type, pdos);
    if (esi.empty() && pdos.empty()) return skip("no PDOs of this direction in ESI or SII");
    // A slave with CoE describes its PDOs in its object dictionary (0x1C12/0x1C13 and the mapping objects),
    // where masters read them; the SII's PDO categories are for devices without CoE (ETG.2010), and EEPROM
    // images made for CoE devices often leave them out. One that is there must still be right.
    if (!category && ctx.has_coe())
        return skip(std::string("no ") + (type == kTxPdo ? "TXPDO" : "RXPDO") +
                    " category: the slave announces CoE, whose dictionary describes its PDOs");
    std::map<uint16_t, const EsiPdo*> by_index;
    for (const auto& p : esi)
        by_index.emplace(p.index, &p);
    std::set<uint16_t> in_sii;
    for (const auto& p : pdos) {
        in_sii.insert(p.index);
        const auto at = by_index.find(p.index);
        if (at == by_index.end()) return fail("the SII has PDO " + hex(p.index) + ", the ESI has none");
        if (sii_pdo_text(p) != esi_pdo_text(*at->second))
            return fail("PDO " + hex(p.index) + " differs", sii_pdo_text(p), esi_pdo_text(*at->second));
        // The SyncManager byte (ETG.2010 PDO category, byte 3) of a PDO the ESI assigns by default (Sm
        // attribute); 0xFF (not assigned) is left alone.
        if (at->second->sm >= 0 && p.sm != 0xFF && p.sm != at->second->sm)
            return fail("PDO " + hex(p.index) + " SyncManager", dec(p.sm), dec(at->second->sm) + " (ESI Sm)");
        // The flags a master acts on (ETG.2010 PDO flags): PdoMandatory and PdoFixedContent as the ESI's
        // Mandatory and Fixed attributes (a fixed PDO is not remapped, a mandatory one is always assigned).
        const uint16_t mask = esc::sii::pdo_flags::Mandatory | esc::sii::pdo_flags::FixedContent;
        const uint16_t want =
            static_cast<uint16_t>((at->second->mandatory ? esc::sii::pdo_flags::Mandatory : 0) |
                                  (at->second->fixed ? esc::sii::pdo_flags::FixedContent : 0));
        if ((p.flags & mask) != want)
            return fail("PDO " + hex(p.index) + " flags (bit 0 PdoMandatory, bit 4 PdoFixedContent)",
                        hex(p.flags & mask), hex(want) + " (ESI Mandatory/Fixed)");
    }
    int optional_left_out = 0;
    for (const auto& p : esi) {
        if (in_sii.count(p.index)) continue;
        if (p.sm >= 0 || p.mandatory)
            return fail("PDO " + hex(p.index) +
                        (p.sm >= 0 ? " (assigned by default to SM " + dec(p.sm) + ")" : " (mandatory)") +
                        " is missing from the SII");
        ++optional_left_out;
    }
    return pass(dec(static_cast<long long>(pdos.size())) + " PDOs as in the ESI" +
                (optional_left_out ? ", " + dec(optional_left_out) + " optional ones only in the ESI" : ""));
}

}  // namespace

void add_sii_tests(Catalogue& c) {
    Adder add{c, "sii"};
    add("read.whole", "The whole EEPROM (size from word 0x3E) reads back", kSii, [](Context& ctx) {
        // Every slave has an SII (ETG.1000.6): one that cannot be read is a failure here, where it is found
        // (the other tests that need it are skipped with the reason).
        if (!ctx.sii) return fail("the SII could not be read", ctx.sii_error, "the SII image");
        const std::size_t want = (ctx.sii->word(0x3E) + 1u) * 128u;
        if (ctx.sii->bytes.size() != want)
            return fail("bytes read", dec(static_cast<long long>(ctx.sii->bytes.size())),
                        dec(static_cast<long long>(want)));
        return pass("read", dec(static_cast<long long>(want)) + " bytes");
    });
    add("read.consistent", "Reading a word twice gives the same value (header words 0..0x3F)", kSii,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            uint8_t b[128];
            if (auto e = ctx.m.sii_read(ctx.addr, 0, b); e != master::Error::Ok)
                return fail("second read", err(e));
            return expect_eq("header bytes", bytes_hex(std::span<const uint8_t>(b, 128), 128),
                             bytes_hex(std::span<const uint8_t>(ctx.sii->bytes).subspan(0, 128), 128));
        });
    add("interface.status",
        "EEPROM interface 0x0500-0x0507 after a read: not busy, no command, write-enable or loading error, "
        "no checksum error with a correct checksum; the PDI does not hold the EEPROM, write enable "
        "cleared; the EEPROM address 0x0504 reads back the address of the command",
        "ETG.1000.4 SII access; ESC datasheet section II EEPROM interface 0x0500-0x0502 (bits 0, 7, 11-15 "
        "of 0x0502, bit 0 of 0x0500/0x0501), 0x0504 EEPROM address (read/write for EtherCAT)",
        [](Context& ctx) {
            uint8_t b[8];
            const auto e = ctx.m.sii_read(ctx.addr, 0, b);
            auto st = ctx.rd<uint16_t>(master::reg::SiiControl);
            if (!st) return fail("0x0502 unreadable", err(st.error()));
            if (e != master::Error::Ok)
                return fail("SII read of word 0: " + err(e), hex(*st), "a completed read");
            CONFORM_NEED(ctx.need_sii());
            const bool crc_ok = esc::sii::crc8(ctx.sii->bytes.data(), 14) == ctx.sii->bytes[14];
            // 11 checksum error, 12 loading error (device information not loaded), 13 command error (missing
            // acknowledge / invalid command), 14 write-enable error, 15 busy.
            const uint16_t mask = crc_ok ? 0xF800 : 0xE000;
            if (*st & mask)
                return fail("error or busy bits after a successful read", hex(*st),
                            std::string("bits ") + (crc_ok ? "11-15" : "13-15") + " clear");
            // The other defined bits of the interface (ESC datasheet section II, 0x0500-0x0502), each against
            // what the read just showed: the ECAT side had the EEPROM (its command completed); the PDI can
            // hold it (0x0501 bit 0) only where 0x0500 bit 0 offers it; write enable (0x0502 bit 0) clears
            // itself with the next frame and reads 1 only while the PDI has the EEPROM.
            auto cfg = ctx.rd<uint16_t>(master::reg::SiiConfig);
            if (!cfg) return fail("0x0500 unreadable", err(cfg.error()));
            const bool offered = *cfg & 0x0001, pdi_holds = *cfg & 0x0100;
            if (pdi_holds && !offered)
                return fail(
                    "0x0501 bit 0 (PDI has EEPROM access) without the offer of 0x0500 bit 0, right after "
                    "an ECAT read completed",
                    "0x0500 = " + hex(*cfg), "0x0501 bit 0 clear");
            if ((*st & 0x0001) && !pdi_holds)
                return fail("0x0502 bit 0 (ECAT write enable) set after a read command", hex(*st),
                            "clear (self-clearing with the next frame)");
            // 0x0504-0x0507 EEPROM address: the address of the command, as written (read/write for
            // EtherCAT), not moved on by the read it served: one read of word 7 leaves 7 there.
            if (auto w7 = ctx.m.sii_read_word(ctx.addr, 7); !w7)
                return fail("SII read of word 7: " + err(w7.error()));
            auto a = ctx.rd<uint32_t>(0x0504);
            if (!a) return fail("0x0504 unreadable", err(a.error()));
            if (*a != 7)
                return fail("0x0504 (EEPROM address) after a read of word 7", hex(*a, 8),
                            "0x00000007 (the address written)");
            return pass("0x0500/0x0502", hex(*cfg) + " / " + hex(*st));
        });
    add(
        "interface.address_algorithm",
        "EEPROM address algorithm 0x0502 bit 7 (1 address byte: up to 16 Kbit) holds the EEPROM size of SII "
        "word 0x3E (a real EEPROM, not one the PDI emulates)",
        "ETG.1000.4 SII access; ESC datasheet section II 0x0502 bit 7 (1 address byte for 1-16 Kbit EEPROMs, "
        "2 "
        "from 32 Kbit), bit 5 (EEPROM emulated by the PDI); ETG.2010 SII word 0x3E (size in Kbit - 1)",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            auto st = ctx.rd<uint16_t>(master::reg::SiiControl);
            if (!st) return fail("0x0502 unreadable", err(st.error()));
            if (*st & 0x0020) return skip("EEPROM emulated by the PDI (0x0502 bit 5): no address algorithm");
            // Only the impossible direction is judged: an SII image may be smaller than its EEPROM (2 address
            // bytes with a size of 16 Kbit or less), but one address byte cannot reach past 16 Kbit.
            const unsigned kbit = ctx.sii->word(0x3E) + 1u;
            if (!(*st & 0x0080) && kbit > 16)
                return fail("one EEPROM address byte (0x0502 bit 7 clear) for a larger EEPROM", hex(*st),
                            "bit 7 set for " + dec(kbit) + " Kbit (SII word 0x3E)");
            return pass("0x0502", hex(*st) + ", " + dec(kbit) + " Kbit");
        },
        "an SII", Severity::Warning);
    add("header.checksum", "Checksum of words 0-6 in word 7 (CRC-8, polynomial 0x07, seed 0xFF)", kSii,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            const uint8_t crc = esc::sii::crc8(ctx.sii->bytes.data(), 14);
            return expect_eq("word 7 low byte", hex(ctx.sii->bytes[14], 2), hex(crc, 2));
        });
    add("header.version", "SII version (word 0x3F) is 1", kSii, [](Context& ctx) {
        CONFORM_NEED(ctx.need_sii());
        return expect_eq("word 0x3F", dec(ctx.sii->word(0x3F)), "1");
    });
    add(
        "header.size_vs_esi", "EEPROM size (word 0x3E) equals the ESI's Eeprom/ByteSize", kSiiEsi,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            CONFORM_NEED(ctx.need_esi());
            if (!ctx.esi->eeprom_bytes) return skip("the ESI gives no Eeprom/ByteSize");
            return expect_eq("bytes", dec((ctx.sii->word(0x3E) + 1) * 128), dec(ctx.esi->eeprom_bytes));
        },
        "ESI given");
    add(
        "header.config_vs_esi", "Configuration area (words 0-6) equals the ESI's Eeprom/ConfigData", kSiiEsi,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            CONFORM_NEED(ctx.need_esi());
            const auto& cd = ctx.esi->config_data;
            if (cd.empty()) return skip("the ESI gives no Eeprom/ConfigData");
            std::size_t n = std::min<std::size_t>(cd.size(), 14);
            return expect_eq("words 0-6", bytes_hex(std::span<const uint8_t>(ctx.sii->bytes).subspan(0, n)),
                             bytes_hex(std::span<const uint8_t>(cd).subspan(0, n)));
        },
        "ESI given");
    struct Id {
        const char* id;
        const char* title;
        std::size_t word;
        uint32_t EsiDevice::*field;
    };
    for (const Id& x : {Id{"header.vendor_vs_esi", "Vendor ID (word 0x08) equals the ESI's Vendor/Id", 0x08,
                           &EsiDevice::vendor_id},
                        Id{"header.product_vs_esi", "Product code (word 0x0A) equals the ESI's ProductCode",
                           0x0A, &EsiDevice::product_code},
                        Id{"header.revision_vs_esi", "Revision (word 0x0C) equals the ESI's RevisionNo", 0x0C,
                           &EsiDevice::revision}}) {
        add(
            x.id, x.title, kSiiEsi,
            [x](Context& ctx) {
                CONFORM_NEED(ctx.need_sii());
                CONFORM_NEED(ctx.need_esi());
                return expect_eq("identity", hex(ctx.sii->dword(x.word), 8), hex((*ctx.esi).*(x.field), 8));
            },
            "ESI given");
    }
    add(
        "header.std_mailbox_vs_esi",
        "Standard mailbox (words 0x18-0x1B) equals the ESI's MBoxOut/MBoxIn Sm (0 without a mailbox)",
        kSiiEsi,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            CONFORM_NEED(ctx.need_esi());
            std::string want;
            for (const char* t : {"MBoxOut", "MBoxIn"})
                for (const auto& s : ctx.esi->sms)
                    if (sm_kind(s) == t) want += hex(s.start) + "/" + dec(s.default_size) + " ";
            if (want.empty()) {
                // ETG.2010 SII words 0x18-0x1B: 0 for a device without a mailbox. Nonzero words announce a
                // mailbox a master would set up and talk to.
                if (ctx.esi->has_mailbox) return skip("the ESI has a Mailbox element but no mailbox SMs");
                std::string got;
                for (unsigned w = 0x18; w <= 0x1B; ++w)
                    got += hex(ctx.sii->word(w)) + " ";
                return expect_eq("words 0x18-0x1B of a device without mailbox (the ESI has none)", got,
                                 "0x0000 0x0000 0x0000 0x0000 ");
            }
            std::string got = hex(ctx.sii->word(0x18)) + "/" + dec(ctx.sii->word(0x19)) + " " +
                              hex(ctx.sii->word(0x1A)) + "/" + dec(ctx.sii->word(0x1B)) + " ";
            return expect_eq("out/in start/size", got, want);
        },
        "ESI given");
    add(
        "header.boot_mailbox_vs_esi", "Bootstrap mailbox (words 0x14-0x17) equals the ESI's Eeprom/BootStrap",
        kSiiEsi,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            CONFORM_NEED(ctx.need_esi());
            if (ctx.esi->bootstrap.size() < 8) return skip("the ESI gives no Eeprom/BootStrap");
            return expect_eq("words 0x14-0x17",
                             bytes_hex(std::span<const uint8_t>(ctx.sii->bytes).subspan(0x28, 8)),
                             bytes_hex(std::span<const uint8_t>(ctx.esi->bootstrap).subspan(0, 8)));
        },
        "ESI gives Eeprom/BootStrap");
    add(
        "header.protocols_vs_esi", "Mailbox protocols (word 0x1C) equal the ESI's Mailbox element", kSiiEsi,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            CONFORM_NEED(ctx.need_esi());
            return expect_eq("word 0x1C", hex(ctx.sii->word(0x1C) & 0x3F), hex(ctx.esi->mailbox_protocols()));
        },
        "ESI given");
    add(
        "header.mailbox_sizes", "Standard mailbox sizes hold a mailbox header and a CoE SDO (>= 16 bytes)",
        kSii,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_mailbox());
            if (ctx.sii->word(0x19) < 16 || ctx.sii->word(0x1B) < 16)
                return fail("mailbox too small", dec(ctx.sii->word(0x19)) + "/" + dec(ctx.sii->word(0x1B)),
                            ">= 16/16");
            return pass("sizes", dec(ctx.sii->word(0x19)) + "/" + dec(ctx.sii->word(0x1B)));
        },
        "mailbox slave");
    add("cat.chain", "Category chain from word 0x40 ends with 0xFFFF inside the EEPROM", kSii,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            if (!ctx.sii->error.empty()) return fail(ctx.sii->error);
            return pass(dec(static_cast<long long>(ctx.sii->categories.size())) + " categories");
        });
    add("cat.unique", "Each of STRINGS, General, FMMU, SyncM and DC appears at most once", kSii,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            std::map<uint16_t, int> n;
            for (const auto& k : ctx.sii->categories)
                ++n[k.type];
            for (uint16_t t : {kStrings, kGeneral, kFmmu, kSyncM, kDc})
                if (n[t] > 1) return fail("category " + dec(t) + " repeated", dec(n[t]), "1");
            return pass();
        });
    add("cat.strings", "STRINGS category: count and lengths fit the category, no control characters", kSii,
        [](Context& ctx) {
            Outcome o = category_present(ctx, kStrings, "STRINGS");
            if (o.status != Status::Pass) return o;
            auto d = ctx.sii->data(*ctx.sii->find(kStrings));
            if (d.empty()) return fail("empty STRINGS category");
            std::size_t p = 1;
            for (unsigned i = 0; i < d[0]; ++i) {
                if (p >= d.size() || p + 1 + d[p] > d.size())
                    return fail("string " + dec(i + 1) + " runs past the category",
                                dec(static_cast<long long>(p)), "< " + dec(static_cast<long long>(d.size())));
                // A string is its characters (ETG.2010 STRINGS: length, then the text the ESI gives): a
                // control character (a NUL of a fixed-width field padded out, a terminator counted in the
                // length) makes the name a master shows and compares another one. Bytes from 0x80 (a code
                // page's letters) are text.
                for (std::size_t k = p + 1; k < p + 1 + d[p]; ++k)
                    if (d[k] < 0x20 || d[k] == 0x7F)
                        return fail("string " + dec(i + 1) + " holds a control character at position " +
                                        dec(static_cast<long long>(k - p)),
                                    bytes_hex(d.subspan(p + 1, d[p]), 32), "visible characters only");
                p += 1 + d[p];
            }
            // ETG.2010 STRINGS: the count, then that many strings; what follows in the category's words is no
            // more than padding (0x00, or 0xFF of an erased EEPROM). A string after the counted ones is one
            // the count left out: a reader that goes by the count loses it (and the indices that name it).
            if (p < d.size()) {
                const uint8_t pad = d[p];
                const bool padding = (pad == 0x00 || pad == 0xFF) &&
                                     std::all_of(d.begin() + static_cast<std::ptrdiff_t>(p), d.end(),
                                                 [pad](uint8_t b) { return b == pad; });
                if (!padding)
                    return fail(
                        "data after the " + dec(d[0]) + " counted strings (a string the count leaves out)",
                        bytes_hex(d.subspan(p), 16), "padding (0x00 or 0xff) only");
            }
            return pass(dec(d[0]) + " strings");
        });
    add("cat.general", "General category present (mailbox slaves) and 32 bytes long", kSii, [](Context& ctx) {
        CONFORM_NEED(ctx.need_sii());
        const SiiCategory* g = ctx.sii->find(kGeneral);
        if (!g) {
            if (ctx.sii->word(0x1C)) return fail("a mailbox slave without General category");
            return skip("no General category (no mailbox)");
        }
        if (g->length < 32)
            return fail("General category length", dec(static_cast<long long>(g->length)), ">= 32 bytes");
        return pass();
    });
    add("cat.string_refs", "String indices in General, PDO and DC categories name existing strings", kSii,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            const SiiCategory* s = ctx.sii->find(kStrings);
            const unsigned count = s && s->length ? ctx.sii->bytes[s->offset] : 0;
            auto bad = [&](unsigned i) { return i > count; };
            if (const SiiCategory* g = ctx.sii->find(kGeneral); g && g->length >= 4) {
                auto d = ctx.sii->data(*g);
                for (int i : {0, 1, 2, 3})
                    if (bad(d[static_cast<std::size_t>(i)]))
                        return fail(
                            "General byte " + dec(i) + " names string " + dec(d[static_cast<std::size_t>(i)]),
                            dec(d[static_cast<std::size_t>(i)]), "<= " + dec(count));
            }
            for (uint16_t t : {kTxPdo, kRxPdo}) {
                for (const auto& k : ctx.sii->categories) {
                    if (k.type != t) continue;
                    auto d = ctx.sii->data(k);
                    std::size_t p = 0;
                    while (p + 8 <= d.size()) {
                        if (bad(d[p + 5]))
                            return fail("PDO " + hex(get16(&d[p])) + " name index", dec(d[p + 5]),
                                        "<= " + dec(count));
                        const uint8_t n = d[p + 2];
                        p += 8;
                        for (uint8_t i = 0; i < n && p + 8 <= d.size(); ++i, p += 8)
                            if (bad(d[p + 3]))
                                return fail("PDO entry name index", dec(d[p + 3]), "<= " + dec(count));
                    }
                }
            }
            return pass();
        });
    add("cat.fmmu", "FMMU category: one usage byte per FMMU (0 unused, 1 outputs, 2 inputs, 3 SM status)",
        kSii, [](Context& ctx) {
            Outcome o = category_present(ctx, kFmmu, "FMMU");
            if (o.status != Status::Pass) return o;
            for (uint8_t b : ctx.sii->data(*ctx.sii->find(kFmmu)))
                if (b > 3 && b != 0xFF) return fail("FMMU usage byte", hex(b, 2), "0..3 or 0xff");
            return pass();
        });
    add("cat.syncm", "SyncM category: 8 bytes per SM, type 0..4, mailbox SMs as words 0x18-0x1B", kSii,
        [](Context& ctx) {
            Outcome o = category_present(ctx, kSyncM, "SyncM");
            if (o.status != Status::Pass) return o;
            auto d = ctx.sii->data(*ctx.sii->find(kSyncM));
            if (d.size() % 8)
                return fail("length not a multiple of 8", dec(static_cast<long long>(d.size())));
            for (std::size_t i = 0; i < d.size(); i += 8) {
                if (d[i + 7] > 4)
                    return fail("SM " + dec(static_cast<long long>(i / 8)) + " type", dec(d[i + 7]), "0..4");
                if (d[i + 7] == 1 &&
                    (get16(&d[i]) != ctx.sii->word(0x18) || get16(&d[i + 2]) != ctx.sii->word(0x19)))
                    return fail("mailbox-out SM differs from words 0x18/0x19",
                                hex(get16(&d[i])) + "/" + dec(get16(&d[i + 2])),
                                hex(ctx.sii->word(0x18)) + "/" + dec(ctx.sii->word(0x19)));
                if (d[i + 7] == 2 &&
                    (get16(&d[i]) != ctx.sii->word(0x1A) || get16(&d[i + 2]) != ctx.sii->word(0x1B)))
                    return fail("mailbox-in SM differs from words 0x1A/0x1B",
                                hex(get16(&d[i])) + "/" + dec(get16(&d[i + 2])),
                                hex(ctx.sii->word(0x1A)) + "/" + dec(ctx.sii->word(0x1B)));
            }
            return pass(dec(static_cast<long long>(d.size() / 8)) + " SMs");
        });
    add("cat.txpdo",
        "TXPDO category: PDOs and entries fit, SM index valid, entry data types of their bit length", kSii,
        [](Context& ctx) { return pdo_category(ctx, kTxPdo); });
    add("cat.rxpdo",
        "RXPDO category: PDOs and entries fit, SM index valid, entry data types of their bit length", kSii,
        [](Context& ctx) { return pdo_category(ctx, kRxPdo); });
    add("cat.dc", "DC category: 24 bytes per op mode", kSii, [](Context& ctx) {
        Outcome o = category_present(ctx, kDc, "DC");
        if (o.status != Status::Pass) return o;
        auto n = ctx.sii->find(kDc)->length;
        if (n % 24) return fail("length not a multiple of 24", dec(static_cast<long long>(n)));
        return pass(dec(static_cast<long long>(n / 24)) + " op modes");
    });
    add(
        "esi.syncm", "SyncM category equals the ESI's Sm elements (start, size, control, enable, type)",
        kSiiEsi,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            CONFORM_NEED(ctx.need_sii());
            std::string got, want;
            std::vector<uint16_t> sizes;
            std::vector<uint8_t> types;
            if (const SiiCategory* s = ctx.sii->find(kSyncM)) {
                auto d = ctx.sii->data(*s);
                for (std::size_t i = 0; i + 8 <= d.size(); i += 8) {
                    sizes.push_back(get16(&d[i + 2]));
                    types.push_back(d[i + 7]);
                    got += hex(get16(&d[i])) + "/" + dec(get16(&d[i + 2])) + "/" + hex(d[i + 4], 2) + "/" +
                           ((d[i + 6] & 1) ? "1" : "0") + " ";
                }
            }
            for (std::size_t n = 0; n < ctx.esi->sms.size(); ++n) {
                EsiSm s = ctx.esi->sms[n];
                // A process-data Sm without DefaultSize leaves the size to the configuration (ETG.2000 Sm):
                // the SII may carry 0 or the size of the PDOs the ESI assigns to it by default.
                if (s.default_size == 0 && (sm_kind(s) == "Outputs" || sm_kind(s) == "Inputs") &&
                    n < sizes.size()) {
                    unsigned bits = 0;
                    for (const auto* list : {&ctx.esi->rxpdos, &ctx.esi->txpdos})
                        for (const EsiPdo& p : *list)
                            if (p.sm == static_cast<int>(n)) bits += p.bits();
                    if (sizes[n] == (bits + 7) / 8) s.default_size = sizes[n];
                }
                want += esi_sm(s) + " ";
            }
            if (Outcome o = expect_eq("SMs start/size/control/enable", got, want); o.status != Status::Pass)
                return o;
            // The SM type byte (ETG.2010 SyncM: 1 mailbox out, 2 mailbox in, 3 outputs, 4 inputs) as the
            // ESI's Sm text says; an Sm of another text is not compared. A process-data Sm whose ControlByte
            // names the other direction (ESC datasheet 0x0804 bits 2-3: 00 the master reads, 01 it writes;
            // buffered mode) is the buffer the ESC makes of it: its type is the control byte's.
            std::string tgot, twant;
            for (std::size_t n = 0; n < ctx.esi->sms.size() && n < types.size(); ++n) {
                const EsiSm& sm = ctx.esi->sms[n];
                const std::string t = sm_kind(sm);
                int want_type = t == "MBoxOut"   ? 1
                                : t == "MBoxIn"  ? 2
                                : t == "Outputs" ? 3
                                : t == "Inputs"  ? 4
                                                 : -1;
                if ((want_type == 3 || want_type == 4) && sm.has_control && (sm.control & 0x03) != 0x02)
                    want_type = ((sm.control >> 2) & 0x03) == 0x01 ? 3 : 4;
                if (want_type < 0) continue;
                tgot += "SM" + dec(static_cast<long long>(n)) + " " + dec(types[n]) + " ";
                twant += "SM" + dec(static_cast<long long>(n)) + " " + dec(want_type) + " ";
            }
            return expect_eq("SM types", tgot, twant);
        },
        "ESI given");
    add(
        "esi.fmmu", "FMMU category equals the ESI's Fmmu elements", kSiiEsi,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            CONFORM_NEED(ctx.need_sii());
            std::string got, want;
            std::vector<uint8_t> usages;
            if (const SiiCategory* f = ctx.sii->find(kFmmu))
                for (uint8_t b : ctx.sii->data(*f))
                    if (b != 0 && b != 0xFF) {
                        got += dec(b) + " ";
                        usages.push_back(b);
                    }
            if (ctx.esi->fmmus.empty()) {
                // The ESI declares no Fmmu (ETG.2000: optional; a master's export writes none): the SII's
                // FMMU usage is the device's, and must fit its SMs: an FMMU for outputs, inputs or the
                // mailbox state only where an Sm of that kind is (ETG.2010 FMMU category: 1 outputs,
                // 2 inputs, 3 SyncM status).
                bool out = false, in = false, mbox = false;
                for (const EsiSm& s : ctx.esi->sms) {
                    const std::string k = sm_kind(s);
                    out = out || k == "Outputs";
                    in = in || k == "Inputs";
                    mbox = mbox || k == "MBoxIn";
                }
                for (uint8_t b : usages)
                    if ((b == 1 && !out) || (b == 2 && !in) || (b == 3 && !mbox) || b > 3)
                        return fail(
                            "FMMU usage " + dec(b) + " without an Sm of that kind (the ESI declares no Fmmu)",
                            got, "usages its Sms allow");
                return pass("the ESI declares no Fmmu; the SII's usages fit its Sms", got);
            }
            for (const auto& f : ctx.esi->fmmus)
                want += (f == "Outputs" ? "1 " : f == "Inputs" ? "2 " : f == "MBoxState" ? "3 " : "? ");
            return expect_eq("FMMU usage", got, want);
        },
        "ESI given");
    add(
        "esi.txpdo", "TXPDO category: PDOs as the ESI's TxPdo, every default-assigned or mandatory one",
        kSiiEsi, [](Context& ctx) { return pdo_vs_esi(ctx, kTxPdo); }, "ESI given");
    add(
        "esi.rxpdo", "RXPDO category: PDOs as the ESI's RxPdo, every default-assigned or mandatory one",
        kSiiEsi, [](Context& ctx) { return pdo_vs_esi(ctx, kRxPdo); }, "ESI given");
    add(
        "esi.dc",
        "DC category op modes equal the ESI's Dc/OpMode (AssignActivate; SYNC0 cycle time, shift and factor)",
        kSiiEsi,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            CONFORM_NEED(ctx.need_sii());
            if (!ctx.esi->has_dc) return skip("the ESI has no Dc element");
            std::string got, want;
            std::span<const uint8_t> d;
            if (const SiiCategory* dc = ctx.sii->find(kDc)) d = ctx.sii->data(*dc);
            for (std::size_t i = 0; i + 24 <= d.size(); i += 24)
                got += hex(get16(&d[i + 14])) + " ";
            for (const auto& m : ctx.esi->op_modes)
                want += hex(m.assign_activate) + " ";
            if (Outcome o = expect_eq("AssignActivate per op mode", got, want); o.status != Status::Pass)
                return o;
            // ETG.2010 DC category, per op mode (24 bytes): SYNC0 cycle time (0-3), SYNC0 shift (4-7), SYNC1
            // shift (8-11), SYNC1 cycle factor (12-13), AssignActivate (14-15), SYNC0 cycle factor (16-17).
            // The SYNC0 timing of a mode that activates SYNC0 as the ESI's OpMode gives it: the cycle time,
            // the shift, and the factor where the ESI writes one (a factor of 0 names no cycle).
            got.clear();
            want.clear();
            for (std::size_t n = 0; n < ctx.esi->op_modes.size() && 24 * n + 24 <= d.size(); ++n) {
                const auto& m = ctx.esi->op_modes[n];
                if (!(m.assign_activate & 0x0200)) continue;
                const uint8_t* e = &d[24 * n];
                got += m.name + ": " + dec(get32(e)) + "/" + dec(static_cast<int32_t>(get32(e + 4)));
                want += m.name + ": " + dec(m.cycle_time_sync0) + "/" + dec(m.shift_time_sync0);
                if (m.cycle_time_sync0_factor) {
                    got += " factor " + dec(static_cast<int16_t>(get16(e + 16)));
                    want += " factor " + dec(*m.cycle_time_sync0_factor);
                }
                got += "; ";
                want += "; ";
            }
            return expect_eq("SYNC0 cycle time/shift (factor) per op mode", got, want);
        },
        "ESI has Dc");
    add(
        "esi.coe_details", "General CoE details (byte 5) match the ESI's CoE attributes", kSiiEsi,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            CONFORM_NEED(ctx.need_sii());
            if (!ctx.esi->coe.present) return skip("the ESI has no CoE");
            const SiiCategory* g = ctx.sii->find(kGeneral);
            if (!g || g->length < 6) return fail("no General category");
            const uint8_t b = ctx.sii->bytes[g->offset + 5];
            const auto& e = ctx.esi->coe;
            uint8_t want = static_cast<uint8_t>(0x01 | (e.sdo_info ? 0x02 : 0) | (e.pdo_assign ? 0x04 : 0) |
                                                (e.pdo_config ? 0x08 : 0) | (e.pdo_upload ? 0x10 : 0) |
                                                (e.complete_access ? 0x20 : 0));
            return expect_eq("CoE details", hex(b & 0x3F, 2), hex(want, 2));
        },
        "ESI has CoE");
    add(
        "esi.physics",
        "General physical ports and the ESC's port descriptor 0x0007 as the ESI's Device Physics",
        "ETG.2000 Device Physics; ETG.2010 SII General category (bytes 16-17); ESC datasheet 0x0007",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            CONFORM_NEED(ctx.need_sii());
            if (!ctx.esi->physics || ctx.esi->physics->empty()) return skip("the ESI declares no Physics");
            const std::string& ph = *ctx.esi->physics;
            const SiiCategory* g = ctx.sii->find(kGeneral);
            if (!g || g->length < 18) return fail("no General category of 18 bytes or more");
            const uint16_t ports = get16(&ctx.sii->bytes[g->offset + 16]);
            auto desc = ctx.rd<uint8_t>(0x0007);
            if (!desc) return fail("0x0007 unreadable");
            // One character per port from port 0 (ETG.2000): Y 100BASE-TX (MII), K E-Bus (LVDS), H MII with
            // fast hot connect, a blank or none: no port. ETG.2010 ports nibble: 1 MII, 3 EBUS, 4 fast hot
            // connect, 0 not used; 0x0007 two bits: 11 MII, 10 EBUS, 00 not implemented.
            std::string bad;
            for (int p = 0; p < 4 && bad.empty(); ++p) {
                const char kind =
                    static_cast<std::size_t>(p) < ph.size() ? ph[static_cast<std::size_t>(p)] : ' ';
                const unsigned nib = (ports >> (4 * p)) & 0x0Fu, esc = (*desc >> (2 * p)) & 0x03u;
                const bool nib_ok = kind == 'Y'   ? nib == 1
                                    : kind == 'K' ? nib == 3
                                    : kind == 'H' ? nib == 4 || nib == 1
                                                  : nib == 0;
                const bool esc_ok = kind == 'Y' || kind == 'H' ? esc == 3 : kind == 'K' ? esc == 2 : esc == 0;
                const std::string port = "port " + dec(p) + " ('" + std::string(1, kind) + "')";
                if (!nib_ok)
                    bad = port + ": SII physical port " + dec(nib);
                else if (!esc_ok)
                    bad = port + ": 0x0007 says " +
                          (esc == 0   ? "not implemented"
                           : esc == 1 ? "not configured"
                           : esc == 2 ? "EBUS"
                                      : "MII");
            }
            if (!bad.empty())
                return fail(bad, "ports " + hex(ports) + ", 0x0007 " + hex(*desc, 2),
                            "Physics \"" + ph + "\"");
            return pass("Physics \"" + ph + "\": ports " + hex(ports) + ", 0x0007 " + hex(*desc, 2));
        },
        "ESI given");
    add("general.ports_flags",
        "General category: physical ports as the ESC's port descriptor 0x0007 (port 0 in use), flag 'not "
        "LRW' only where 0x0008 says LRW is not supported",
        "ETG.2010 SII General category (bytes 11, 16-17); ESC datasheet 0x0007, 0x0008 bit 9",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            const SiiCategory* g = ctx.sii->find(kGeneral);
            if (!g || g->length < 18) return skip("no General category of 18 bytes or more");
            const uint8_t* b = &ctx.sii->bytes[g->offset];
            const uint16_t ports = get16(b + 16);
            auto desc = ctx.rd<uint8_t>(0x0007);
            auto features = ctx.rd<uint16_t>(0x0008);
            if (!desc || !features) return fail("0x0007/0x0008 unreadable");
            // ETG.2010 physical port (4 bits a port): 0 not used, 1 MII, 3 EBUS, 4 fast hot connect; 0x0007
            // two bits a port, 00 not implemented. A port 0 (where the frames come in) not used, or a port
            // the SII uses that the ESC does not implement, is a description the line does not have.
            std::string bad;
            if (ports && !(ports & 0x000F)) bad = "port 0 'not used', yet the frames come in there";
            for (int p = 0; p < 4 && bad.empty(); ++p)
                if (((ports >> (4 * p)) & 0x0F) && !((*desc >> (2 * p)) & 3))
                    bad = "port " + dec(p) + " in use, yet 0x0007 says not implemented";
            if (bad.empty() && (b[11] & 0x02) && !(*features & 0x0200))
                bad = "flag 'not LRW' (byte 11 bit 1), yet 0x0008 bit 9 clear (LRW supported)";
            if (!bad.empty())
                return fail(bad,
                            "ports " + hex(ports) + ", flags " + hex(b[11], 2) + " (0x0007 " + hex(*desc, 2) +
                                ", 0x0008 " + hex(*features) + ")",
                            "as the ESC");
            return pass("ports " + hex(ports) + ", flags " + hex(b[11], 2));
        });
    add(
        "esi.foe_details", "General FoE details (byte 6) match the ESI's FoE element", kSiiEsi,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            CONFORM_NEED(ctx.need_sii());
            const SiiCategory* g = ctx.sii->find(kGeneral);
            if (!g || g->length < 7) return skip("no General category");
            return expect_eq("FoE enabled", dec(ctx.sii->bytes[g->offset + 6] & 1), ctx.esi->foe ? "1" : "0");
        },
        "ESI given");
    add(
        "esi.general", "General flags, identification register and E-Bus current match the ESI", kSiiEsi,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            CONFORM_NEED(ctx.need_sii());
            const SiiCategory* g = ctx.sii->find(kGeneral);
            if (!g || g->length < 20) return skip("no General category of 20 bytes or more");
            const uint8_t* b = &ctx.sii->bytes[g->offset];
            const auto& e = *ctx.esi;
            // ETG.2010 General byte 11: bit 2 mailbox data link layer (ESI Mailbox DataLinkLayer), bit 3
            // identification in AL status code (Info/IdentificationReg134), bit 4 identification in the ESC
            // register of bytes 18-19 (Info/IdentificationAdo). A master configured from the ESI and one
            // that reads the SII must find the same device: each field the ESI declares, both ways.
            const uint8_t want_flags = static_cast<uint8_t>(
                (e.has_mailbox && e.mailbox_data_link_layer ? 0x04 : 0) |
                (e.identification_reg134 ? 0x08 : 0) | (e.identification_ado ? 0x10 : 0));
            std::string got = "flags " + hex(b[11] & 0x1C, 2);
            std::string want = "flags " + hex(want_flags, 2);
            if (e.identification_ado) {
                got += ", identification register " + hex(get16(b + 18));
                want += ", identification register " + hex(*e.identification_ado);
            }
            // The E-Bus current: an ESI without Electrical/EBusCurrent describes a device that draws none.
            got += ", E-Bus current " + std::to_string(static_cast<int16_t>(get16(b + 12))) + " mA";
            want += ", E-Bus current " + std::to_string(e.ebus_current_ma.value_or(0)) + " mA";
            return expect_eq("General (bits 2 DataLinkLayer, 3 IdentificationReg134, 4 IdentificationAdo)",
                             got, want);
        },
        "ESI given");
    add("general.protocol_details",
        "General CoE, FoE, EoE details and SoE channels (bytes 5-8) only for protocols of word 0x1C",
        "ETG.2010 SII General category bytes 5 (CoE details), 6 (FoE details), 7 (EoE details), 8 (SoE "
        "channels) and word 0x1C (mailbox protocols)",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            const SiiCategory* g = ctx.sii->find(kGeneral);
            if (!g || g->length < 9) return skip("no General category of 9 bytes or more");
            const uint8_t* b = &ctx.sii->bytes[g->offset];
            const uint16_t proto = ctx.sii->word(0x1C);
            // Each details byte describes a protocol's features; bit 0 of CoE/FoE/EoE details enables the
            // protocol, the SoE byte counts its channels. A protocol the mailbox protocols word does not
            // announce has nothing to describe: a master that reads one or the other must find the same.
            struct P {
                const char* name;
                uint8_t value;
                uint16_t bit;
            };
            std::string got, want;
            for (const P& p : {P{"CoE", static_cast<uint8_t>(b[5] & 1), 0x04},
                               P{"FoE", static_cast<uint8_t>(b[6] & 1), 0x08},
                               P{"EoE", static_cast<uint8_t>(b[7] & 1), 0x02}, P{"SoE", b[8], 0x10}}) {
                if (p.value && !(proto & p.bit)) {
                    got += std::string(p.name) + " details " + hex(p.value, 2) + " ";
                    want += std::string(p.name) + " not in word 0x1C " + hex(proto) + " ";
                }
            }
            if (!got.empty()) return fail("details of a protocol the SII does not announce", got, want);
            return pass("details", "bytes 5-8 " + hex(b[5], 2) + " " + hex(b[6], 2) + " " + hex(b[7], 2) +
                                       " " + hex(b[8], 2) + ", word 0x1C " + hex(proto));
        });
    add(
        "esi.order_name_present",
        "General category order number and name strings present where the ESI gives a Type and a Name",
        "ETG.2010 SII General category bytes 2 (order number string) and 3 (name string); ETG.2000 "
        "Device/Type, Device/Name",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            CONFORM_NEED(ctx.need_sii());
            const SiiCategory* g = ctx.sii->find(kGeneral);
            if (!g || g->length < 4) return skip("no General category");
            auto d = ctx.sii->data(*g);
            // The texts may differ (esi.names warns: language, abbreviation); a missing string is a lost
            // field.
            if (!ctx.esi->type_name.empty() && (d[2] == 0 || ctx.sii->string(d[2]).empty()))
                return fail("no order number string (General byte 2 = " + dec(d[2]) + ")", "none",
                            "\"" + ctx.esi->type_name + "\"");
            if (!ctx.esi->name.empty() && (d[3] == 0 || ctx.sii->string(d[3]).empty()))
                return fail("no name string (General byte 3 = " + dec(d[3]) + ")", "none",
                            "\"" + ctx.esi->name + "\"");
            return pass("present", ctx.sii->string(d[2]) + " / " + ctx.sii->string(d[3]));
        },
        "ESI given");
    add(
        "esi.names", "General category order number and name equal the ESI's Type and Name", kSiiEsi,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            CONFORM_NEED(ctx.need_sii());
            const SiiCategory* g = ctx.sii->find(kGeneral);
            if (!g || g->length < 4) return skip("no General category");
            auto d = ctx.sii->data(*g);
            return expect_eq("order/name", ctx.sii->string(d[2]) + " / " + ctx.sii->string(d[3]),
                             ctx.esi->type_name + " / " + ctx.esi->name);
        },
        "ESI given", Severity::Warning);
    add(
        "esi.group", "General category group equals the ESI's GroupType", kSiiEsi,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            CONFORM_NEED(ctx.need_sii());
            const SiiCategory* g = ctx.sii->find(kGeneral);
            if (!g || g->length < 1) return skip("no General category");
            if (ctx.esi->group_type.empty()) return skip("the ESI has no GroupType");
            return expect_eq("group", ctx.sii->string(ctx.sii->data(*g)[0]), ctx.esi->group_type);
        },
        "ESI given", Severity::Warning);
}

}  // namespace conform
