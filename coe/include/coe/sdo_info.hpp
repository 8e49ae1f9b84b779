#pragma once
// SDO information service helpers (ETG.1000.6 SDO Information) shared with the ESI/SII side.
#include <cstdint>
#include <string_view>

#include "od/dictionary.hpp"

namespace coe {

// Get OD list types: 0 = the number of objects in lists 1..5, then the lists themselves.
enum class OdList : uint16_t { Lengths = 0, All = 1, RxPdo = 2, TxPdo = 3, Backup = 4, Settings = 5 };

// Whether an object belongs to list type 1..5: all objects, or objects with at least one entry that is
// RxPDO-mappable / TxPDO-mappable / backed up / a setting.
bool in_od_list(const od::Object& obj, uint16_t list_type);

// The entry-description unit word (value info bit 3) for a unit text such as "ms", "mA", "V", "Hz":
// CiA 303-2 layout, byte 3 = power-of-ten prefix, byte 2 = SI unit code. 0 when there is no SI code.
uint32_t unit_code(std::string_view unit);

}  // namespace coe
