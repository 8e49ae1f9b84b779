#include "esi/model.hpp"

#include <bit>
#include <cmath>
#include <cstdio>

namespace esi {
namespace {

std::string hex4(uint32_t v) {
    char b[16];
    std::snprintf(b, sizeof b, "0x%04X", static_cast<unsigned>(v));
    return b;
}

std::string where(uint16_t index, uint8_t sub) {
    char b[24];
    std::snprintf(b, sizeof b, "0x%04X:%02X", static_cast<unsigned>(index), static_cast<unsigned>(sub));
    return b;
}

// Declared default of an entry as an unsigned integer (0 if none).
uint64_t default_of(const od::Entry* e) {
    if (e == nullptr) return 0;
    return number_bits(e->default_value, e->type, e->bit_length).value_or(0);
}

void read_mapping(const od::Dictionary& dict, const od::Object& obj, PdoInfo& pdo,
                  std::vector<std::string>& warnings) {
    const od::Entry* count_entry = obj.entry(0);
    const uint64_t count = default_of(count_entry);
    if (count_entry != nullptr) pdo.fixed = (count_entry->access & od::access::WriteMask) == 0;
    for (uint64_t i = 1; i <= count && i <= 0xFF; ++i) {
        const auto sub = static_cast<uint8_t>(i);
        const od::Entry* slot = obj.entry(sub);
        if (slot == nullptr) {
            warnings.push_back(where(obj.index, 0) + " counts " + std::to_string(count) +
                               " entries but subindex " + std::to_string(i) + " does not exist");
            break;
        }
        const auto word = static_cast<uint32_t>(default_of(slot));
        PdoEntryInfo pe;
        pe.index = static_cast<uint16_t>(word >> 16);
        pe.subindex = static_cast<uint8_t>(word >> 8);
        pe.bit_length = static_cast<uint8_t>(word);
        if (pe.index != 0) {
            const od::Object* target_obj = dict.find(pe.index);
            const od::Entry* target = dict.find(pe.index, pe.subindex);
            if (target == nullptr || target_obj == nullptr) {
                warnings.push_back(where(obj.index, sub) + " maps " + where(pe.index, pe.subindex) +
                                   " which does not exist");
            } else {
                pe.entry = target;
                pe.type = target->type;
                pe.name = (target_obj->code == od::ObjectCode::Var || target->name.empty()) ? target_obj->name
                                                                                            : target->name;
                const bool mappable = pdo.rx ? target->rx_mappable() : target->tx_mappable();
                if (!mappable)
                    warnings.push_back(where(obj.index, sub) + " maps " + where(pe.index, pe.subindex) +
                                       " which is not " + (pdo.rx ? "RxPDO" : "TxPDO") + " mappable");
                if (!target->mappable_with(pe.bit_length))
                    warnings.push_back(where(obj.index, sub) + " maps " + where(pe.index, pe.subindex) +
                                       " with " + std::to_string(pe.bit_length) + " bits, the entry has " +
                                       std::to_string(target->bit_length));
            }
        }
        pdo.entries.push_back(std::move(pe));
    }
}

}  // namespace

uint32_t PdoInfo::bit_size() const {
    uint32_t bits = 0;
    for (const auto& e : entries)
        bits += e.bit_length;
    return bits;
}

std::optional<uint64_t> number_bits(const od::Number& n, od::DataType type, uint16_t bit_length) {
    if (std::holds_alternative<std::monostate>(n)) return std::nullopt;
    const unsigned width = (bit_length == 0 || bit_length > 64) ? 64u : bit_length;
    const uint64_t mask = width == 64 ? ~uint64_t{0} : ((uint64_t{1} << width) - 1);
    if (od::is_real(type)) {
        double d = 0;
        if (const auto* pd = std::get_if<double>(&n)) d = *pd;
        if (const auto* pi = std::get_if<int64_t>(&n)) d = static_cast<double>(*pi);
        if (const auto* pu = std::get_if<uint64_t>(&n)) d = static_cast<double>(*pu);
        if (width == 32) return std::bit_cast<uint32_t>(static_cast<float>(d));
        return std::bit_cast<uint64_t>(d);
    }
    uint64_t v = 0;
    if (const auto* pd = std::get_if<double>(&n))
        v = static_cast<uint64_t>(static_cast<int64_t>(std::llround(*pd)));
    if (const auto* pi = std::get_if<int64_t>(&n)) v = static_cast<uint64_t>(*pi);
    if (const auto* pu = std::get_if<uint64_t>(&n)) v = *pu;
    return v & mask;
}

DeviceModel derive_model(const od::DeviceDescription& d, const od::Dictionary& dict) {
    DeviceModel m;

    // ---- PDOs: every mapping object with its default mapping, in the direction the object model declares
    // (od::Object::direction), wherever its index lies ----
    for (const od::Object& obj : dict.objects()) {
        if (!obj.is_pdo_mapping()) continue;
        PdoInfo pdo;
        pdo.index = obj.index;
        pdo.rx = obj.rx();
        pdo.name = obj.name;
        read_mapping(dict, obj, pdo, m.warnings);
        m.pdos.push_back(std::move(pdo));
    }
    for (const od::PdoRule& rule : d.pdo_rules) {
        PdoInfo* found = nullptr;
        for (auto& p : m.pdos)
            if (p.index == rule.pdo) found = &p;
        if (found == nullptr) {
            m.warnings.push_back("PDO rule for " + hex4(rule.pdo) + ", which is not a mapping object");
            continue;
        }
        found->mandatory = found->mandatory || rule.mandatory;
        if (rule.fixed) found->fixed = *rule.fixed;
        for (uint16_t x : rule.exclude) {
            bool known = false;
            for (const auto& p : m.pdos)
                known = known || (p.index == x && p.rx == found->rx);
            if (!known)
                m.warnings.push_back(hex4(rule.pdo) + " excludes " + hex4(x) +
                                     ", not a PDO of its direction");
            else
                found->exclude.push_back(x);
        }
    }

    // ---- SyncManagers and their default PDO assignment (0x1C10 + n) ----
    for (std::size_t n = 0; n < d.sync_managers.size(); ++n) {
        const od::SyncManagerDefault& sm = d.sync_managers[n];
        SmInfo si{sm.kind, sm.start, sm.default_size, sm.control, sm.enable, sm.min_size, sm.max_size};
        const std::string name = "SM" + std::to_string(n);
        switch (sm.kind) {
            case od::SmKind::MBoxOut:
            case od::SmKind::MBoxIn: {
                const bool out = sm.kind == od::SmKind::MBoxOut;
                const uint16_t start = out ? d.standard_mailbox.out_start : d.standard_mailbox.in_start;
                const uint16_t size = out ? d.standard_mailbox.out_size : d.standard_mailbox.in_size;
                if ((sm.start != 0 && sm.start != start) || (sm.default_size != 0 && sm.default_size != size))
                    m.warnings.push_back(name + " declares " + hex4(sm.start) + "/" +
                                         std::to_string(sm.default_size) + ", the standard mailbox is " +
                                         hex4(start) + "/" + std::to_string(size));
                si.start = start;
                si.size = size;
                break;
            }
            case od::SmKind::Outputs:
            case od::SmKind::Inputs: {
                const bool rx = sm.kind == od::SmKind::Outputs;
                const auto assign_index = static_cast<uint16_t>(0x1C10 + n);
                uint32_t bits = 0;
                if (const od::Object* assign = dict.find(assign_index)) {
                    const uint64_t count = default_of(assign->entry(0));
                    for (uint64_t k = 1; k <= count && k <= 0xFF; ++k) {
                        const od::Entry* e = assign->entry(static_cast<uint8_t>(k));
                        const auto pdo_index = static_cast<uint16_t>(default_of(e));
                        PdoInfo* found = nullptr;
                        for (auto& p : m.pdos)
                            if (p.index == pdo_index) found = &p;
                        if (found == nullptr || found->rx != rx) {
                            m.warnings.push_back(where(assign_index, static_cast<uint8_t>(k)) + " assigns " +
                                                 hex4(pdo_index) + " which is not an " +
                                                 (rx ? "RxPDO" : "TxPDO") + " of this dictionary");
                            continue;
                        }
                        if (found->sm >= 0)
                            m.warnings.push_back(hex4(pdo_index) + " assigned to SM" +
                                                 std::to_string(found->sm) + " and " + name);
                        found->sm = static_cast<int>(n);
                        bits += found->bit_size();
                    }
                }
                const auto bytes = static_cast<uint16_t>((bits + 7) / 8);
                if (sm.default_size != 0 && sm.default_size != bytes)
                    m.warnings.push_back(name + " declares default size " + std::to_string(sm.default_size) +
                                         ", its default mapping has " + std::to_string(bytes) + " bytes");
                si.size = bytes;
                break;
            }
        }
        m.sync_managers.push_back(si);
    }

    // ---- The order of the PDOs: by index, the default-assigned ones permuted among their own places into
    // their assignment order. A vendor lists its PDOs by index and assigns them in that order, so the ESI
    // it wrote, the ESI written here and the SII all list them alike; where the assignment order differs
    // from the index order, both files still give a master the process-image order of 0x1C1n.
    for (const bool rx : {true, false}) {
        std::vector<std::size_t> assigned;  // in assignment order
        std::vector<bool> taken(m.pdos.size(), false);
        for (std::size_t n = 0; n < m.sync_managers.size(); ++n) {
            if (m.sync_managers[n].kind != (rx ? od::SmKind::Outputs : od::SmKind::Inputs)) continue;
            const od::Object* assign = dict.find(static_cast<uint16_t>(0x1C10 + n));
            if (assign == nullptr) continue;
            const uint64_t count = default_of(assign->entry(0));
            for (uint64_t k = 1; k <= count && k <= 0xFF; ++k) {
                const auto pdo_index =
                    static_cast<uint16_t>(default_of(assign->entry(static_cast<uint8_t>(k))));
                for (std::size_t i = 0; i < m.pdos.size(); ++i)
                    if (!taken[i] && m.pdos[i].rx == rx && m.pdos[i].index == pdo_index &&
                        m.pdos[i].sm == static_cast<int>(n)) {
                        taken[i] = true;
                        assigned.push_back(i);
                    }
            }
        }
        std::size_t next = 0;
        for (std::size_t i = 0; i < m.pdos.size(); ++i)  // m.pdos is in index order
            if (m.pdos[i].rx == rx) m.pdo_order.push_back(taken[i] ? assigned[next++] : i);
    }

    // ---- Predefined PDO sets (AlternativeSmMapping): PDOs of their direction, within the PDO rules ----
    int rx_sm = -1, tx_sm = -1;
    for (std::size_t n = 0; n < m.sync_managers.size(); ++n) {
        if (m.sync_managers[n].kind == od::SmKind::Outputs && rx_sm < 0) rx_sm = static_cast<int>(n);
        if (m.sync_managers[n].kind == od::SmKind::Inputs && tx_sm < 0) tx_sm = static_cast<int>(n);
    }
    std::vector<uint16_t> default_rx, default_tx;
    for (const auto& p : m.pdos)
        if (p.sm >= 0) (p.rx ? default_rx : default_tx).push_back(p.index);
    for (const od::PdoSet& set : d.pdo_sets) {
        PdoSetInfo info{set.name, false, rx_sm, tx_sm, {}, {}};
        bool ok = true;
        for (const bool rx : {true, false})
            for (uint16_t index : rx ? set.rx : set.tx) {
                const PdoInfo* found = nullptr;
                for (const auto& p : m.pdos)
                    if (p.index == index && p.rx == rx) found = &p;
                if (found == nullptr) {
                    m.warnings.push_back("PDO set '" + set.name + "' names " + hex4(index) + ", not an " +
                                         (rx ? "RxPDO" : "TxPDO") + " of this dictionary");
                    ok = false;
                    continue;
                }
                for (uint16_t x : found->exclude)
                    for (uint16_t other : rx ? set.rx : set.tx)
                        if (other == x) {
                            m.warnings.push_back("PDO set '" + set.name + "' holds " + hex4(index) + " and " +
                                                 hex4(x) + ", which exclude each other");
                            ok = false;
                        }
                (rx ? info.rx : info.tx).push_back(index);
            }
        if (!ok) continue;
        info.is_default = info.rx == default_rx && info.tx == default_tx;
        m.pdo_sets.push_back(std::move(info));
    }

    // ---- FMMUs: one per process-data direction, one for the mailbox status ----
    auto has = [&](od::SmKind k) {
        for (const auto& s : m.sync_managers)
            if (s.kind == k) return true;
        return false;
    };
    if (!d.fmmus.empty()) {
        for (uint8_t f : d.fmmus)
            m.fmmus.push_back(f <= 0x03 ? static_cast<FmmuUse>(f) : FmmuUse::Unused);
    } else {
        if (has(od::SmKind::Outputs)) m.fmmus.push_back(FmmuUse::Outputs);
        if (has(od::SmKind::Inputs)) m.fmmus.push_back(FmmuUse::Inputs);
        if (has(od::SmKind::MBoxIn)) m.fmmus.push_back(FmmuUse::MBoxState);
    }

    // ---- Profile: the one the description names (ESI ProfileNo), else the device type 0x1000's ----
    if (d.profile_number != 0) {
        m.profile_number = d.profile_number;
        m.profile_add_info = d.profile_add_info;
    } else if (const od::Entry* dt = dict.find(0x1000, 0)) {
        const auto v = static_cast<uint32_t>(default_of(dt));
        m.profile_number = static_cast<uint16_t>(v);
        m.profile_add_info = static_cast<uint16_t>(v >> 16);
    }

    // ---- EEPROM configuration words 0-6 and bootstrap mailbox words 0x14-0x17 ----
    auto put16 = [](uint8_t* p, uint16_t v) {
        p[0] = static_cast<uint8_t>(v);
        p[1] = static_cast<uint8_t>(v >> 8);
    };
    m.config_data[0] = d.pdi_control;
    m.config_data[1] = d.esc_config;
    put16(&m.config_data[2], d.pdi_config);
    put16(&m.config_data[4], d.sync_pulse_length);
    put16(&m.config_data[6], d.extended_pdi_config);
    put16(&m.config_data[8], d.station_alias);
    put16(&m.config_data[10], d.config_words_5_6[0]);
    put16(&m.config_data[12], d.config_words_5_6[1]);
    put16(&m.bootstrap[0], d.bootstrap_mailbox.out_start);
    put16(&m.bootstrap[2], d.bootstrap_mailbox.out_size);
    put16(&m.bootstrap[4], d.bootstrap_mailbox.in_start);
    put16(&m.bootstrap[6], d.bootstrap_mailbox.in_size);
    return m;
}

}  // namespace esi

