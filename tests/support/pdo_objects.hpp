#pragma once
// Process-data objects made by hand for tests of PDO mapping and assignment: a VAR to map, and a mapping or
// assignment object (ARRAY of UNSIGNED32 mapping words or UNSIGNED16 PDO indices) with its direction declared
// as a product declares it (od::Object::direction), whatever its index.
#include <cstdint>
#include <string>
#include <vector>

#include "od/dictionary.hpp"

namespace test_support {

inline od::Object pdo_var(uint16_t index, od::DataType type, uint16_t bits, uint16_t access) {
    od::Object o;
    o.index = index;
    o.type = type;
    o.name = "v";
    od::Entry e;
    e.index = index;
    e.type = type;
    e.bit_length = bits;
    e.access = access;
    e.name = "v";
    e.default_value = uint64_t{0};
    o.entries.push_back(e);
    return o;
}

// Subindex 0 the count (writable in Pre-Op), 1..n the values; UNSIGNED16 entries for an assignment,
// UNSIGNED32 for a mapping.
inline od::Object pdo_array(uint16_t index, od::PdoDirection dir, od::DataType type,
                            const std::vector<uint64_t>& values) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Array;
    o.type = type;
    o.name = "o";
    o.direction = dir;
    od::Entry n;
    n.index = index;
    n.type = od::DataType::Unsigned8;
    n.bit_length = 8;
    n.access = od::access::RW_PreOp;
    n.name = "n";
    n.default_value = uint64_t{values.size()};
    o.entries.push_back(n);
    for (std::size_t k = 0; k < values.size(); ++k) {
        od::Entry e = n;
        e.subindex = static_cast<uint8_t>(k + 1);
        e.type = type;
        e.bit_length = type == od::DataType::Unsigned16 ? 16 : 32;
        e.name = "e" + std::to_string(k + 1);
        e.default_value = values[k];
        o.entries.push_back(e);
    }
    return o;
}

}  // namespace test_support
