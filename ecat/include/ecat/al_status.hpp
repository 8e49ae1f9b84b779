#pragma once
// AL status codes written to 0x0134: the constants and their names live in the AL vocabulary
// (ecat/wire/al.hpp, ETG.1000.6 Table 11); this header keeps the slave's name() spelling.
#include <cstdint>
#include <string_view>

#include "ecat/wire/al.hpp"

namespace ecat::al {

// Human-readable name ("" for codes not in the table).
std::string_view name(uint16_t code);

}  // namespace ecat::al
