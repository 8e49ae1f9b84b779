#pragma once
// Products made by hand through the od API, as the ESI reader makes them (tests/device): a digital IO
// terminal without mailbox and an analog terminal with CoE but no drive.
#include <memory>
#include <string>
#include <vector>

#include "od/dictionary.hpp"
#include "od/product.hpp"

namespace test_products {

inline od::Entry entry(uint8_t sub, std::string name, od::DataType type, uint16_t access,
                       uint64_t value = 0) {
    od::Entry e;
    e.subindex = sub;
    e.name = std::move(name);
    e.type = type;
    e.access = access;
    e.default_value = value;
    return e;
}

inline od::Object var(uint16_t index, std::string name, od::DataType type, uint64_t value) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Var;
    o.name = name;
    o.type = type;
    o.entries.push_back(entry(0, std::move(name), type, od::access::RO, value));
    return o;
}

inline od::Object record(uint16_t index, std::string name, std::vector<od::Entry> entries) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Record;
    o.name = std::move(name);
    o.type = od::DataType::Identity;
    o.entries = std::move(entries);
    return o;
}

inline od::Object array(uint16_t index, std::string name, od::DataType type,
                        const std::vector<uint64_t>& values) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Array;
    o.name = std::move(name);
    o.type = type;
    for (std::size_t i = 0; i < values.size(); ++i)
        o.entries.push_back(entry(static_cast<uint8_t>(i + 1), "SubIndex " + std::to_string(i + 1), type,
                                  od::access::RO, values[i]));
    return o;
}

inline void add_identity(od::Dictionary& d, const od::DeviceDescription& desc) {
    d.add(var(0x1000, "Device type", od::DataType::Unsigned32, 0x00001389));
    const od::Identity& id = desc.identity;
    d.add(record(0x1018, "Identity",
                 {entry(1, "Vendor ID", od::DataType::Unsigned32, od::access::RO, id.vendor_id),
                  entry(2, "Product code", od::DataType::Unsigned32, od::access::RO, id.product_code),
                  entry(3, "Revision", od::DataType::Unsigned32, od::access::RO, id.revision),
                  entry(4, "Serial number", od::DataType::Unsigned32, od::access::RO, id.serial_number)}));
}

constexpr uint16_t kRo = od::access::RO;
constexpr uint16_t kTx = od::access::RO | od::access::TxPdo;
constexpr uint16_t kRx = od::access::RO | od::access::WritePreOp | od::access::WriteSafeOp |
                         od::access::WriteOp | od::access::RxPdo;

// The PDOs of both products: RxPDO 0x1600 (0x7000:01 "Value" U16, 0x7000:02 "Output" BOOL, 7 bits
// padding: 3 bytes), TxPDO 0x1A00 (0x6000:01 "Value" U16 mirrors the output of that name, 0x6000:02
// "Cycle Counter" U8 counts, 0x6000:03 "Status" U16 keeps 0x1234: 5 bytes).
inline void add_io(od::Dictionary& d, uint16_t out_assign, uint16_t in_assign) {
    d.add(record(0x1600, "Outputs",
                 {entry(1, "SubIndex 001", od::DataType::Unsigned32, kRo, 0x70000110),
                  entry(2, "SubIndex 002", od::DataType::Unsigned32, kRo, 0x70000201),
                  entry(3, "SubIndex 003", od::DataType::Unsigned32, kRo, 0x00000007)}));
    d.add(record(0x1A00, "Inputs",
                 {entry(1, "SubIndex 001", od::DataType::Unsigned32, kRo, 0x60000110),
                  entry(2, "SubIndex 002", od::DataType::Unsigned32, kRo, 0x60000208),
                  entry(3, "SubIndex 003", od::DataType::Unsigned32, kRo, 0x60000310)}));
    d.add(array(out_assign, "RxPDO assign", od::DataType::Unsigned16, {0x1600}));
    d.add(array(in_assign, "TxPDO assign", od::DataType::Unsigned16, {0x1A00}));
    d.add(record(0x6000, "Inputs",
                 {entry(1, "Value", od::DataType::Unsigned16, kTx, 0),
                  entry(2, "Cycle Counter", od::DataType::Unsigned8, kTx, 250),
                  entry(3, "Status", od::DataType::Unsigned16, kTx, 0x1234)}));
    d.add(record(0x7000, "Outputs",
                 {entry(1, "Value", od::DataType::Unsigned16, kRx, 0),
                  entry(2, "Output", od::DataType::Boolean, kRx, 0)}));
}

