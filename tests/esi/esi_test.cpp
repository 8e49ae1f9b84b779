// ESI XML: schema validation (in-process and with xmllint), every object and subindex of the dictionary
// parsed back from the file, and agreement with the SII image.
#include <gtest/gtest.h>
#include <libxml/parser.h>
#include <libxml/tree.h>
#include <libxml/xmlschemas.h>
#include <unistd.h>

#include <bit>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>

#include "esi/esi.hpp"
#include "esi/esi_reader.hpp"
#include "esi/sii.hpp"
#include "test_device.hpp"

#ifndef SOFTECAT_ESI_SCHEMA
#error "SOFTECAT_ESI_SCHEMA must be defined"
#endif

namespace {

using esi_test::Device;
namespace a = od::access;

const std::string kXsd = SOFTECAT_ESI_SCHEMA;  // esi/schema/ in the repository

// ---- libxml2 helpers ----------------------------------------------------------------------------------

using Doc = std::unique_ptr<xmlDoc, decltype(&xmlFreeDoc)>;

Doc parse(const std::string& xml) {
    return Doc(xmlReadMemory(xml.data(), static_cast<int>(xml.size()), "esi.xml", nullptr, XML_PARSE_NONET),
               &xmlFreeDoc);
}

bool is(xmlNodePtr n, const char* name) {
    return n->type == XML_ELEMENT_NODE && std::strcmp(reinterpret_cast<const char*>(n->name), name) == 0;
}

std::vector<xmlNodePtr> all(xmlNodePtr parent, const char* name) {
    std::vector<xmlNodePtr> v;
    if (parent == nullptr) return v;
    for (xmlNodePtr c = parent->children; c != nullptr; c = c->next)
        if (is(c, name)) v.push_back(c);
    return v;
}

xmlNodePtr first(xmlNodePtr parent, const char* name) {
    auto v = all(parent, name);
    return v.empty() ? nullptr : v.front();
}

xmlNodePtr path(xmlNodePtr n, std::initializer_list<const char*> names) {
    for (const char* name : names) {
        if (n == nullptr) return nullptr;
        n = first(n, name);
    }
    return n;
}

std::string text(xmlNodePtr n) {
    if (n == nullptr) return {};
    xmlChar* c = xmlNodeGetContent(n);
    std::string s = c ? reinterpret_cast<const char*>(c) : "";
    xmlFree(c);
    return s;
}

std::optional<std::string> prop(xmlNodePtr n, const char* name) {
    xmlChar* c = xmlGetProp(n, reinterpret_cast<const xmlChar*>(name));
    if (c == nullptr) return std::nullopt;
    std::string s = reinterpret_cast<const char*>(c);
    xmlFree(c);
    return s;
}

// HexDecValue: "#x1a00" or "-12".
int64_t hexdec(const std::string& s) {
    if (s.rfind("#x", 0) == 0) return static_cast<int64_t>(std::stoull(s.substr(2), nullptr, 16));
    return std::stoll(s);
}

std::vector<uint8_t> hexbin(const std::string& s) {
    std::vector<uint8_t> v;
    for (std::size_t i = 0; i + 1 < s.size(); i += 2)
        v.push_back(static_cast<uint8_t>(std::stoul(s.substr(i, 2), nullptr, 16)));
    return v;
}

// ---- Expectations, independent of the generator ---------------------------------------------------------

std::string expected_type(const od::Entry& e) {
    using od::DataType;
    switch (e.type) {
        case DataType::Boolean:
            return "BOOL";
        case DataType::Integer8:
            return "SINT";
        case DataType::Integer16:
            return "INT";
        case DataType::Integer32:
            return "DINT";
        case DataType::Integer64:
            return "LINT";
        case DataType::Unsigned8:
            return e.bit_length == 8 ? "USINT" : "BIT" + std::to_string(e.bit_length);
        case DataType::Unsigned16:
            return e.bit_length == 16 ? "UINT" : "BIT" + std::to_string(e.bit_length);
        case DataType::Unsigned32:
            return e.bit_length == 32 ? "UDINT" : "BIT" + std::to_string(e.bit_length);
        case DataType::Unsigned64:
            return "ULINT";
        case DataType::Real32:
            return "REAL";
        case DataType::Real64:
            return "LREAL";
        case DataType::VisibleString:
            return "STRING(" + std::to_string(e.bit_length / 8) + ")";
        case DataType::OctetString:
            return "ARRAY [0.." + std::to_string(e.bit_length / 8 - 1) + "] OF BYTE";
        case DataType::UnicodeString:
            return "UNICODE_STRING(" + std::to_string(e.bit_length / 16) + ")";
        default:
            return "?";
    }
}

uint16_t states(const std::optional<std::string>& r, uint16_t preop, uint16_t safeop, uint16_t op) {
    if (!r) return preop | safeop | op;
    uint16_t bits = 0;
    if (r->find("PreOP") != std::string::npos || r->find("PreOp") != std::string::npos) bits |= preop;
    if (r->find("SafeOP") != std::string::npos) bits |= safeop;
    if (*r == "OP" || r->find("_OP") != std::string::npos) bits |= op;
    return bits;
}

// od access bits (read/write per state, PDO, backup, setting) back from an ESI Flags element.
uint16_t access_from(xmlNodePtr flags) {
    uint16_t bits = 0;
    xmlNodePtr acc = first(flags, "Access");
    const std::string t = text(acc);
    if (t == "ro" || t == "rw")
        bits |= states(prop(acc, "ReadRestrictions"), a::ReadPreOp, a::ReadSafeOp, a::ReadOp);
    if (t == "wo" || t == "rw")
        bits |= states(prop(acc, "WriteRestrictions"), a::WritePreOp, a::WriteSafeOp, a::WriteOp);
    const std::string pdo = text(first(flags, "PdoMapping"));
    if (pdo.find('R') != std::string::npos) bits |= a::RxPdo;
    if (pdo.find('T') != std::string::npos) bits |= a::TxPdo;
    if (text(first(flags, "Backup")) == "1") bits |= a::Backup;
    if (text(first(flags, "Setting")) == "1") bits |= a::Settings;
    return bits;
}

std::optional<uint64_t> expected_default(const od::Entry& e) {
    const unsigned w = e.bit_length >= 64 || e.bit_length == 0 ? 64 : e.bit_length;
    const uint64_t mask = w == 64 ? ~uint64_t{0} : (uint64_t{1} << w) - 1;
    if (std::holds_alternative<std::monostate>(e.default_value)) return std::nullopt;
    if (od::is_real(e.type)) {
        double d = 0;
        if (auto p = std::get_if<double>(&e.default_value)) d = *p;
        if (auto p = std::get_if<int64_t>(&e.default_value)) d = static_cast<double>(*p);
        if (auto p = std::get_if<uint64_t>(&e.default_value)) d = static_cast<double>(*p);
        return w == 32 ? uint64_t{std::bit_cast<uint32_t>(static_cast<float>(d))}
                       : std::bit_cast<uint64_t>(d);
    }
    if (auto p = std::get_if<int64_t>(&e.default_value)) return static_cast<uint64_t>(*p) & mask;
    if (auto p = std::get_if<uint64_t>(&e.default_value)) return *p & mask;
    if (auto p = std::get_if<double>(&e.default_value))
        return static_cast<uint64_t>(static_cast<int64_t>(*p)) & mask;
    return std::nullopt;
}

// The default an ESI Info element declares, as raw bits.
std::optional<uint64_t> declared_default(xmlNodePtr info, const od::Entry& e) {
    const unsigned w = e.bit_length >= 64 || e.bit_length == 0 ? 64 : e.bit_length;
    const uint64_t mask = w == 64 ? ~uint64_t{0} : (uint64_t{1} << w) - 1;
    if (xmlNodePtr dd = first(info, "DefaultData")) {
        uint64_t v = 0;
        const auto b = hexbin(text(dd));
        for (std::size_t i = 0; i < b.size() && i < 8; ++i)
            v |= uint64_t{b[i]} << (8 * i);
        return v;
    }
    if (xmlNodePtr dv = first(info, "DefaultValue")) return static_cast<uint64_t>(hexdec(text(dv))) & mask;
    return std::nullopt;
}

void check_value(xmlNodePtr info, const od::Entry& e, const std::string& where) {
    SCOPED_TRACE(where);
    if (od::is_string(e.type)) {
        if (e.default_string.empty()) return;
        ASSERT_NE(info, nullptr);
        if (e.type == od::DataType::VisibleString) {
            EXPECT_EQ(text(first(info, "DefaultString")), e.default_string);
        } else {
            const auto b = hexbin(text(first(info, "DefaultData")));
            EXPECT_EQ(std::string(b.begin(), b.end()), e.default_string);
        }
        return;
    }
    const auto want = expected_default(e);
    if (!want) return;
    ASSERT_NE(info, nullptr);
    EXPECT_EQ(declared_default(info, e), want);
    if (!od::is_real(e.type)) {
        auto limit = [&](const od::Number& n, const char* name) {
            if (std::holds_alternative<std::monostate>(n)) return;
            xmlNodePtr v = first(info, name);
            ASSERT_NE(v, nullptr) << name;
            const int64_t got = hexdec(text(v));
            if (auto p = std::get_if<int64_t>(&n)) {
                if (od::is_signed(e.type)) {
                    EXPECT_EQ(got, *p) << name;
                }
            }
            if (auto p = std::get_if<uint64_t>(&n)) {
                EXPECT_EQ(static_cast<uint64_t>(got), *p) << name;
            }
        };
        limit(e.minimum, "MinValue");
        limit(e.maximum, "MaxValue");
    }
}

// ---- Fixture --------------------------------------------------------------------------------------------

class EsiDevice : public ::testing::TestWithParam<std::string> {
  protected:
    Device dev() const {
        for (auto& [name, make] : esi_test::all_devices())
            if (name == GetParam()) return make();
        throw std::logic_error("no device " + GetParam());
    }
    std::filesystem::path temp(const std::string& suffix) const {
        return std::filesystem::temp_directory_path() /
               ("esi_test_" + GetParam() + "_" + std::to_string(::getpid()) + suffix);
    }
};

std::vector<std::string> g_schema_errors;
void collect_error(void*, const xmlError* e) {
    g_schema_errors.push_back("line " + std::to_string(e->line) + ": " + (e->message ? e->message : "?"));
}

// Validates doc against the ETG.2000 schema in process; each error the schema reports is a failure.
void expect_schema_valid(xmlDoc* doc) {
    std::unique_ptr<xmlSchemaParserCtxt, decltype(&xmlSchemaFreeParserCtxt)> pc(
        xmlSchemaNewParserCtxt(kXsd.c_str()), &xmlSchemaFreeParserCtxt);
    ASSERT_NE(pc, nullptr);
    std::unique_ptr<xmlSchema, decltype(&xmlSchemaFree)> schema(xmlSchemaParse(pc.get()), &xmlSchemaFree);
    ASSERT_NE(schema, nullptr) << "cannot load " << kXsd;
    std::unique_ptr<xmlSchemaValidCtxt, decltype(&xmlSchemaFreeValidCtxt)> vc(
        xmlSchemaNewValidCtxt(schema.get()), &xmlSchemaFreeValidCtxt);
    g_schema_errors.clear();
    xmlSchemaSetValidStructuredErrors(vc.get(), reinterpret_cast<xmlStructuredErrorFunc>(&collect_error),
                                      nullptr);
    EXPECT_EQ(xmlSchemaValidateDoc(vc.get(), doc), 0);
    for (const auto& e : g_schema_errors)
        ADD_FAILURE() << e;
}

TEST_P(EsiDevice, ValidatesAgainstTheSchemaInProcess) {
    const Device d = dev();
    const std::string xml = esi::build_esi(d.description, d.dictionary);
    Doc doc = parse(xml);
    ASSERT_NE(doc, nullptr);
    expect_schema_valid(doc.get());
}

TEST_P(EsiDevice, ValidatesWithXmllint) {
    const Device d = dev();
    const auto file = temp(".xml");
    esi::write_esi(file, d.description, d.dictionary);
    const auto log = temp(".log");
    const std::string cmd =
        "xmllint --noout --schema '" + kXsd + "' '" + file.string() + "' > '" + log.string() + "' 2>&1";
    const int rc = std::system(cmd.c_str());
    std::ifstream in(log);
    std::stringstream out;
    out << in.rdbuf();
    EXPECT_EQ(rc, 0) << out.str();
    EXPECT_NE(out.str().find("validates"), std::string::npos) << out.str();
    std::filesystem::remove(file);
    std::filesystem::remove(log);
}

TEST_P(EsiDevice, EveryObjectAndSubindexAppearsWithTypeAccessMappingAndDefault) {
    const Device d = dev();
    Doc doc = parse(esi::build_esi(d.description, d.dictionary));
    ASSERT_NE(doc, nullptr);
    xmlNodePtr dictionary =
        path(xmlDocGetRootElement(doc.get()), {"Descriptions", "Devices", "Device", "Profile", "Dictionary"});
    ASSERT_NE(dictionary, nullptr);
    std::map<std::string, xmlNodePtr> types;
    for (xmlNodePtr t : all(first(dictionary, "DataTypes"), "DataType")) {
        const std::string name = text(first(t, "Name"));
        EXPECT_EQ(types.count(name), 0u) << "duplicate data type " << name;
        types[name] = t;
    }
    // An entry's type: its base type, or for an enumerated entry a DataType with that base type and an
    // EnumInfo for each named value the entry takes, in order.
    auto check_type = [&](const std::string& name, const od::Entry& e) {
        if (e.enumeration.empty()) {
            EXPECT_EQ(name, expected_type(e));
            return;
        }
        ASSERT_EQ(types.count(name), 1u) << name;
        xmlNodePtr t = types[name];
        EXPECT_EQ(text(first(t, "BaseType")), expected_type(e));
        const auto enums = all(t, "EnumInfo");
        ASSERT_EQ(enums.size(), e.enumeration.size()) << name;
        for (std::size_t k = 0; k < enums.size(); ++k) {
            EXPECT_EQ(text(first(enums[k], "Text")), e.enumeration[k].text);
            EXPECT_EQ(std::stoll(text(first(enums[k], "Enum"))), e.enumeration[k].value);
        }
    };
    std::map<uint16_t, xmlNodePtr> objects;
    for (xmlNodePtr o : all(first(dictionary, "Objects"), "Object"))
        objects[static_cast<uint16_t>(hexdec(text(first(o, "Index"))))] = o;
    EXPECT_EQ(objects.size(), d.dictionary.objects().size());

    for (const od::Object& o : d.dictionary.objects()) {
        char idx[8];
        std::snprintf(idx, sizeof idx, "%04X", o.index);
        SCOPED_TRACE(std::string("object 0x") + idx + " " + o.name);
        ASSERT_EQ(objects.count(o.index), 1u);
        xmlNodePtr x = objects[o.index];
        EXPECT_EQ(text(first(x, "Name")), o.name);
        const std::string type = text(first(x, "Type"));
        ASSERT_EQ(types.count(type), 1u) << type;
        xmlNodePtr dt = types[type];
        if (o.code == od::ObjectCode::Var) {
            const od::Entry& e = o.entries.at(0);
            check_type(type, e);
            EXPECT_EQ(std::stoul(text(first(x, "BitSize"))), e.bit_length);
            EXPECT_EQ(std::stoul(text(first(dt, "BitSize"))), e.bit_length);
            EXPECT_EQ(access_from(first(x, "Flags")),
                      e.access & (a::RW | a::RxPdo | a::TxPdo | a::Backup | a::Settings));
            check_value(first(x, "Info"), e, "value");
            continue;
        }
        EXPECT_EQ(type, "DT" + std::string(idx));
        EXPECT_EQ(text(first(x, "BitSize")), text(first(dt, "BitSize")));
        const auto items = all(dt, "SubItem");
        const auto infos = all(first(x, "Info"), "SubItem");
        ASSERT_EQ(infos.size(), o.entries.size());
        xmlNodePtr elements = nullptr;
        for (xmlNodePtr si : items)
            if (text(first(si, "Name")) == "Elements") elements = si;
        for (std::size_t i = 0; i < o.entries.size(); ++i) {
            const od::Entry& e = o.entries[i];
            SCOPED_TRACE("subindex " + std::to_string(e.subindex));
            xmlNodePtr item = nullptr;
            for (xmlNodePtr si : items)
                if (first(si, "SubIdx") != nullptr && std::stoul(text(first(si, "SubIdx"))) == e.subindex)
                    item = si;
            std::string item_type;
            uint16_t item_access = 0;
            if (item != nullptr) {
                item_type = text(first(item, "Type"));
                EXPECT_EQ(std::stoul(text(first(item, "BitSize"))), e.bit_length);
                item_access = access_from(first(item, "Flags"));
                // Object Info/SubItem names match the data type's SubItem names (record style).
                EXPECT_EQ(text(first(infos[i], "Name")), text(first(item, "Name")));
            } else {
                // Array element: described by the "Elements" SubItem and its ARRAY data type.
                ASSERT_NE(elements, nullptr) << "subindex missing from " << type;
                ASSERT_GE(e.subindex, 1);
                xmlNodePtr arr = types[text(first(elements, "Type"))];
                ASSERT_NE(arr, nullptr);
                item_type = text(first(arr, "BaseType"));
                const auto n = std::stoul(text(path(arr, {"ArrayInfo", "Elements"})));
                EXPECT_EQ(std::stoul(text(path(arr, {"ArrayInfo", "LBound"}))), 1u);
                EXPECT_LE(e.subindex, n);
                EXPECT_EQ(std::stoul(text(first(arr, "BitSize"))), n * e.bit_length);
                item_access = access_from(first(elements, "Flags"));
            }
            check_type(item_type, e);
            EXPECT_EQ(types.count(item_type), 1u) << item_type;
            EXPECT_EQ(item_access, e.access & (a::RW | a::RxPdo | a::TxPdo | a::Backup | a::Settings));
            check_value(first(infos[i], "Info"), e, "value");
        }
    }
}

TEST_P(EsiDevice, AgreesWithTheSiiImage) {
    const Device d = dev();
    const auto img = esi::build_sii(d.description, d.dictionary);
    const auto sii = esi::parse_sii(img);
    ASSERT_TRUE(sii.general.has_value());
    Doc doc = parse(esi::build_esi(d.description, d.dictionary));
    ASSERT_NE(doc, nullptr);
    xmlNodePtr root = xmlDocGetRootElement(doc.get());
    EXPECT_EQ(static_cast<uint32_t>(hexdec(text(path(root, {"Vendor", "Id"})))), sii.vendor_id);
    xmlNodePtr device = path(root, {"Descriptions", "Devices", "Device"});
    ASSERT_NE(device, nullptr);
    xmlNodePtr type = first(device, "Type");
    EXPECT_EQ(static_cast<uint32_t>(hexdec(prop(type, "ProductCode").value_or("-1"))), sii.product_code);
    EXPECT_EQ(static_cast<uint32_t>(hexdec(prop(type, "RevisionNo").value_or("-1"))), sii.revision);
    EXPECT_EQ(text(type), sii.general->order);
    EXPECT_EQ(text(first(device, "Name")), sii.general->name);
    EXPECT_EQ(text(first(device, "GroupType")), sii.general->group);
    EXPECT_EQ(text(path(root, {"Descriptions", "Groups", "Group", "Type"})), sii.general->group);
    if (sii.general->ds402_channels) {
        EXPECT_EQ(text(path(device, {"Profile", "ProfileNo"})), "402");
    }

    // FMMUs
    const char* fmmu_names[] = {"", "Outputs", "Inputs", "MBoxState"};
    const auto fmmus = all(device, "Fmmu");
    std::size_t used = 0;
    for (uint8_t f : sii.fmmus)
        if (f >= 1 && f <= 3) {
            ASSERT_LT(used, fmmus.size());
            EXPECT_EQ(text(fmmus[used++]), fmmu_names[f]);
        }
    EXPECT_EQ(used, fmmus.size());

    // SyncManagers
    const char* sm_names[] = {"", "MBoxOut", "MBoxIn", "Outputs", "Inputs"};
    const auto sms = all(device, "Sm");
    ASSERT_EQ(sms.size(), sii.sync_managers.size());
    for (std::size_t i = 0; i < sms.size(); ++i) {
        const auto& s = sii.sync_managers[i];
        SCOPED_TRACE("SM" + std::to_string(i));
        ASSERT_LE(s.type, 4);
        EXPECT_EQ(text(sms[i]), sm_names[s.type]);
        EXPECT_EQ(hexdec(prop(sms[i], "StartAddress").value_or("-1")), s.start);
        EXPECT_EQ(hexdec(prop(sms[i], "ControlByte").value_or("-1")), s.control);
        EXPECT_EQ(hexdec(prop(sms[i], "DefaultSize").value_or("0")), s.length);
        EXPECT_EQ(hexdec(prop(sms[i], "Enable").value_or("0")), s.enable & 1);
    }

    // PDOs
    auto check_pdos = [&](const char* name, const std::vector<esi::SiiPdo>& list) {
        const auto pdos = all(device, name);
        ASSERT_EQ(pdos.size(), list.size()) << name;
        for (std::size_t i = 0; i < pdos.size(); ++i) {
            const auto& p = list[i];
            SCOPED_TRACE(p.name);
            EXPECT_EQ(hexdec(text(first(pdos[i], "Index"))), p.index);
            EXPECT_EQ(text(first(pdos[i], "Name")), p.name);
            EXPECT_EQ(prop(pdos[i], "Sm").value_or("255"), std::to_string(p.sm));
            EXPECT_EQ(prop(pdos[i], "Fixed").value_or("0") == "1",
                      (p.flags & esi::pdo_flags::FixedContent) != 0);
            const auto entries = all(pdos[i], "Entry");
            ASSERT_EQ(entries.size(), p.entries.size());
            for (std::size_t k = 0; k < entries.size(); ++k) {
                EXPECT_EQ(hexdec(text(first(entries[k], "Index"))), p.entries[k].index);
                EXPECT_EQ(
                    hexdec(text(first(entries[k], "SubIndex")).empty() ? "0"
                                                                       : text(first(entries[k], "SubIndex"))),
                    p.entries[k].subindex);
                EXPECT_EQ(std::stoul(text(first(entries[k], "BitLen"))), p.entries[k].bit_length);
                EXPECT_EQ(text(first(entries[k], "Name")), p.entries[k].name);
            }
        }
    };
    check_pdos("RxPdo", sii.rx_pdos);
    check_pdos("TxPdo", sii.tx_pdos);

    // Stack properties: mailbox data link layer (General flags bit 2), identification in 0x0134 (bit 3),
    // two MII ports.
    xmlNodePtr mbx = first(device, "Mailbox");
    EXPECT_EQ(prop(mbx, "DataLinkLayer") == "true", (sii.general->flags & 0x04) != 0);
    EXPECT_EQ(text(path(device, {"Info", "IdentificationReg134"})) == "true",
              (sii.general->flags & 0x08) != 0);
    EXPECT_EQ(all(first(device, "Info"), "Port").size(), 2u);
    EXPECT_EQ(sii.general->physical_ports, 0x0011);
    EXPECT_EQ(prop(device, "Physics"), "YY");

    // Mailbox
    xmlNodePtr coe = first(mbx, "CoE");
    EXPECT_EQ(coe != nullptr, (sii.mailbox_protocols & od::mailbox_protocol::CoE) != 0);
    EXPECT_EQ(first(mbx, "FoE") != nullptr, (sii.mailbox_protocols & od::mailbox_protocol::FoE) != 0);
    EXPECT_EQ(first(mbx, "EoE") != nullptr, (sii.mailbox_protocols & od::mailbox_protocol::EoE) != 0);
    if (coe != nullptr) {
        const uint8_t cd = sii.general->coe_details;
        EXPECT_EQ(prop(coe, "SdoInfo") == "true", (cd & od::coe_details::SdoInfo) != 0);
        EXPECT_EQ(prop(coe, "PdoAssign") == "true", (cd & od::coe_details::PdoAssign) != 0);
        EXPECT_EQ(prop(coe, "PdoConfig") == "true", (cd & od::coe_details::PdoConfig) != 0);
        EXPECT_EQ(prop(coe, "PdoUpload") == "true", (cd & od::coe_details::PdoUpload) != 0);
        EXPECT_EQ(prop(coe, "CompleteAccess") == "true", (cd & od::coe_details::CompleteAccess) != 0);
    }

    // DC
    const auto modes = all(first(device, "Dc"), "OpMode");
    ASSERT_EQ(modes.size(), sii.dc_modes.size());
    for (std::size_t i = 0; i < modes.size(); ++i) {
        const auto& m = sii.dc_modes[i];
        EXPECT_EQ(text(first(modes[i], "Name")), m.name);
        EXPECT_EQ(text(first(modes[i], "Desc")), m.description);
        EXPECT_EQ(hexdec(text(first(modes[i], "AssignActivate"))), m.assign_activate);
        if (m.assign_activate != 0) {
            EXPECT_EQ(prop(first(modes[i], "CycleTimeSync0"), "Factor"),
                      std::to_string(m.sync0_cycle_factor));
            EXPECT_EQ(hexdec(text(first(modes[i], "ShiftTimeSync0"))), m.sync0_shift_time);
        }
    }

    // EEPROM
    xmlNodePtr eeprom = first(device, "Eeprom");
    EXPECT_EQ(std::stoul(text(first(eeprom, "ByteSize"))), img.size());
    EXPECT_EQ(hexbin(text(first(eeprom, "ConfigData"))), std::vector<uint8_t>(img.begin(), img.begin() + 14));
    EXPECT_EQ(hexbin(text(first(eeprom, "BootStrap"))),
              std::vector<uint8_t>(img.begin() + 0x28, img.begin() + 0x30));
}

TEST_P(EsiDevice, WriteHelpersWriteWhatTheBuildersReturn) {
    const Device d = dev();
    const auto xml_path = temp(".esi.xml");
    const auto bin_path = temp(".sii.bin");
    esi::write_esi(xml_path, d.description, d.dictionary);
    esi::write_sii(bin_path, d.description, d.dictionary);
    std::ifstream x(xml_path, std::ios::binary), b(bin_path, std::ios::binary);
    const std::string xml((std::istreambuf_iterator<char>(x)), std::istreambuf_iterator<char>());
    const std::vector<uint8_t> bin((std::istreambuf_iterator<char>(b)), std::istreambuf_iterator<char>());
    EXPECT_EQ(xml, esi::build_esi(d.description, d.dictionary));
    EXPECT_EQ(bin, esi::build_sii(d.description, d.dictionary));
    std::filesystem::remove(xml_path);
    std::filesystem::remove(bin_path);
}

INSTANTIATE_TEST_SUITE_P(Devices, EsiDevice, ::testing::Values("small", "drive"));

TEST(Esi, SpecialCharactersAreEscapedAndRoundTrip) {
    const Device d = esi_test::small_device();
    ASSERT_NE(d.description.identity.device_name.find('&'), std::string::npos);
    Doc doc = parse(esi::build_esi(d.description, d.dictionary));
    ASSERT_NE(doc, nullptr);
    EXPECT_EQ(text(path(xmlDocGetRootElement(doc.get()), {"Descriptions", "Devices", "Device", "Name"})),
              d.description.identity.device_name);
}

// Byte strings that are not valid XML text (control characters, broken UTF-8) still give a valid file.
TEST(Esi, InvalidTextBytesStillGiveAValidFile) {
    od::DeviceDescription desc = esi_test::small_description();
    desc.identity.device_name = "Bad\x01name\xFF\xC3Z\xE2\x82\xAC ok \xC2\xB5s";
    desc.identity.group_type = "Drives\x1F";
    od::Dictionary dict = esi_test::small_dictionary(desc);
    const std::string xml = esi::build_esi(desc, dict);
    Doc doc = parse(xml);
    ASSERT_NE(doc, nullptr);
    const std::string name =
        text(path(xmlDocGetRootElement(doc.get()), {"Descriptions", "Devices", "Device", "Name"}));
    EXPECT_EQ(name, "Bad?name??Z\xE2\x82\xAC ok \xC2\xB5s");
    expect_schema_valid(doc.get());
}

// A device with nothing but an identity: no objects, no SyncManagers, no DC modes, no mailbox.
TEST(Esi, EmptyDeviceGivesValidFiles) {
    od::DeviceDescription desc;
    desc.mailbox_protocols = 0;
    od::Dictionary dict;
    Doc doc = parse(esi::build_esi(desc, dict));
    ASSERT_NE(doc, nullptr);
    expect_schema_valid(doc.get());
    const auto sii = esi::parse_sii(esi::build_sii(desc, dict));
    EXPECT_TRUE(sii.problems.empty());
    EXPECT_TRUE(sii.sync_managers.empty());
    EXPECT_TRUE(sii.tx_pdos.empty());
    ASSERT_TRUE(sii.general.has_value());
    EXPECT_EQ(sii.general->coe_details, 0);
}

// DiagMessages come from the device description, not from having a diagnosis history: a device with 0x10F3
// and no texts (its messages carry their text as a parameter) writes none, and still says DiagHistory. (That
// its ESI validates: EsiDevice/ValidatesAgainstTheSchema*, "small".)
TEST(Esi, ADeviceWithAHistoryButNoTextsWritesNoDiagMessages) {
    const Device d = esi_test::small_device();
    ASSERT_NE(d.dictionary.find(0x10F3), nullptr);
    ASSERT_TRUE(d.description.diag_messages.empty());
    const std::string xml = esi::build_esi(d.description, d.dictionary);
    EXPECT_EQ(xml.find("DiagMessage"), std::string::npos);
    const esi::EsiDevice back = esi::read_esi(xml);
    EXPECT_TRUE(back.diag_messages.empty());
    EXPECT_TRUE(back.coe_attributes.at("DiagHistory"));
}

TEST(Esi, StateDependentAccessUsesRestrictions) {
    const Device d = esi_test::small_device();
    const std::string xml = esi::build_esi(d.description, d.dictionary);
    EXPECT_NE(xml.find("<Access WriteRestrictions=\"PreOP\">rw</Access>"), std::string::npos);
    EXPECT_NE(xml.find("<Access WriteRestrictions=\"PreOP_SafeOP\">rw</Access>"), std::string::npos);
    EXPECT_NE(xml.find("<Access ReadRestrictions=\"OP\" WriteRestrictions=\"OP\">rw</Access>"),
              std::string::npos);
    EXPECT_NE(xml.find(">wo</Access>"), std::string::npos);
}

// BitOffs follow the complete-access image coe/ produces: subindex 0 in 16 bits, byte-sized entries on a
// byte boundary, bits packed, missing subindices skipped.
TEST(Esi, RecordBitOffsetsFollowTheCompleteAccessLayout) {
    const Device d = esi_test::small_device();
    Doc doc = parse(esi::build_esi(d.description, d.dictionary));
    ASSERT_NE(doc, nullptr);
    xmlNodePtr types = path(xmlDocGetRootElement(doc.get()),
                            {"Descriptions", "Devices", "Device", "Profile", "Dictionary", "DataTypes"});
    auto offsets = [&](const std::string& name, std::string& bits) {
        std::vector<int> v;
        for (xmlNodePtr t : all(types, "DataType"))
            if (text(first(t, "Name")) == name) {
                bits = text(first(t, "BitSize"));
                for (xmlNodePtr si : all(t, "SubItem"))
                    v.push_back(std::stoi(text(first(si, "BitOffs"))));
            }
        return v;
    };
    std::string bits;
    EXPECT_EQ(offsets("DT2003", bits), (std::vector<int>{0, 16, 17, 24}));
    EXPECT_EQ(bits, "40");
    EXPECT_EQ(offsets("DT1C32", bits), (std::vector<int>{0, 16, 32, 64, 80}));  // subindices 0, 1, 2, 4, 32
    EXPECT_EQ(bits, "81");
    EXPECT_EQ(offsets("DT1C12", bits), (std::vector<int>{0, 16}));  // SI0 + "Elements" (2 x UINT)
    EXPECT_EQ(bits, "48");
}

TEST(Esi, UnitsOnlyWhereTheCodeIsKnown) {
    EXPECT_EQ(esi::unit_code("mA"), 0xFD040000u);  // as in the EJ7211 ESI
    EXPECT_EQ(esi::unit_code("ns"), 0xF7030000u);
    EXPECT_FALSE(esi::unit_code("inc").has_value());
    const Device d = esi_test::small_device();
    const std::string xml = esi::build_esi(d.description, d.dictionary);
    EXPECT_NE(xml.find("<Unit>#xfd040000</Unit>"), std::string::npos);
    EXPECT_NE(xml.find("<Unit>#xf7030000</Unit>"), std::string::npos);
}

}  // namespace
