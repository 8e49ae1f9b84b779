#pragma once
// The texts of the drive's diagnosis messages (0x10F3, ETG.1020) by text id, constexpr and od-free: the
// CiA 402 core's own (drive/src/device_control.cpp state names, homing.cpp, supervisor.cpp) and one per
// error code of its error table (error_codes.hpp). A product that runs the drive core lists them in its
// device description (od::DeviceDescription::diag_messages, e.g. maxpos::description()), so its ESI carries
// them as DiagMessages (ETG.2000) and its 0x10F3 messages carry their ids; ecatctl diag names the ids of the
// built-in drive with them when it has no ESI. Target `drive_wire`.
#include <array>
#include <cstdint>
#include <string_view>

#include "drive/wire/error_codes.hpp"

namespace drive {

struct DiagText {
    uint16_t id = 0;
    uint8_t type = 0;  // ETG.1020 message type: 0 info, 1 warning, 2 error
    std::string_view text;
};

// The messages the drive emits without an error of its table: the states it enters (to_string(State)),
// homing progress, a refused fault reset.
inline constexpr std::array<DiagText, 12> kDiagTexts{{
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

// The text id of the message an error of the table raises (and of the warning it becomes with the reaction
// "signal only"): the error code itself. ETG.1020 leaves text ids to the device; the error codes and the ids
// above do not overlap (tests/drive check it), and a master shows the same number twice.
constexpr uint16_t error_text_id(uint16_t error_code) {
    return error_code;
}

// The built-in drive's text of an id (the table above, then the errors' names); empty if the id is unknown.
constexpr std::string_view diag_text_of(uint16_t id) {
    for (const DiagText& t : kDiagTexts)
        if (t.id == id) return t.text;
    for (const ErrorInfo& e : kErrorTable)
        if (error_text_id(e.code) == id) return e.name;
    return {};
}

}  // namespace drive