inline od::SyncManagerDefault sm(od::SmKind kind, uint16_t start, uint16_t size, uint8_t control) {
    od::SyncManagerDefault s;
    s.kind = kind;
    s.start = start;
    s.default_size = size;
    s.control = control;
    return s;
}

inline od::Identity identity(uint32_t product) {
    od::Identity id;
    id.vendor_id = 0xE0000123;
    id.product_code = product;
    id.revision = 0x00010000;
    id.vendor_name = "Example";
    id.device_name = "IO terminal";
    id.order_code = "EX1234";
    id.group_type = "DigIO";
    return id;
}

// The parts every hand-built product shares: its source, identity and SMs, no Bootstrap mailbox, and either
// no mailbox at all or CoE with SDO information on the standard mailbox (the default one).
inline std::shared_ptr<od::Product> base_product(std::string source, uint32_t product_code,
                                                 std::vector<od::SyncManagerDefault> sms, bool coe) {
    auto p = std::make_shared<od::Product>();
    p->source = std::move(source);
    od::DeviceDescription& d = p->description;
    d.identity = identity(product_code);
    d.bootstrap_mailbox = {0, 0, 0, 0};
    if (coe) {
        d.mailbox_protocols = od::mailbox_protocol::CoE;
        d.coe_details = od::coe_details::Sdo | od::coe_details::SdoInfo;
    } else {
        d.standard_mailbox = {0, 0, 0, 0};
        d.mailbox_protocols = 0;
        d.coe_details = 0;
    }
    d.sync_managers = std::move(sms);
    return p;
}

// A digital IO terminal without mailbox: outputs in SM0 (0x0F00, 0x44), inputs in SM1 (0x1000, 0x00).
inline std::shared_ptr<const od::Product> io_terminal() {
    auto p = base_product("hand-built IO terminal", 0x00001234,
                          {sm(od::SmKind::Outputs, 0x0F00, 3, 0x44), sm(od::SmKind::Inputs, 0x1000, 5, 0x00)},
                          false);
    od::DeviceDescription& d = p->description;
    d.pdi_control = 0x04;  // digital IO
    d.esc_config = 0;
    p->make_dictionary = [](const od::DeviceDescription& desc) {
        od::Dictionary dict;
        add_identity(dict, desc);
        add_io(dict, 0x1C10, 0x1C11);
        return dict;
    };
    p->application = od::Application::None;
    p->warnings = {"Element 'Info/VendorSpecific' is not emulated"};
    return p;
}

// An analog terminal with CoE (SDO, SDO info) and no drive: standard mailbox, process data in SM2/SM3.
// `fixed_sync_modes`: 0x1C32:01 and 0x1C33:01 read-only, as a device with one synchronisation type declares
// them (ETG.1020: "RW if more than one synchronization type is supported"; Beckhoff's EL1502 0x1C33).
inline std::shared_ptr<const od::Product> coe_terminal(bool fixed_sync_modes = false) {
    auto p =
        base_product("hand-built CoE terminal", 0x00005678,
                     {sm(od::SmKind::MBoxOut, 0x1000, 128, 0x26), sm(od::SmKind::MBoxIn, 0x1080, 128, 0x22),
                      sm(od::SmKind::Outputs, 0x1100, 3, 0x64), sm(od::SmKind::Inputs, 0x1180, 5, 0x20)},
                     true);
    p->make_dictionary = [fixed_sync_modes](const od::DeviceDescription& desc) {
        od::Dictionary dict;
        add_identity(dict, desc);
        dict.add(array(0x1C00, "Sync manager type", od::DataType::Unsigned8, {1, 2, 3, 4}));
        // SM output/input parameters (ETG.1000.6): sync mode writable in Pre-Op, free run / SM-synchronous.
        constexpr uint16_t kRwPreOp = od::access::RO | od::access::WritePreOp;
        const uint16_t sync_mode_access = fixed_sync_modes ? kRo : kRwPreOp;
        for (const uint16_t index : {uint16_t{0x1C32}, uint16_t{0x1C33}})
            dict.add(record(index, index == 0x1C32 ? "SM output parameter" : "SM input parameter",
                            {entry(1, "Sync mode", od::DataType::Unsigned16, sync_mode_access, 1),
                             entry(2, "Cycle time", od::DataType::Unsigned32, kRwPreOp, 0),
                             entry(4, "Sync modes supported", od::DataType::Unsigned16, kRo, 0x0003)}));
        add_io(dict, 0x1C12, 0x1C13);
        return dict;
    };
    return p;
}

