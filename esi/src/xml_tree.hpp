#pragma once
// Walking a libxml2 tree: the few helpers the ESI and ENI readers (esi_reader.cpp, eni/src/eni_reader.cpp)
// share. Internal to the readers (libxml2 stays out of their public headers).
#include <libxml/tree.h>

#include <string>
#include <vector>

namespace esi::xml {

using Node = xmlNode*;

inline std::string name_of(Node n) {
    return n && n->name ? reinterpret_cast<const char*>(n->name) : "";
}
inline bool is(Node n, const char* name) {
    return n && n->type == XML_ELEMENT_NODE && name_of(n) == name;
}
inline Node child(Node n, const char* name) {
    if (!n) return nullptr;
    for (Node c = n->children; c; c = c->next)
        if (is(c, name)) return c;
    return nullptr;
}
inline std::vector<Node> children(Node n, const char* name) {
    std::vector<Node> out;
    if (!n) return out;
    for (Node c = n->children; c; c = c->next)
        if (is(c, name)) out.push_back(c);
    return out;
}
inline std::string trim(const std::string& s) {
    auto b = s.find_first_not_of(" \t\r\n");
    auto e = s.find_last_not_of(" \t\r\n");
    return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}
// The text content of an element, blanks around it removed ("" for none).
inline std::string text(Node n) {
    if (!n) return "";
    xmlChar* t = xmlNodeGetContent(n);
    std::string s = t ? reinterpret_cast<const char*>(t) : "";
    xmlFree(t);
    return trim(s);
}

}  // namespace esi::xml