namespace esi {

std::vector<uint8_t> device_image_bmp() {
    constexpr int kW = 16, kH = 14;
    constexpr uint32_t kPixels = kW * kH * 3;  // 48 bytes a row: no padding needed
    constexpr uint32_t kHeader = 14 + 40;
    // The drawing, top row first: a servo drive (grey housing, cooling fins, status LEDs green/red) with its
    // motor (blue, round) on the right. '.' white, 'k' dark grey, 'g' grey, 'G' green, 'R' red, 'b' blue,
    // 'B' dark blue, 'y' yellow shaft.
    static const char* const kArt[kH] = {
        "................",  //
        ".kkkkkkk........",  //
        ".kgggggk........",  //
        ".kgGgRgk...bbb..",  //
        ".kgggggk..bBBBb.",  //
        ".kkkkkkk.bBbbbBb",  //
        ".kgggggkbbBbyybB",  //
        ".kkkkkkk.bBbyybB",  //
        ".kgggggk.bBbbbBb",  //
        ".kkkkkkk..bBBBb.",  //
        ".kgggggk...bbb..",  //
        ".kkkkkkk........",  //
        ".kk...kk........",  //
        "................",  //
    };
    auto color = [](char c) -> std::array<uint8_t, 3> {  // B, G, R
        switch (c) {
            case 'k':
                return {0x40, 0x40, 0x40};
            case 'g':
                return {0xA0, 0xA0, 0xA0};
            case 'G':
                return {0x00, 0xC0, 0x00};
            case 'R':
                return {0x00, 0x00, 0xE0};
            case 'b':
                return {0xC0, 0x60, 0x20};
            case 'B':
                return {0x80, 0x30, 0x10};
            case 'y':
                return {0x00, 0xD0, 0xF0};
            default:
                return {0xFF, 0xFF, 0xFF};
        }
    };
    std::vector<uint8_t> b;
    auto u16 = [&b](uint32_t v) {
        b.push_back(static_cast<uint8_t>(v));
        b.push_back(static_cast<uint8_t>(v >> 8));
    };
    auto u32 = [&u16](uint32_t v) {
        u16(v & 0xFFFF);
        u16(v >> 16);
    };
    b.push_back('B');
    b.push_back('M');
    u32(kHeader + kPixels);  // file size
    u32(0);                  // reserved
    u32(kHeader);            // pixel data offset
    u32(40);                 // BITMAPINFOHEADER
    u32(kW);
    u32(kH);  // positive: bottom-up
    u16(1);   // planes
    u16(24);  // bits per pixel
    u32(0);   // BI_RGB
    u32(kPixels);
    u32(3780);  // 96 dpi
    u32(3780);
    u32(0);
    u32(0);
    for (int y = kH - 1; y >= 0; --y)
        for (int x = 0; x < kW; ++x)
            for (uint8_t c : color(kArt[y][x]))
                b.push_back(c);
    return b;
}

}  // namespace esi
