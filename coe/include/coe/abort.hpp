#pragma once
// The one mapping from od::Status to an SDO abort code (the codes and their texts: coe/wire/sdo.hpp).
#include <cstdint>

#include "coe/wire/sdo.hpp"
#include "od/types.hpp"

namespace coe {

// The abort code the standard names for an object-model result (0 for Ok).
uint32_t abort_code(od::Status s);

}  // namespace coe