// A terminal with two outputs SMs and two inputs SMs, each with its own PDO (as Beckhoff's EL2262 or drives
// with a second channel): with CoE (standard mailbox) outputs in SM2/SM4, inputs in SM3/SM5; without mailbox
// outputs in SM0/SM2, inputs in SM1/SM3. The first pair carries the PDOs of add_io (3 and 5 bytes), the
// second RxPDO 0x1601 (0x7010:01 "Channel 2" U16: 2 bytes) and TxPDO 0x1A01 (0x6010:01 "Channel 2" U16
// mirrors it, 0x6010:02 "Status 2" U8 keeps 0x5A: 3 bytes). Four FMMUs for the process data, one for the
// mailbox state (ESI Fmmu elements). `second_assigned` false: the second pair has no assignment objects
// (nothing assigned to it, as a device whose further SMs are unused need not have them).
inline std::shared_ptr<const od::Product> two_sm_terminal(bool coe, bool second_assigned = true) {
    std::vector<od::SyncManagerDefault> sms;
    if (coe) {
        sms = {sm(od::SmKind::MBoxOut, 0x1000, 128, 0x26), sm(od::SmKind::MBoxIn, 0x1080, 128, 0x22),
               sm(od::SmKind::Outputs, 0x1100, 3, 0x64),   sm(od::SmKind::Inputs, 0x1180, 5, 0x20),
               sm(od::SmKind::Outputs, 0x1200, 2, 0x64),   sm(od::SmKind::Inputs, 0x1280, 3, 0x20)};
    } else {
        sms = {sm(od::SmKind::Outputs, 0x0F00, 3, 0x64), sm(od::SmKind::Inputs, 0x1000, 5, 0x20),
               sm(od::SmKind::Outputs, 0x1100, 2, 0x64), sm(od::SmKind::Inputs, 0x1200, 3, 0x20)};
    }
    auto p = base_product(coe ? "hand-built two-SM CoE terminal" : "hand-built two-SM IO terminal",
                          coe ? 0x00002262 : 0x00001262, std::move(sms), coe);
    od::DeviceDescription& d = p->description;
    d.fmmus = coe ? std::vector<uint8_t>{1, 1, 2, 2, 3} : std::vector<uint8_t>{1, 1, 2, 2};
    if (!coe) {
        d.pdi_control = 0x04;  // digital IO
        d.esc_config = 0;
        p->application = od::Application::None;
    }
    const uint16_t first = coe ? 0x1C12 : 0x1C10;  // the assignment object of the first outputs SM
    p->make_dictionary = [first, second_assigned](const od::DeviceDescription& desc) {
        od::Dictionary dict;
        add_identity(dict, desc);
        add_io(dict, first, static_cast<uint16_t>(first + 1));
        dict.add(record(0x1601, "Outputs 2",
                        {entry(1, "SubIndex 001", od::DataType::Unsigned32, kRo, 0x70100110)}));
        dict.add(record(0x1A01, "Inputs 2",
                        {entry(1, "SubIndex 001", od::DataType::Unsigned32, kRo, 0x60100110),
                         entry(2, "SubIndex 002", od::DataType::Unsigned32, kRo, 0x60100208)}));
        if (second_assigned) {
            dict.add(
                array(static_cast<uint16_t>(first + 2), "RxPDO assign", od::DataType::Unsigned16, {0x1601}));
            dict.add(
                array(static_cast<uint16_t>(first + 3), "TxPDO assign", od::DataType::Unsigned16, {0x1A01}));
        }
        dict.add(record(0x6010, "Inputs 2",
                        {entry(1, "Channel 2", od::DataType::Unsigned16, kTx, 0),
                         entry(2, "Status 2", od::DataType::Unsigned8, kTx, 0x5A)}));
        dict.add(record(0x7010, "Outputs 2", {entry(1, "Channel 2", od::DataType::Unsigned16, kRx, 0)}));
        return dict;
    };
    return p;
}

