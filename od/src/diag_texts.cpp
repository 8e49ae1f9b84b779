#include "od/diag_texts.hpp"

#include <array>

namespace od {

namespace {

// drive/src/state_machine.cpp to_string(State), drive/src/homing.cpp, drive/src/axis.cpp.
constexpr std::array<DiagText, 12> kTexts{{
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

}  // namespace

std::span<const DiagText> drive_diag_texts() {
    return kTexts;
}

uint16_t diag_text_id(std::string_view text) {
    for (const DiagText& t : kTexts)
        if (t.text == text) return t.id;
    return 0;
}

std::string_view diag_text(uint16_t id) {
    for (const DiagText& t : kTexts)
        if (t.id == id) return t.text;
    return {};
}

}  // namespace od
