#pragma once
// The names of the values of the MAXPOS's enumerated entries, declared once: the modes of operation
// (0x6060/0x6061), the option codes (0x605A-0x605E), the homing methods (0x6098), the synchronisation types
// of 0x1C32/0x1C33 and the motor types (0x6402). The drive's dictionary gives each such entry the names of
// exactly the values it accepts (od::Entry::enumeration, from its value set or its limits), the ESI lists
// them as EnumInfo (ETG.2000) and a master tool can print them. Texts: IEC 61800-7-201 (CiA 402), ETG.1020
// (synchronisation types), the MAXPOS firmware specification where maxon defines its own values.
#include <cstdint>
#include <string_view>

namespace maxpos {

// True if the entry's values have names here.
bool has_value_names(uint16_t index, uint8_t sub);
// The name of one value; empty if it has none.
std::string_view value_name(uint16_t index, uint8_t sub, int64_t value);

}  // namespace maxpos
