#pragma once
// The drive's diagnosis texts by id (0x10F3, ETG.1020; listed as DiagMessages in the ESI, ETG.2000), as a
// constexpr table with no other dependency: od/diag_texts.hpp serves it to the slave, and a master tool
// (ecatctl diag) names the ids without linking the object model. Target `od_wire`.
#include <array>
#include <cstdint>
#include <string_view>

namespace od {

struct DiagText {
    uint16_t id = 0;
    uint8_t type = 0;  // ETG.1020 message type: 0 info, 1 warning, 2 error
    std::string_view text;
};

// drive/src/state_machine.cpp to_string(State), drive/src/homing.cpp, drive/src/axis.cpp.
inline constexpr std::array<DiagText, 12> kDriveDiagTexts{{
    {0x8001, 0, "Not Ready to Switch On"},
    {0x8002, 0, "Switch On Disabled"},
    {0x8003, 0, "Ready to Switch On"},
    {0x8004, 0, "Switched On"},
    {0x8005, 0, "Operation Enabled"},
    {0x8006, 0, "Quick Stop Active"},
    {0x8007, 0, "Fault Reaction Active"},
    {0x8008, 0, "Fault"},
    {0x8010, 0, "Homing started"},
    {0x8011, 0, "Homing attained"},
    {0x8012, 1, "Homing error"},
    {0x8020, 1, "Fault reset refused: cause still present"},
}};

// The text of an id; empty if the id is unknown.
constexpr std::string_view diag_text_of(uint16_t id) {
    for (const DiagText& t : kDriveDiagTexts)
        if (t.id == id) return t.text;
    return {};
}

}  // namespace od
