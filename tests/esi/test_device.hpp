#pragma once
// Devices the esi tests run against: a small hand-made dictionary that exercises every shape the generators
// handle (VAR, uniform ARRAY, ARRAY with gaps, RECORD with gaps, strings, reals, min/max, units, backup,
// state-dependent access, padding in a mapping), and the real drive (maxpos::dictionary).
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "maxpos/maxpos.hpp"
#include "od/device.hpp"
#include "od/dictionary.hpp"

namespace esi_test {

inline od::Entry entry(uint16_t index, uint8_t sub, std::string name, od::DataType type, uint16_t access,
                       od::Number def = {}, uint16_t bits = 0) {
    od::Entry e;
    e.index = index;
    e.subindex = sub;
    e.name = std::move(name);
    e.type = type;
    e.bit_length = bits ? bits : od::bit_size(type);
    e.access = access;
    e.default_value = def;
    return e;
}

inline od::Object var(uint16_t index, std::string name, od::DataType type, uint16_t access,
                      od::Number def = {}) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Var;
    o.name = name;
    o.type = type;
    o.entries.push_back(entry(index, 0, std::move(name), type, access, def));
    return o;
}

inline od::DeviceDescription small_description() {
    od::DeviceDescription d;
    d.identity.product_code = 0x30010000;
    d.identity.revision = 0x01200000;
    d.identity.serial_number = 0x12345678;
    d.identity.device_name = "Small & <test> drive";
    d.identity.order_code = "SMALL-1";
    d.mailbox_protocols = od::mailbox_protocol::CoE | od::mailbox_protocol::FoE;
    d.sync_managers = {
        {od::SmKind::MBoxOut, 0x1000, 128, 0x26, true},
        {od::SmKind::MBoxIn, 0x1080, 128, 0x22, true},
        {od::SmKind::Outputs, 0x1100, 6, 0x64, true},
        {od::SmKind::Inputs, 0x1180, 7, 0x20, true},
    };
    d.dc_modes = {{"SM-Synchron", "SM2 event", 0x0000, 1, 0}, {"DC", "DC SYNC0", 0x0300, 1, 50000}};
    return d;
}

