#include "coe/pdo_validation.hpp"

#include <algorithm>
#include <array>
#include <memory>
#include <vector>

#include "wire.hpp"

namespace coe {

namespace {

// The direction of a process-data object as the object model declares it (od::Object::direction), wherever
// its index lies; None for anything else.
od::PdoDirection mapping_direction(const od::Dictionary& d, uint16_t pdo) {
    const od::Object* o = d.find(pdo);
    return o != nullptr && o->is_pdo_mapping() ? o->direction : od::PdoDirection::None;
}
od::PdoDirection assignment_direction(const od::Dictionary& d, uint16_t assign) {
    const od::Object* o = d.find(assign);
    return o != nullptr && o->is_pdo_assignment() ? o->direction : od::PdoDirection::None;
}

uint8_t u8(const od::Dictionary& d, uint16_t i, uint8_t s) {
    auto r = d.raw(i, s);
    return r.empty() ? 0 : r[0];
}
uint16_t u16(const od::Dictionary& d, uint16_t i, uint8_t s) {
    auto r = d.raw(i, s);
    return r.size() < 2 ? 0 : wire::get16(r, 0);
}
uint32_t u32(const od::Dictionary& d, uint16_t i, uint8_t s) {
    auto r = d.raw(i, s);
    return r.size() < 4 ? 0 : wire::get32(r, 0);
}

std::size_t bits_of(const od::Dictionary& d, uint16_t pdo, uint8_t count) {
    std::size_t bits = 0;
    for (uint8_t s = 1; s <= count && s != 0; ++s)
        bits += u32(d, pdo, s) & 0xFF;
    return bits;
}

// Bytes an assignment maps when PDO `changed` maps `changed_bits` (or as it stands when changed == 0).
std::size_t assigned_bytes(const od::Dictionary& d, uint16_t assign, uint8_t count, uint16_t changed,
                           std::size_t changed_bits) {
    std::size_t bits = 0;
    for (uint8_t s = 1; s <= count && s != 0; ++s) {
        uint16_t pdo = u16(d, assign, s);
        bits += pdo == changed && changed != 0 ? changed_bits : mapped_bits(d, pdo);
    }
    return (bits + 7) / 8;
}

od::Status check_mapping(const od::Dictionary& d, uint16_t pdo, const od::Entry& e,
                         std::span<const uint8_t> v, const PdoLimits& lim) {
    const bool rx = mapping_direction(d, pdo) == od::PdoDirection::Rx;
    if (e.subindex != 0) {
        // ETG.1000.6 / ETG.1020: a mapping entry can be changed only while subindex 0 is 0.
        if (u8(d, pdo, 0) != 0) return od::Status::SubindexZeroFirst;
        if (v.size() != 4) return od::Status::LengthMismatch;
        return check_mapping_entry(d, rx, wire::get32(v, 0));
    }
    if (v.size() != 1) return od::Status::LengthMismatch;
    const uint8_t n = v[0];
    const od::Object* obj = d.find(pdo);
    if (obj == nullptr) return od::Status::NoObject;
    for (uint8_t s = 1; s <= n && s != 0; ++s) {
        if (obj->entry(s) == nullptr) return od::Status::ValueTooHigh;
        if (check_mapping_entry(d, rx, u32(d, pdo, s)) != od::Status::Ok) return od::Status::NotMappable;
    }
    const std::size_t bits = bits_of(d, pdo, n);
    if ((bits + 7) / 8 > lim.max_sm_bytes) return od::Status::PdoLengthExceeded;
    // Where the PDO is assigned to a SyncManager (any of its direction), that SyncManager's image must still
    // fit.
    for (const od::Object& a : d.objects()) {
        if (!a.is_pdo_assignment() || a.direction != mapping_direction(d, pdo)) continue;
        const uint8_t count = u8(d, a.index, 0);
        bool assigned = false;
        for (uint8_t s = 1; s <= count && s != 0; ++s)
            assigned = assigned || u16(d, a.index, s) == pdo;
        if (assigned && assigned_bytes(d, a.index, count, pdo, bits) > lim.max_sm_bytes)
            return od::Status::PdoLengthExceeded;
    }
    return od::Status::Ok;
}

// A PDO an assignment may hold: a mapping object of the assignment's direction.
bool valid_pdo_for(const od::Dictionary& d, uint16_t assign, uint16_t pdo) {
    const od::PdoDirection dir = mapping_direction(d, pdo);
    return dir != od::PdoDirection::None && dir == assignment_direction(d, assign);
}

// The PDOs an assignment holds with `count` entries.
od::Status rules_after(const od::Dictionary& d, uint16_t assign, uint8_t count,
                       std::span<const od::PdoRule> rules) {
    if (rules.empty()) return od::Status::Ok;
    std::array<uint16_t, 255> pdos{};
    std::size_t n = 0;
    for (uint8_t s = 1; s <= count && s != 0; ++s)
        pdos[n++] = u16(d, assign, s);
    return check_pdo_rules(d, assign, std::span<const uint16_t>(pdos.data(), n), rules);
}

od::Status check_assignment(const od::Dictionary& d, uint16_t assign, const od::Entry& e,
                            std::span<const uint8_t> v, const PdoLimits& lim,
                            std::span<const od::PdoRule> rules) {
    if (e.subindex != 0) {
        // ETG.1000.6 / ETG.1020: the assignment, like a mapping, is changed only while subindex 0 is 0.
        if (u8(d, assign, 0) != 0) return od::Status::SubindexZeroFirst;
        if (v.size() != 2) return od::Status::LengthMismatch;
        uint16_t pdo = wire::get16(v, 0);
        if (pdo != 0 && !valid_pdo_for(d, assign, pdo)) return od::Status::InvalidValue;
        return od::Status::Ok;
    }
    if (v.size() != 1) return od::Status::LengthMismatch;
    const uint8_t n = v[0];
    const od::Object* obj = d.find(assign);
    if (obj == nullptr) return od::Status::NoObject;
    for (uint8_t s = 1; s <= n && s != 0; ++s) {
        if (obj->entry(s) == nullptr) return od::Status::ValueTooHigh;
        uint16_t pdo = u16(d, assign, s);
        if (!valid_pdo_for(d, assign, pdo)) return od::Status::InvalidValue;
        for (uint8_t t = 1; t < s; ++t)
            if (u16(d, assign, t) == pdo) return od::Status::InvalidValue;  // assigned twice
    }
    if (assigned_bytes(d, assign, n, 0, 0) > lim.max_sm_bytes) return od::Status::PdoLengthExceeded;
    // Count 0 opens the assignment for a change (the first write of every reassignment a configuration tool
    // makes, TwinCAT's and EC-Engineer's CoE init commands alike): Mandatory and Exclude are checked on the
    // count that puts an assignment in force.
    if (n == 0) return od::Status::Ok;
    return rules_after(d, assign, n, rules);
}

}  // namespace

bool rule_applies(const od::Dictionary& dict, uint16_t assign, uint16_t pdo) {
    const od::PdoDirection dir = assignment_direction(dict, assign);
    if (dir == od::PdoDirection::None || mapping_direction(dict, pdo) != dir) return false;
    // With several SyncManagers of one direction (EL1252's three input SMs), a PDO belongs to the one whose
    // assignment holds it by default; with one, to that one.
    bool others = false;
    for (const od::Object& a : dict.objects())
        others = others || (a.is_pdo_assignment() && a.direction == dir && a.index != assign);
    if (!others) return true;
    const od::Object* o = dict.find(assign);
    const auto defaults = dict.default_raw(assign, 0);
    const uint8_t count = defaults.empty() ? 0 : defaults[0];
    for (uint8_t s = 1; s <= count && s != 0; ++s) {
        const auto v = dict.default_raw(assign, s);
        if (o->entry(s) != nullptr && v.size() >= 2 && wire::get16(v, 0) == pdo) return true;
    }
    return false;
}

od::Status check_pdo_rules(const od::Dictionary& dict, uint16_t assign, std::span<const uint16_t> assigned,
                           std::span<const od::PdoRule> rules) {
    auto holds = [&](uint16_t pdo) {
        return std::find(assigned.begin(), assigned.end(), pdo) != assigned.end();
    };
    for (const od::PdoRule& r : rules) {
        if (!rule_applies(dict, assign, r.pdo)) continue;
        if (r.mandatory && !holds(r.pdo)) return od::Status::Incompatible;
        if (!holds(r.pdo)) continue;
        for (uint16_t x : r.exclude)
            if (x != r.pdo && holds(x)) return od::Status::Incompatible;
    }
    return od::Status::Ok;
}

od::Status check_mapping_entry(const od::Dictionary& dict, bool rx, uint32_t value) {
    if (value == 0) return od::Status::Ok;
    const uint16_t index = static_cast<uint16_t>(value >> 16);
    const uint8_t sub = static_cast<uint8_t>(value >> 8);
    const uint8_t bits = static_cast<uint8_t>(value);
    if (bits == 0) return od::Status::NotMappable;
    // A gap of `bits` bits: index 0, or a dummy data-type object (BOOLEAN..UNSIGNED32), as ecat/ reads it.
    if (index <= 0x0007) return sub == 0 ? od::Status::Ok : od::Status::NotMappable;
    const od::Entry* e = dict.find(index, sub);
    if (e == nullptr) return od::Status::NotMappable;
    if (rx ? !e->rx_mappable() : !e->tx_mappable()) return od::Status::NotMappable;
    if (!e->mappable_with(bits)) return od::Status::NotMappable;
    return od::Status::Ok;
}

std::size_t mapped_bits(const od::Dictionary& dict, uint16_t pdo) {
    if (dict.find(pdo) == nullptr) return 0;
    return bits_of(dict, pdo, u8(dict, pdo, 0));
}

void install_pdo_validators(od::Dictionary& dict, PdoLimits limits) {
    install_pdo_validators(dict, limits, {});
}

void install_pdo_validators(od::Dictionary& dict, PdoLimits limits, std::span<const od::PdoRule> rules) {
    od::Dictionary* d = &dict;
    auto kept = std::make_shared<const std::vector<od::PdoRule>>(rules.begin(), rules.end());
    for (const auto& obj : dict.objects()) {
        const uint16_t index = obj.index;
        if (obj.is_pdo_mapping()) {
            dict.add_validator(index, [d, index, limits](const od::Entry& e, std::span<const uint8_t> v) {
                return check_mapping(*d, index, e, v, limits);
            });
        } else if (obj.is_pdo_assignment()) {
            dict.add_validator(index,
                               [d, index, limits, kept](const od::Entry& e, std::span<const uint8_t> v) {
                                   return check_assignment(*d, index, e, v, limits, *kept);
                               });
        }
    }
}

}  // namespace coe