// A digital output terminal without mailbox with one byte of outputs in each of SM0..SM3, on the digital
// output registers 0x0F00..0x0F03 (as Beckhoff's FB1111 "Dig. Out" and iTegva's E7.820.004 declare them,
// with one FMMU for all four): RxPDO 0x1600 + k maps 0x7000:0(k+1) "Output k" U8.
inline std::shared_ptr<const od::Product> byte_outputs_terminal() {
    std::vector<od::SyncManagerDefault> sms;
    for (uint16_t k = 0; k < 4; ++k)
        sms.push_back(sm(od::SmKind::Outputs, static_cast<uint16_t>(0x0F00 + k), 1, 0x44));
    auto p = base_product("hand-built byte outputs terminal", 0x00001111, std::move(sms), false);
    od::DeviceDescription& d = p->description;
    d.fmmus = {1};
    d.pdi_control = 0x04;  // digital IO
    d.esc_config = 0;
    p->application = od::Application::None;
    p->make_dictionary = [](const od::DeviceDescription& desc) {
        od::Dictionary dict;
        add_identity(dict, desc);
        std::vector<od::Entry> outputs;
        for (uint8_t k = 0; k < 4; ++k) {
            const auto pdo = static_cast<uint16_t>(0x1600 + k);
            const uint64_t mapping = 0x70000008 | (uint64_t{k + 1u} << 8);
            dict.add(record(pdo, "Output " + std::to_string(k),
                            {entry(1, "SubIndex 001", od::DataType::Unsigned32, kRo, mapping)}));
            dict.add(
                array(static_cast<uint16_t>(0x1C10 + k), "RxPDO assign", od::DataType::Unsigned16, {pdo}));
            outputs.push_back(entry(static_cast<uint8_t>(k + 1), "Output " + std::to_string(k),
                                    od::DataType::Unsigned8, kRx, 0));
        }
        dict.add(record(0x7000, "Outputs", std::move(outputs)));
        return dict;
    };
    return p;
}

// A device with a mailbox and no process data (an EoE switch port, a gateway configured by CoE only): the
// two mailbox SMs, CoE, identity objects and nothing mapped.
inline std::shared_ptr<const od::Product> mailbox_only_terminal() {
    auto p = base_product(
        "hand-built mailbox-only terminal", 0x00009ABC,
        {sm(od::SmKind::MBoxOut, 0x1800, 128, 0x26), sm(od::SmKind::MBoxIn, 0x1C00, 128, 0x22)}, true);
    p->make_dictionary = [](const od::DeviceDescription& desc) {
        od::Dictionary dict;
        add_identity(dict, desc);
        return dict;
    };
    return p;
}

// A terminal whose one object is mapped both ways (KickCAT's example slaves: 0x6000 "wdg_counter" in the
// RxPDO and the TxPDO, PdoMapping "rt"): the master writes a watchdog counter and reads it back. Outputs in
// SM0, inputs in SM1, no mailbox.
inline std::shared_ptr<const od::Product> echo_terminal() {
    auto p = base_product("hand-built echo terminal", 0x00004321,
                          {sm(od::SmKind::Outputs, 0x1000, 2, 0x64), sm(od::SmKind::Inputs, 0x1100, 4, 0x20)},
                          false);
    p->make_dictionary = [](const od::DeviceDescription& desc) {
        od::Dictionary dict;
        add_identity(dict, desc);
        dict.add(
            record(0x1600, "Outputs", {entry(1, "SubIndex 001", od::DataType::Unsigned32, kRo, 0x60000010)}));
        dict.add(record(0x1A00, "Inputs",
                        {entry(1, "SubIndex 001", od::DataType::Unsigned32, kRo, 0x60000010),
                         entry(2, "SubIndex 002", od::DataType::Unsigned32, kRo, 0x60010010)}));
        dict.add(array(0x1C10, "RxPDO assign", od::DataType::Unsigned16, {0x1600}));
        dict.add(array(0x1C11, "TxPDO assign", od::DataType::Unsigned16, {0x1A00}));
        od::Object wdg = var(0x6000, "wdg_counter", od::DataType::Unsigned16, 0);
        wdg.entries[0].access = kRx | od::access::TxPdo;
        dict.add(wdg);
        od::Object cycles = var(0x6001, "cycle counter", od::DataType::Unsigned16, 0);
        cycles.entries[0].access = kTx;
        dict.add(cycles);
        return dict;
    };
    p->application = od::Application::None;
    return p;
}

}  // namespace test_products