inline od::Dictionary small_dictionary(const od::DeviceDescription& d) {
    using od::DataType;
    namespace a = od::access;
    od::Dictionary dict;
    dict.add(var(0x1000, "Device type", DataType::Unsigned32, a::RO, uint64_t{0x00020192}));
    {
        od::Object o = var(0x1008, "Manufacturer device name", DataType::VisibleString, a::RO);
        o.entries[0].bit_length = 8 * 16;
        o.entries[0].default_string = d.identity.device_name.substr(0, 16);
        dict.add(std::move(o));
    }
    {
        od::Object o;
        o.index = 0x1018;
        o.code = od::ObjectCode::Record;
        o.name = "Identity";
        o.type = DataType::Identity;
        o.entries = {
            entry(0x1018, 0, "Number of entries", DataType::Unsigned8, a::RO, uint64_t{4}),
            entry(0x1018, 1, "Vendor ID", DataType::Unsigned32, a::RO, uint64_t{d.identity.vendor_id}),
            entry(0x1018, 2, "Product code", DataType::Unsigned32, a::RO, uint64_t{d.identity.product_code}),
            entry(0x1018, 3, "Revision", DataType::Unsigned32, a::RO, uint64_t{d.identity.revision}),
            entry(0x1018, 4, "Serial number", DataType::Unsigned32, a::RO,
                  uint64_t{d.identity.serial_number})};
        dict.add(std::move(o));
    }
    {
        od::Object o;
        o.index = 0x10F3;
        o.code = od::ObjectCode::Record;  // mixed entry types: a RECORD (od refuses such an ARRAY)
        o.name = "Diagnosis history";
        o.type = DataType::OctetString;
        o.entries = {entry(0x10F3, 0, "Number of entries", DataType::Unsigned8, a::RO, uint64_t{6}),
                     entry(0x10F3, 1, "Maximum messages", DataType::Unsigned8, a::RO, uint64_t{2}),
                     entry(0x10F3, 6, "Diagnosis message 1", DataType::OctetString, a::RO, {}, 64)};
        o.entries[2].default_string = std::string("\x01\x02\x00\xFF", 4);
        dict.add(std::move(o));
    }
    auto mapping = [&](uint16_t index, const char* name, std::vector<uint32_t> words) {
        od::Object o;
        o.index = index;
        o.code = od::ObjectCode::Record;
        o.name = name;
        o.type = DataType::PdoMapping;
        o.entries.push_back(entry(index, 0, "Number of mapped objects", DataType::Unsigned8, a::RW_PreOp,
                                  uint64_t{words.size()}));
        for (std::size_t i = 0; i < 4; ++i)
            o.entries.push_back(entry(index, static_cast<uint8_t>(i + 1),
                                      "Mapping entry " + std::to_string(i + 1), DataType::Unsigned32,
                                      a::RW_PreOp, uint64_t{i < words.size() ? words[i] : 0}));
        dict.add(std::move(o));
    };
    mapping(0x1600, "RxPDO 1", {0x60400010, 0x607A0020});
    mapping(0x1601, "RxPDO 2", {0x60400010, 0x00000008, 0x60600008});
    mapping(0x1A00, "TxPDO 1", {0x60410010, 0x60640020, 0x60610008});
    {
        od::Object fixed = var(0x1A01, "TxPDO 2 (fixed)", DataType::Unsigned8, a::RO, uint64_t{1});
        fixed.code = od::ObjectCode::Record;
        fixed.type = DataType::PdoMapping;
        fixed.entries[0].name = "Number of mapped objects";
        fixed.entries.push_back(
            entry(0x1A01, 1, "Mapping entry 1", DataType::Unsigned32, a::RO, uint64_t{0x60410010}));
        dict.add(std::move(fixed));
    }
    {
        od::Object o;
        o.index = 0x1C00;
        o.code = od::ObjectCode::Array;
        o.name = "Sync manager type";
        o.type = DataType::Unsigned8;
        o.entries.push_back(entry(0x1C00, 0, "Number of used sync manager channels", DataType::Unsigned8,
                                  a::RO, uint64_t{4}));
        for (uint8_t i = 1; i <= 4; ++i)
            o.entries.push_back(entry(0x1C00, i, "Communication type SM" + std::to_string(i - 1),
                                      DataType::Unsigned8, a::RO, uint64_t{i}));
        dict.add(std::move(o));
    }
    auto assign = [&](uint16_t index, const char* name, std::vector<uint16_t> pdos) {
        od::Object o;
        o.index = index;
        o.code = od::ObjectCode::Array;
        o.name = name;
        o.type = DataType::Unsigned16;
        o.entries.push_back(entry(index, 0, "Number of assigned PDOs", DataType::Unsigned8,
                                  a::RW_PreOp | a::Backup, uint64_t{pdos.size()}));
        for (std::size_t i = 0; i < 2; ++i)
            o.entries.push_back(entry(index, static_cast<uint8_t>(i + 1), "PDO " + std::to_string(i + 1),
                                      DataType::Unsigned16, a::RW_PreOp | a::Backup,
                                      uint64_t{i < pdos.size() ? pdos[i] : uint16_t{0}}));
        dict.add(std::move(o));
    };
    assign(0x1C12, "RxPDO assign", {0x1600});
    assign(0x1C13, "TxPDO assign", {0x1A00});
    {
        od::Object o;
        o.index = 0x1C32;
        o.code = od::ObjectCode::Record;
        o.name = "SM output parameter";
        o.type = DataType::SyncManagerParameter;
        o.entries = {entry(0x1C32, 0, "Number of entries", DataType::Unsigned8, a::RO, uint64_t{32}),
                     entry(0x1C32, 1, "Sync mode", DataType::Unsigned16, a::RW_PreOp, uint64_t{2}),
                     entry(0x1C32, 2, "Cycle time", DataType::Unsigned32, a::RW_PreOp, uint64_t{1000000}),
                     entry(0x1C32, 4, "Sync modes supported", DataType::Unsigned16, a::RO, uint64_t{6}),
                     entry(0x1C32, 32, "Sync error", DataType::Boolean, a::RO | a::TxPdo, uint64_t{0})};
        o.entries[2].unit = "ns";
        dict.add(std::move(o));
    }
    {
        od::Object o = var(0x6040, "Controlword", DataType::Unsigned16, a::RW | a::RxPdo, uint64_t{0});
        dict.add(std::move(o));
    }
    dict.add(var(0x6041, "Statusword", DataType::Unsigned16, a::RO | a::TxPdo, uint64_t{0}));
    {
        od::Object o =
            var(0x6060, "Modes of operation", DataType::Integer8, a::RW | a::RxPdo | a::Backup, int64_t{8});
        o.entries[0].minimum = int64_t{-1};
        o.entries[0].maximum = int64_t{10};
        dict.add(std::move(o));
    }
    dict.add(var(0x6061, "Modes of operation display", DataType::Integer8, a::RO | a::TxPdo, int64_t{0}));
    {
        od::Object o =
            var(0x6064, "Position actual value", DataType::Integer32, a::RO | a::TxPdo, int64_t{0});
        o.entries[0].unit = "inc";
        dict.add(std::move(o));
    }
    {
        od::Object o = var(0x607A, "Target position", DataType::Integer32, a::RW | a::RxPdo, int64_t{-5});
        o.entries[0].minimum = int64_t{-2147483648LL};
        o.entries[0].maximum = int64_t{2147483647LL};
        dict.add(std::move(o));
    }
    {
        od::Object o =
            var(0x2000, "Gain", DataType::Real32, a::RO | a::WritePreOp | a::WriteSafeOp | a::Settings, 0.5);
        o.entries[0].minimum = 0.0;
        o.entries[0].maximum = 10.0;
        dict.add(std::move(o));
    }
    dict.add(var(0x2001, "Write-only command", DataType::Unsigned32, a::WO, uint64_t{0}));
    {
        od::Object o =
            var(0x2002, "Op-only readable", DataType::Unsigned16, a::ReadOp | a::WriteOp, uint64_t{7});
        o.entries[0].unit = "mA";
        dict.add(std::move(o));
    }
    {
        od::Object o;
        o.index = 0x2003;
        o.code = od::ObjectCode::Record;
        o.name = "Bits and a word";
        o.type = DataType::Unsigned8;
        o.entries = {entry(0x2003, 0, "Number of entries", DataType::Unsigned8, a::RO, uint64_t{3}),
                     entry(0x2003, 1, "Flag A", DataType::Boolean, a::RW, uint64_t{1}),
                     entry(0x2003, 2, "Flag B", DataType::Boolean, a::RW, uint64_t{0}),
                     entry(0x2003, 3, "Word", DataType::Unsigned16, a::RW, uint64_t{0xBEEF})};
        dict.add(std::move(o));
    }
    return dict;
}

struct Device {
    std::string name;
    od::DeviceDescription description;
    od::Dictionary dictionary;
};

inline Device small_device() {
    auto d = small_description();
    auto dict = small_dictionary(d);
    return {"small", std::move(d), std::move(dict)};
}

inline Device drive_device() {
    auto d = maxpos::description();
    auto dict = maxpos::dictionary(d);
    return {"drive", std::move(d), std::move(dict)};
}

inline std::vector<std::pair<std::string, std::function<Device()>>> all_devices() {
    return {{"small", small_device}, {"drive", drive_device}};
}

}  // namespace esi_test
