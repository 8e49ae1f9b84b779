// An ENI slave as an od::Product (see esi/eni/eni_product.hpp).
#include "esi/eni/eni_product.hpp"

#include <algorithm>
#include <map>
#include <memory>
#include <stdexcept>

#include "util/strfmt.hpp"

namespace esi::eni {

namespace {

using util::hex;

std::string entry_name(uint16_t index, uint8_t sub) {
    return hex(index, 4) + ":" + hex(sub, 2);
}

// The od type of an ENI (ETG.2000 base) data type name with its bit length; nothing when softecat has no
// storage of that size (STRING in a PDO, structured types, a bit length that is not the type's).
std::optional<od::DataType> scalar_type(const std::string& name, uint16_t bits) {
    static const std::map<std::string, od::DataType> types = {
        {"BOOL", od::DataType::Boolean},     {"BIT", od::DataType::Bit1},
        {"BIT1", od::DataType::Bit1},        {"BIT2", od::DataType::Bit2},
        {"BIT3", od::DataType::Bit3},        {"BIT4", od::DataType::Bit4},
        {"BIT5", od::DataType::Bit5},        {"BIT6", od::DataType::Bit6},
        {"BIT7", od::DataType::Bit7},        {"BIT8", od::DataType::Bit8},
        {"SINT", od::DataType::Integer8},    {"INT", od::DataType::Integer16},
        {"INT24", od::DataType::Integer24},  {"DINT", od::DataType::Integer32},
        {"LINT", od::DataType::Integer64},   {"USINT", od::DataType::Unsigned8},
        {"BYTE", od::DataType::Unsigned8},   {"UINT", od::DataType::Unsigned16},
        {"WORD", od::DataType::Unsigned16},  {"UINT24", od::DataType::Unsigned24},
        {"UDINT", od::DataType::Unsigned32}, {"DWORD", od::DataType::Unsigned32},
        {"ULINT", od::DataType::Unsigned64}, {"LWORD", od::DataType::Unsigned64},
        {"REAL", od::DataType::Real32},      {"LREAL", od::DataType::Real64}};
    auto it = types.find(name);
    if (it == types.end() || od::bit_size(it->second) != bits) return std::nullopt;
    return it->second;
}

od::DataType type_of_size(std::size_t bytes) {
    switch (bytes) {
        case 1:
            return od::DataType::Unsigned8;
        case 2:
            return od::DataType::Unsigned16;
        case 4:
            return od::DataType::Unsigned32;
        case 8:
            return od::DataType::Unsigned64;
        default:
            return od::DataType::OctetString;
    }
}

uint64_t little_endian(const std::vector<uint8_t>& d) {
    uint64_t v = 0;
    for (std::size_t i = 0; i < d.size() && i < 8; ++i)
        v |= uint64_t{d[i]} << (8 * i);
    return v;
}

// What the dictionary holds besides the communication objects, worked out once from the ENI slave; the
// product's make_dictionary builds from it for any identity.
struct Plan {
    std::map<uint16_t, std::map<uint8_t, od::Entry>> app;  // objects of the PDO entries and CoE InitCmds
    std::map<uint16_t, std::string> app_names;
    struct Mapping {
        uint16_t index = 0;
        bool rx = false;  // the ENI's RxPdo or TxPdo element, wherever the index lies
        std::string name;
        bool fixed = false;
        std::vector<uint32_t> entries;  // index << 16 | sub << 8 | bits
        uint8_t capacity = 0;
    };
    std::vector<Mapping> mappings;
    struct Assign {
        uint16_t index = 0;                                   // 0x1C10 + SM
        od::PdoDirection direction = od::PdoDirection::None;  // the SM's (Outputs: Rx, Inputs: Tx)
        std::vector<uint16_t> pdos;
        uint8_t capacity = 0;
    };
    std::vector<Assign> assigns;
    std::vector<uint8_t> sm_types;  // 0x1C00: 1 MBoxOut, 2 MBoxIn, 3 Outputs, 4 Inputs, 0 unused
    bool coe = false;
};

od::PdoDirection direction_of(od::SmKind k) {
    if (k == od::SmKind::Outputs) return od::PdoDirection::Rx;
    if (k == od::SmKind::Inputs) return od::PdoDirection::Tx;
    return od::PdoDirection::None;
}

uint8_t sm_type_code(const std::string& type) {
    if (type == "MBoxOut") return 1;
    if (type == "MBoxIn") return 2;
    if (type == "Outputs") return 3;
    if (type == "Inputs") return 4;
    return 0;
}

od::Entry u_entry(uint8_t sub, od::DataType type, uint16_t access, uint64_t def, std::string name) {
    od::Entry e;
    e.subindex = sub;
    e.type = type;
    e.access = access;
    e.default_value = def;
    e.name = std::move(name);
    return e;
}

od::Dictionary build(const Plan& plan, const od::DeviceDescription& d) {
    using od::DataType;
    namespace acc = od::access;
    od::Dictionary dict;
    auto var = [&](uint16_t index, od::Entry e, std::string name) {
        od::Object o;
        o.index = index;
        o.code = od::ObjectCode::Var;
        o.type = e.type;
        o.name = std::move(name);
        e.subindex = 0;
        o.entries.push_back(std::move(e));
        dict.add(std::move(o));
    };
    if (plan.coe) {
        var(0x1000, u_entry(0, DataType::Unsigned32, acc::RO, 0, "Device Type"), "Device Type");
        od::Entry name;
        name.type = DataType::VisibleString;
        name.access = acc::RO;
        name.default_string = d.identity.device_name;
        name.name = "Manufacturer Device Name";
        if (!name.default_string.empty()) var(0x1008, name, "Manufacturer Device Name");
    }
    {
        od::Object id;
        id.index = 0x1018;
        id.code = od::ObjectCode::Record;
        id.type = DataType::Identity;
        id.name = "Identity";
        id.entries.push_back(u_entry(0, DataType::Unsigned8, acc::RO, 4, "Number of entries"));
        id.entries.push_back(u_entry(1, DataType::Unsigned32, acc::RO, d.identity.vendor_id, "Vendor ID"));
        id.entries.push_back(
            u_entry(2, DataType::Unsigned32, acc::RO, d.identity.product_code, "Product Code"));
        id.entries.push_back(u_entry(3, DataType::Unsigned32, acc::RO, d.identity.revision, "Revision"));
        id.entries.push_back(
            u_entry(4, DataType::Unsigned32, acc::RO, d.identity.serial_number, "Serial Number"));
        dict.add(std::move(id));
    }
    for (const Plan::Mapping& m : plan.mappings) {
        od::Object o;
        o.index = m.index;
        o.code = od::ObjectCode::Record;
        o.type = DataType::PdoMapping;
        o.direction = m.rx ? od::PdoDirection::Rx : od::PdoDirection::Tx;
        o.name = m.name.empty() ? (m.rx ? "RxPDO " : "TxPDO ") + hex(m.index, 4) : m.name;
        const uint16_t a = m.fixed ? acc::RO : acc::RW_PreOp;
        od::Entry n = u_entry(0, DataType::Unsigned8, a, m.entries.size(), "Number of mapped objects");
        n.maximum = uint64_t{m.capacity};
        o.entries.push_back(std::move(n));
        for (uint8_t k = 1; k <= m.capacity; ++k)
            o.entries.push_back(u_entry(k, DataType::Unsigned32, a,
                                        k <= m.entries.size() ? m.entries[k - 1u] : 0,
                                        "Mapped object " + std::to_string(k)));
        dict.add(std::move(o));
    }
    if (!plan.sm_types.empty()) {
        od::Object o;
        o.index = 0x1C00;
        o.code = od::ObjectCode::Array;
        o.type = DataType::Unsigned8;
        o.name = "Sync manager type";
        o.entries.push_back(
            u_entry(0, DataType::Unsigned8, acc::RO, plan.sm_types.size(), "Number of entries"));
        for (std::size_t k = 0; k < plan.sm_types.size(); ++k)
            o.entries.push_back(u_entry(static_cast<uint8_t>(k + 1), DataType::Unsigned8, acc::RO,
                                        plan.sm_types[k], "SM" + std::to_string(k)));
        dict.add(std::move(o));
    }
    for (const Plan::Assign& as : plan.assigns) {
        od::Object o;
        o.index = as.index;
        o.code = od::ObjectCode::Array;
        o.type = DataType::Unsigned16;
        o.direction = as.direction;
        o.name = "SM" + std::to_string(as.index - 0x1C10) + " PDO assignment";
        od::Entry n =
            u_entry(0, DataType::Unsigned8, acc::RW_PreOp, as.pdos.size(), "Number of assigned PDOs");
        n.maximum = uint64_t{as.capacity};
        o.entries.push_back(std::move(n));
        for (uint8_t k = 1; k <= as.capacity; ++k)
            o.entries.push_back(u_entry(k, DataType::Unsigned16, acc::RW_PreOp,
                                        k <= as.pdos.size() ? as.pdos[k - 1u] : 0,
                                        "PDO " + std::to_string(k)));
        dict.add(std::move(o));
    }
    for (const auto& [index, subs] : plan.app) {
        od::Object o;
        o.index = index;
        o.name = plan.app_names.at(index);
        if (subs.size() == 1 && subs.begin()->first == 0) {
            o.code = od::ObjectCode::Var;
            o.type = subs.begin()->second.type;
            o.entries.push_back(subs.begin()->second);
        } else {
            o.code = od::ObjectCode::Record;
            o.type = DataType::Unsigned8;
            for (const auto& [sub, e] : subs)
                o.entries.push_back(e);
            if (o.entries.front().subindex != 0) {
                od::Entry n = u_entry(0, DataType::Unsigned8, od::access::RO, subs.rbegin()->first,
                                      "Number of entries");
                o.entries.insert(o.entries.begin(), std::move(n));
            }
        }
        dict.add(std::move(o));
    }
    return dict;
}

}  // namespace

od::Product product_from_eni(const Config& config, std::size_t index) {
    const Slave& s = config.slaves.at(index);
    const std::string who = config.where(s.line);  // Product::source names the slave
    auto fail = [&](int line, const std::string& what) { throw EniError(config.where(line) + ": " + what); };
    od::Product p;
    p.source = config.file + ", slave " + std::to_string(index) + " '" + s.info.name + "' (ENI data)";
    std::vector<std::string>& warn = p.warnings;

    // ---- identity -------------------------------------------------------------------------------------
    od::DeviceDescription& d = p.description;
    d.identity.vendor_id = s.info.vendor_id;
    d.identity.product_code = s.info.product_code;
    d.identity.revision = s.info.revision;
    d.identity.serial_number = s.info.serial;
    d.identity.vendor_name = "Vendor " + hex(s.info.vendor_id, 8);
    d.identity.device_name = s.info.name.empty() ? "Slave " + std::to_string(index) : s.info.name;
    const auto open = s.info.name.rfind('(');
    const auto close = s.info.name.rfind(')');
    d.identity.order_code = open != std::string::npos && close != std::string::npos && close > open + 1
                                ? s.info.name.substr(open + 1, close - open - 1)
                                : d.identity.device_name;
    d.identity.group_type = "ENI";
    // The slave's ports (Info/Physics, as the ESI's Device Physics: one character per port, ETG.2000); one
    // that is not a port type, or none at port 0, leaves the two MII ports.
    if (const std::string& ph = s.info.physics;
        !ph.empty() && ph.size() <= 4 && ph[0] != ' ' && ph.find_first_not_of("YKH ") == std::string::npos)
        d.physics = ph;
    d.identity.hardware_version.clear();
    d.identity.software_version.clear();

    // ---- mailbox ---------------------------------------------------------------------------------------
    const Mailbox& mb = s.mailbox;
    d.mailbox_protocols = 0;
    d.foe_details = 0;
    if (mb.present) {
        d.standard_mailbox = {mb.send.start, mb.send.length, mb.recv.start, mb.recv.length};
        if (mb.bootstrap_send && mb.bootstrap_recv)
            d.bootstrap_mailbox = {mb.bootstrap_send->start, mb.bootstrap_send->length,
                                   mb.bootstrap_recv->start, mb.bootstrap_recv->length};
        else
            d.bootstrap_mailbox = {0, 0, 0, 0};
        d.mailbox_protocols = mb.protocol_bits();
        if (mb.has("FoE")) d.foe_details = 1;
        for (const char* proto : {"AoE", "EoE", "SoE", "VoE"})
            if (mb.has(proto))
                warn.push_back(
                    who + ": Mailbox/Protocol " + proto +
                    ": not emulated (answered with the mailbox error for an unsupported protocol)");
        for (const auto& [proto, count] : mb.other_init_cmds)
            warn.push_back(who + ": Mailbox/" + proto + "/InitCmds (" + std::to_string(count) +
                           "): not emulated, the protocol is not served");
    } else {
        d.standard_mailbox = {0, 0, 0, 0};
        d.bootstrap_mailbox = {0, 0, 0, 0};
    }
    const bool coe = mb.present && mb.has("CoE");
    d.coe_details = coe ? static_cast<uint8_t>(od::coe_details::Sdo | od::coe_details::SdoInfo |
                                               od::coe_details::PdoAssign | od::coe_details::PdoConfig |
                                               od::coe_details::CompleteAccess)
                        : 0;

    // ---- SyncManagers ----------------------------------------------------------------------------------
    const ProcessData& pd = s.process_data;
    auto plan = std::make_shared<Plan>();
    plan->coe = coe;
    int sm_count = 0;
    for (const Sm& sm : pd.sms)
        sm_count = std::max(sm_count, sm.number + 1);
    if (mb.present) sm_count = std::max(sm_count, 2);
    auto kind_of = [](uint8_t code) { return static_cast<od::SmKind>(code); };
    for (int n = 0; n < sm_count; ++n) {
        od::SyncManagerDefault sd;
        const Sm* sm = pd.sm(n);
        if (sm) {
            sd.kind = kind_of(sm_type_code(sm->type));
            sd.start = sm->start;
            sd.control = sm->control;
            sd.enable = sm->enable;
            sd.default_size = sm->default_size;
            if (sm->min_size) sd.min_size = *sm->min_size;
            if (sm->max_size) sd.max_size = *sm->max_size;
        } else if (mb.present && n < 2) {
            sd.kind = n == 0 ? od::SmKind::MBoxOut : od::SmKind::MBoxIn;
            sd.start = n == 0 ? mb.send.start : mb.recv.start;
            sd.default_size = n == 0 ? mb.send.length : mb.recv.length;
            sd.control = od::default_sm_control(sd.kind);
        } else {
            sd.kind = od::SmKind::Outputs;  // a gap in the numbering: an SM the device has but does not use
            sd.enable = false;
        }
        if (mb.present && n < 2) sd.default_size = n == 0 ? mb.send.length : mb.recv.length;
        d.sync_managers.push_back(sd);
        plan->sm_types.push_back(sm || (mb.present && n < 2) ? static_cast<uint8_t>(sd.kind) : 0);
    }

    // ---- PDOs and their entries -----------------------------------------------------------------------
    auto add_entry = [&](const Pdo& pdo, const PdoEntry& e) -> bool {
        const std::string what = (pdo.rx ? "RxPdo " : "TxPdo ") + hex(pdo.index, 4) + " entry " +
                                 entry_name(e.index, e.subindex) + " '" + e.name + "'";
        const bool own = e.index == 0x1000 || e.index == 0x1008 || e.index == 0x1018 || e.index == 0x1C00 ||
                         (e.index & 0xFFF0) == 0x1C10 || pd.pdo(e.index) != nullptr ||
                         od::standard_pdo_direction(e.index) != od::PdoDirection::None;
        if (own) {
            warn.push_back(who + ": " + what +
                           ": an object the slave declares itself (identity, SyncManager or "
                           "PDO objects) cannot be mapped; its bits are a gap (always 0)");
            return false;
        }
        const auto type = scalar_type(e.data_type, e.bit_len);
        if (!type) {
            warn.push_back(who + ": " + what + " of type " + e.data_type + " (" + std::to_string(e.bit_len) +
                           " bits): not emulated, its bits are mapped as a gap (always 0)");
            return false;
        }
        auto& subs = plan->app[e.index];
        if (!plan->app_names.count(e.index))
            plan->app_names[e.index] = e.name.empty() ? hex(e.index, 4) : e.name;
        auto it = subs.find(e.subindex);
        if (it != subs.end()) {
            if (it->second.type != *type)
                fail(pdo.line,
                     what + " is declared " + e.data_type + " here and with another type in another PDO");
            it->second.access |= pdo.rx ? od::access::RxPdo | od::access::RW : od::access::TxPdo;
            return true;
        }
        od::Entry en;
        en.subindex = e.subindex;
        en.name = e.name;
        en.type = *type;
        en.access = pdo.rx ? static_cast<uint16_t>(od::access::RW | od::access::RxPdo)
                           : static_cast<uint16_t>(od::access::RO | od::access::TxPdo);
        en.default_value = uint64_t{0};
        if (od::is_real(*type)) en.default_value = 0.0;
        subs.emplace(e.subindex, std::move(en));
        return true;
    };
    std::map<int, std::vector<uint16_t>> sm_pdos;  // SM -> PDOs, as the ENI assigns them
    const bool sm_lists =
        std::any_of(pd.sms.begin(), pd.sms.end(), [](const Sm& sm) { return !sm.pdos.empty(); });
    for (const Sm& sm : pd.sms)
        for (uint16_t idx : sm.pdos)
            sm_pdos[sm.number].push_back(idx);
    for (const auto* list : {&pd.rxpdos, &pd.txpdos})
        for (const Pdo& pdo : *list) {
            Plan::Mapping m;
            m.index = pdo.index;
            m.rx = pdo.rx;
            m.name = pdo.name;
            m.fixed = pdo.fixed;
            for (const PdoEntry& e : pdo.entries) {
                const bool real = e.index != 0 && add_entry(pdo, e);
                m.entries.push_back(
                    real ? (uint32_t{e.index} << 16 | uint32_t{e.subindex} << 8 | (e.bit_len & 0xFF))
                         : (e.bit_len & 0xFF));
                if (e.bit_len > 255)
                    fail(pdo.line, "PDO entry of " + std::to_string(e.bit_len) + " bits (at most 255)");
            }
            m.capacity = static_cast<uint8_t>(std::min<std::size_t>(255, m.entries.size()));
            plan->mappings.push_back(std::move(m));
            // The SMs' Pdo lists are the assignment where the ENI writes them, else the PDOs' Sm attributes.
            if (pdo.sm && !sm_lists) sm_pdos[*pdo.sm].push_back(pdo.index);
        }
    for (auto& [n, pdos] : sm_pdos) {
        if (n >= static_cast<int>(d.sync_managers.size())) continue;
        od::SyncManagerDefault& sd = d.sync_managers[static_cast<std::size_t>(n)];
        unsigned bits = 0;
        for (uint16_t idx : pdos)
            if (const Pdo* q = pd.pdo(idx)) bits += q->bits();
        sd.default_size = static_cast<uint16_t>((bits + 7) / 8);
        Plan::Assign as;
        as.index = static_cast<uint16_t>(0x1C10 + n);
        as.direction = direction_of(sd.kind);
        as.pdos = pdos;
        const std::size_t same_direction =
            sd.kind == od::SmKind::Outputs ? pd.rxpdos.size() : pd.txpdos.size();
        as.capacity = static_cast<uint8_t>(std::min<std::size_t>(255, std::max(pdos.size(), same_direction)));
        plan->assigns.push_back(std::move(as));
    }
    // A process-data SM without PDOs still has its (empty) assignment, so the master can read it.
    for (std::size_t n = 2; n < d.sync_managers.size(); ++n) {
        const auto k = d.sync_managers[n].kind;
        if ((k == od::SmKind::Outputs || k == od::SmKind::Inputs) && pd.sm(static_cast<int>(n)) &&
            !sm_pdos.count(static_cast<int>(n))) {
            Plan::Assign as;
            as.index = static_cast<uint16_t>(0x1C10 + n);
            as.direction = direction_of(k);
            as.capacity =
                static_cast<uint8_t>(k == od::SmKind::Outputs ? pd.rxpdos.size() : pd.txpdos.size());
            plan->assigns.push_back(std::move(as));
        }
    }

    // ---- CoE init commands: the objects the master will read and write ---------------------------------
    if (coe) {
        for (const CoeInitCmd& c : mb.coe_init_cmds) {
            if (c.disabled) continue;
            const std::string what = "CoE InitCmd " + entry_name(c.index, c.subindex) +
                                     (c.comment.empty() ? "" : " ('" + c.comment + "')");
            // The communication objects the product declares itself: grow them to what the master writes.
            if ((c.index & 0xFFF0) == 0x1C10 || pd.pdo(c.index) != nullptr ||
                od::standard_pdo_direction(c.index) != od::PdoDirection::None) {
                if (c.complete_access) {
                    warn.push_back(who + ": " + what +
                                   " by complete access: the object is declared from the PDOs, "
                                   "its capacity as the ENI's PDO lists");
                    continue;
                }
                auto grow = [&](uint8_t& cap) { cap = std::max(cap, c.subindex); };
                bool found = false;
                for (auto& m : plan->mappings)
                    if (m.index == c.index) grow(m.capacity), found = true;
                for (auto& as : plan->assigns)
                    if (as.index == c.index) grow(as.capacity), found = true;
                if (!found) {
                    if ((c.index & 0xFFF0) == 0x1C10 &&
                        static_cast<std::size_t>(c.index - 0x1C10) < d.sync_managers.size()) {
                        Plan::Assign as;
                        as.index = c.index;
                        as.direction = direction_of(d.sync_managers[c.index - 0x1C10u].kind);
                        as.capacity = c.subindex;
                        plan->assigns.push_back(std::move(as));
                    } else {
                        warn.push_back(who + ": " + what +
                                       ": names a PDO or SyncManager the ENI does not declare; "
                                       "not emulated");
                    }
                }
                continue;
            }
            if (c.index == 0x1000 || c.index == 0x1008 || c.index == 0x1018 || c.index == 0x1C00) continue;
            if (c.complete_access) {
                // A complete access from subindex 0 with the count, its padding byte (ETG.1000.6: subindex 0
                // takes 16 bits in a complete access) and that many values of one size is an array the master
                // writes whole, as ETG.5001.1's configured module ident list 0xF030: served as that array,
                // holding what the master writes. Any other structure is not in the ENI.
                const std::size_t n = c.data.empty() ? 0 : c.data[0];
                const std::size_t k = n == 0 || c.data.size() <= 2 ? 0 : (c.data.size() - 2) / n;
                const bool array = c.ccs == 1 && c.subindex == 0 && k != 0 && (c.data.size() - 2) % n == 0 &&
                                   (k == 1 || k == 2 || k == 4 || k == 8);
                if (array && plan->app.count(c.index)) {
                    // Written whole again (another transition): the same array, or a structure it cannot be.
                    const auto& subs = plan->app.at(c.index);
                    const bool same =
                        subs.size() == n + 1 && std::all_of(subs.begin(), subs.end(), [&](const auto& x) {
                            return x.first == 0 || x.second.type == type_of_size(k);
                        });
                    if (same) continue;
                } else if (array) {
                    auto& subs = plan->app[c.index];
                    plan->app_names[c.index] = c.comment.empty() ? "Object " + hex(c.index, 4) : c.comment;
                    const uint16_t writable = static_cast<uint16_t>(od::access::RO | od::access::WritePreOp |
                                                                    od::access::WriteSafeOp);
                    od::Entry count;
                    count.subindex = 0;
                    count.name = "SubIndex 000";
                    count.type = od::DataType::Unsigned8;
                    count.access = writable;
                    count.default_value = n;
                    subs.emplace(uint8_t{0}, std::move(count));
                    for (std::size_t i = 1; i <= n; ++i) {
                        od::Entry e;
                        e.subindex = static_cast<uint8_t>(i);
                        e.name = entry_name(c.index, e.subindex);
                        e.type = type_of_size(k);
                        e.access = writable;
                        const auto at = c.data.begin() + static_cast<std::ptrdiff_t>(2 + (i - 1) * k);
                        e.default_value =
                            little_endian(std::vector<uint8_t>(at, at + static_cast<std::ptrdiff_t>(k)));
                        subs.emplace(e.subindex, std::move(e));
                    }
                    continue;
                }
                warn.push_back(who + ": " + what +
                               " by complete access: the object's structure is not in the ENI; "
                               "not emulated (the master's transfer is refused)");
                continue;
            }
            auto& subs = plan->app[c.index];
            if (!plan->app_names.count(c.index))
                plan->app_names[c.index] = c.comment.empty() ? "Object " + hex(c.index, 4) : c.comment;
            auto it = subs.find(c.subindex);
            if (it != subs.end()) {
                // An entry of a PDO: writable as well, if the lengths agree.
                const std::size_t size = (od::bit_size(it->second.type) + 7u) / 8u;
                if (c.ccs == 1 && !c.data.empty() && c.data.size() != size) {
                    warn.push_back(who + ": " + what + " writes " + std::to_string(c.data.size()) +
                                   " bytes to an entry of " + std::to_string(size) +
                                   ": not emulated (the master's transfer is refused)");
                    continue;
                }
                if (c.ccs == 1) it->second.access |= od::access::WritePreOp | od::access::WriteSafeOp;
                continue;
            }
            if (c.data.empty()) {
                warn.push_back(who + ": " + what + " without data: its size is unknown; not emulated");
                if (subs.empty()) plan->app.erase(c.index), plan->app_names.erase(c.index);
                continue;
            }
            od::Entry e;
            e.subindex = c.subindex;
            e.name = c.comment.empty() ? entry_name(c.index, c.subindex) : c.comment;
            e.type = type_of_size(c.data.size());
            e.access =
                c.ccs == 1
                    ? static_cast<uint16_t>(od::access::RO | od::access::WritePreOp | od::access::WriteSafeOp)
                    : od::access::RO;
            if (e.type == od::DataType::OctetString)
                e.default_string.assign(c.data.begin(), c.data.end());
            else
                e.default_value = little_endian(c.data);
            subs.emplace(c.subindex, std::move(e));
        }
        // A record whose sub 0 the master writes (the count) must hold the count type: keep it as written.
        for (auto& [idx, subs] : plan->app)
            if (subs.size() > 1 && subs.count(0) && subs.at(0).type != od::DataType::Unsigned8) {
                warn.push_back(who + ": object " + hex(idx, 4) +
                               ": sub-index 0 written with more than one byte; served as one byte");
                subs.at(0).type = od::DataType::Unsigned8;
                subs.at(0).default_value = uint64_t{subs.rbegin()->first};
            }
    } else if (!mb.coe_init_cmds.empty()) {
        warn.push_back(who + ": Mailbox/CoE/InitCmds without CoE among the protocols: not emulated");
    }

    // ---- distributed clocks ----------------------------------------------------------------------------
    if (auto aa = s.assign_activate(); aa && *aa != 0) {
        od::DcOpMode free;
        free.name = "SM-Synchron";
        free.description = "SM-Synchron";
        od::DcOpMode dc;
        dc.name = "DC";
        dc.description = "DC (as the ENI activates it)";
        dc.assign_activate = *aa;
        dc.shift_time_sync0 = s.dc.shift_time0.value_or(0);
        d.dc_modes = {free, dc};
    }

    // ---- what the ENI says that an ENI slave does not have --------------------------------------------
    // A CiA 402 drive (controlword 0x6040 and statusword 0x6041 mapped) needs its dictionary for the drive
    // core.
    auto mapped = [&](uint16_t idx) { return plan->app.count(idx) && plan->app.at(idx).count(0); };
    if (mapped(0x6040) && mapped(0x6041))
        warn.push_back(who +
                       ": maps 0x6040/0x6041 (CiA 402 controlword and statusword): served as process data "
                       "only; give the drive's ESI (--esi-dir) for the CiA 402 drive core");

    // A product is one value: the dictionary builder owns its plan.
    p.make_dictionary = [plan](const od::DeviceDescription& desc) { return build(*plan, desc); };
    p.application = od::Application::None;
    // Everything must be declarable now, not when the first unit starts.
    try {
        (void)p.make_dictionary(p.description);
    } catch (const std::logic_error& e) {
        fail(s.line, "slave " + std::to_string(index) + " cannot be served from the ENI: " + e.what());
    }
    return p;
}

}  // namespace esi::eni
