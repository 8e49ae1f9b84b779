// The od-free ESI reader (see esi/esi_reader.hpp), over libxml2's tree.
#include "esi/esi_reader.hpp"

#include <libxml/parser.h>
#include <libxml/tree.h>

#include <cstring>
#include <memory>
#include <stdexcept>

namespace esi {

namespace {

bool is(xmlNodePtr n, const char* name) {
    return n != nullptr && n->type == XML_ELEMENT_NODE &&
           std::strcmp(reinterpret_cast<const char*>(n->name), name) == 0;
}

xmlNodePtr first(xmlNodePtr parent, const char* name) {
    if (parent == nullptr) return nullptr;
    for (xmlNodePtr c = parent->children; c != nullptr; c = c->next)
        if (is(c, name)) return c;
    return nullptr;
}

std::vector<xmlNodePtr> all(xmlNodePtr parent, const char* name) {
    std::vector<xmlNodePtr> v;
    if (parent == nullptr) return v;
    for (xmlNodePtr c = parent->children; c != nullptr; c = c->next)
        if (is(c, name)) v.push_back(c);
    return v;
}

xmlNodePtr path(xmlNodePtr n, std::initializer_list<const char*> names) {
    for (const char* name : names)
        n = first(n, name);
    return n;
}

std::string text(xmlNodePtr n) {
    if (n == nullptr) return {};
    xmlChar* c = xmlNodeGetContent(n);
    std::string s = c != nullptr ? reinterpret_cast<const char*>(c) : "";
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

bool truth(const std::optional<std::string>& v) {
    return v && (*v == "1" || *v == "true");
}

uint64_t number(xmlNodePtr n) {
    return parse_hex_dec(text(n)).value_or(0);
}

std::optional<uint32_t> number_prop(xmlNodePtr n, const char* name) {
    const auto p = prop(n, name);
    if (!p) return std::nullopt;
    const auto v = parse_hex_dec(*p);
    if (!v) return std::nullopt;
    return static_cast<uint32_t>(*v);
}

std::vector<uint8_t> hex_binary(const std::string& s) {
    std::vector<uint8_t> out;
    auto nibble = [](char c) -> int {
        if (c >= '0' && c <= '9') return c - '0';
        if (c >= 'a' && c <= 'f') return c - 'a' + 10;
        if (c >= 'A' && c <= 'F') return c - 'A' + 10;
        return -1;
    };
    for (std::size_t i = 0; i + 1 < s.size(); i += 2) {
        const int hi = nibble(s[i]), lo = nibble(s[i + 1]);
        if (hi < 0 || lo < 0) return {};
        out.push_back(static_cast<uint8_t>(hi << 4 | lo));
    }
    return out;
}

EsiPdo read_pdo(xmlNodePtr n, bool rx) {
    EsiPdo p;
    p.rx = rx;
    p.index = static_cast<uint16_t>(number(first(n, "Index")));
    p.name = text(first(n, "Name"));
    if (const auto sm = number_prop(n, "Sm")) p.sm = static_cast<int>(*sm);
    p.fixed = truth(prop(n, "Fixed"));
    p.mandatory = truth(prop(n, "Mandatory"));
    for (xmlNodePtr x : all(n, "Exclude"))
        p.exclude.push_back(static_cast<uint16_t>(number(x)));
    for (xmlNodePtr e : all(n, "Entry")) {
        EsiPdoEntry pe;
        pe.index = static_cast<uint16_t>(number(first(e, "Index")));
        pe.subindex = static_cast<uint8_t>(number(first(e, "SubIndex")));
        pe.bit_length = static_cast<uint8_t>(number(first(e, "BitLen")));
        pe.name = text(first(e, "Name"));
        pe.data_type = text(first(e, "DataType"));
        p.entries.push_back(std::move(pe));
    }
    return p;
}

}  // namespace

std::optional<uint64_t> parse_hex_dec(const std::string& t) {
    if (t.empty()) return std::nullopt;
    const bool hex = t.size() > 2 && t[0] == '#' && (t[1] == 'x' || t[1] == 'X');
    const std::string digits = hex ? t.substr(2) : t;
    if (digits.empty()) return std::nullopt;
    uint64_t v = 0;
    for (char c : digits) {
        int d = -1;
        if (c >= '0' && c <= '9') d = c - '0';
        if (hex && c >= 'a' && c <= 'f') d = c - 'a' + 10;
        if (hex && c >= 'A' && c <= 'F') d = c - 'A' + 10;
        if (d < 0) return std::nullopt;
        v = v * (hex ? 16u : 10u) + static_cast<uint64_t>(d);
    }
    return v;
}

const EsiPdo* EsiDevice::pdo(uint16_t index) const {
    for (const EsiPdo& p : pdos)
        if (p.index == index) return &p;
    return nullptr;
}

const EsiObject* EsiDevice::object(uint16_t index) const {
    for (const EsiObject& o : objects)
        if (o.index == index) return &o;
    return nullptr;
}

EsiDevice read_esi(const std::string& xml) {
    std::unique_ptr<xmlDoc, decltype(&xmlFreeDoc)> doc(
        xmlReadMemory(xml.data(), static_cast<int>(xml.size()), "esi.xml", nullptr,
                      XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING),
        &xmlFreeDoc);
    if (!doc) throw std::runtime_error("ESI: not well-formed XML");
    xmlNodePtr root = xmlDocGetRootElement(doc.get());
    if (!is(root, "EtherCATInfo")) throw std::runtime_error("ESI: the root element is not EtherCATInfo");
    xmlNodePtr device = path(root, {"Descriptions", "Devices", "Device"});
    if (device == nullptr) throw std::runtime_error("ESI: no Descriptions/Devices/Device");

    EsiDevice d;
    xmlNodePtr vendor = first(root, "Vendor");
    d.vendor_id = static_cast<uint32_t>(number(first(vendor, "Id")));
    d.vendor_name = text(first(vendor, "Name"));
    xmlNodePtr type = first(device, "Type");
    d.type = text(type);
    d.product_code = number_prop(type, "ProductCode").value_or(0);
    d.revision = number_prop(type, "RevisionNo").value_or(0);
    d.name = text(first(device, "Name"));

    xmlNodePtr timeout = path(device, {"Info", "Mailbox", "Timeout"});
    if (timeout != nullptr) {
        d.mailbox_request_timeout_ms = static_cast<uint32_t>(number(first(timeout, "RequestTimeout")));
        d.mailbox_response_timeout_ms = static_cast<uint32_t>(number(first(timeout, "ResponseTimeout")));
    }

    xmlNodePtr profile = first(device, "Profile");
    if (xmlNodePtr no = first(profile, "ProfileNo")) d.profile_number = static_cast<uint32_t>(number(no));
    for (xmlNodePtr o : all(path(profile, {"Dictionary", "Objects"}), "Object")) {
        EsiObject obj;
        obj.index = static_cast<uint16_t>(number(first(o, "Index")));
        obj.name = text(first(o, "Name"));
        obj.type = text(first(o, "Type"));
        obj.bit_size = static_cast<uint32_t>(number(first(o, "BitSize")));
        obj.access = text(path(o, {"Flags", "Access"}));
        d.objects.push_back(std::move(obj));
    }
    for (xmlNodePtr m : all(first(profile, "DiagMessages"), "DiagMessage"))
        d.diag_messages[static_cast<uint16_t>(number(first(m, "TextId")))] = text(first(m, "MessageText"));

    for (xmlNodePtr s : all(device, "Sm")) {
        EsiSm sm;
        sm.kind = text(s);
        sm.start = number_prop(s, "StartAddress").value_or(0);
        sm.default_size = number_prop(s, "DefaultSize");
        sm.min_size = number_prop(s, "MinSize");
        sm.max_size = number_prop(s, "MaxSize");
        sm.control = number_prop(s, "ControlByte").value_or(0);
        sm.enable = number_prop(s, "Enable").value_or(0) != 0;
        d.sync_managers.push_back(std::move(sm));
    }
    for (xmlNodePtr p : all(device, "RxPdo"))
        d.pdos.push_back(read_pdo(p, true));
    for (xmlNodePtr p : all(device, "TxPdo"))
        d.pdos.push_back(read_pdo(p, false));

    xmlNodePtr mailbox = first(device, "Mailbox");
    if (xmlNodePtr coe = first(mailbox, "CoE")) {
        for (xmlAttrPtr a = coe->properties; a != nullptr; a = a->next) {
            const std::string name = reinterpret_cast<const char*>(a->name);
            const auto v = prop(coe, name.c_str());
            if (v && (*v == "true" || *v == "false" || *v == "1" || *v == "0")) d.coe[name] = truth(v);
        }
    }
    d.foe = first(mailbox, "FoE") != nullptr;

    xmlNodePtr eeprom = first(device, "Eeprom");
    d.eeprom_bytes = static_cast<uint32_t>(number(first(eeprom, "ByteSize")));
    d.config_data = hex_binary(text(first(eeprom, "ConfigData")));
    d.image16x14 = hex_binary(text(first(device, "ImageData16x14")));
    return d;
}

}  // namespace esi
