#include "identity.hpp"

#include <libxml/parser.h>
#include <libxml/tree.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <memory>

#include "maxpos/maxpos.hpp"
#include "od/device_config.hpp"

namespace fwimage {

namespace {

DeviceIdentity from(const od::Identity& id) {
    return {id.vendor_id, id.product_code, id.device_name};
}

// ESI numbers: "#x30010000" (hex, ETG.2000 HexDecValue) or decimal.
std::optional<uint32_t> esi_number(const std::string& text) {
    std::string t = text;
    int base = 10;
    if (t.size() > 2 && t[0] == '#' && (t[1] == 'x' || t[1] == 'X')) {
        t = t.substr(2);
        base = 16;
    }
    if (t.empty() || t[0] == '-') return std::nullopt;
    errno = 0;
    char* end = nullptr;
    const unsigned long long v = std::strtoull(t.c_str(), &end, base);
    if (errno != 0 || *end != '\0' || v > 0xFFFFFFFFull) return std::nullopt;
    return static_cast<uint32_t>(v);
}

xmlNodePtr child(xmlNodePtr n, const char* name) {
    for (xmlNodePtr c = n ? n->children : nullptr; c != nullptr; c = c->next)
        if (c->type == XML_ELEMENT_NODE && std::strcmp(reinterpret_cast<const char*>(c->name), name) == 0)
            return c;
    return nullptr;
}

std::string text_of(xmlNodePtr n) {
    if (!n) return {};
    std::unique_ptr<xmlChar, decltype(xmlFree)> t(xmlNodeGetContent(n), xmlFree);
    return t ? reinterpret_cast<const char*>(t.get()) : "";
}

std::string attr_of(xmlNodePtr n, const char* name) {
    if (!n) return {};
    std::unique_ptr<xmlChar, decltype(xmlFree)> t(xmlGetProp(n, reinterpret_cast<const xmlChar*>(name)),
                                                  xmlFree);
    return t ? reinterpret_cast<const char*>(t.get()) : "";
}

}  // namespace

DeviceIdentity default_identity() {
    return from(maxpos::description().identity);
}

std::optional<DeviceIdentity> identity_from_config(const std::string& path, std::string& error) {
    try {
        return from(maxpos::load_config(path).identity);
    } catch (const std::exception& e) {
        error = e.what();
        return std::nullopt;
    }
}

std::optional<DeviceIdentity> identity_from_esi(const std::string& path, std::string& error) {
    std::unique_ptr<xmlDoc, decltype(&xmlFreeDoc)> doc(
        xmlReadFile(path.c_str(), nullptr, XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING),
        &xmlFreeDoc);
    if (!doc) {
        const xmlError* e = xmlGetLastError();
        error = path + ": not a readable XML file" +
                (e && e->message ? std::string(" (line ") + std::to_string(e->line) + ": " + e->message : "");
        while (!error.empty() && (error.back() == '\n' || error.back() == ' '))
            error.pop_back();
        if (e && e->message) error += ")";
        return std::nullopt;
    }
    xmlNodePtr root = xmlDocGetRootElement(doc.get());
    if (!root || std::strcmp(reinterpret_cast<const char*>(root->name), "EtherCATInfo") != 0) {
        error = path + ": not an ESI file (the root element is not EtherCATInfo)";
        return std::nullopt;
    }
    xmlNodePtr device = child(child(child(root, "Descriptions"), "Devices"), "Device");
    xmlNodePtr type = child(device, "Type");
    auto vendor = esi_number(text_of(child(child(root, "Vendor"), "Id")));
    auto product = esi_number(attr_of(type, "ProductCode"));
    if (!vendor || !product) {
        error = path + ": no Vendor/Id or Descriptions/Devices/Device/Type ProductCode in it";
        return std::nullopt;
    }
    DeviceIdentity id{*vendor, *product, text_of(child(device, "Name"))};
    if (id.device_name.empty()) id.device_name = text_of(type);
    return id;
}

}  // namespace fwimage
