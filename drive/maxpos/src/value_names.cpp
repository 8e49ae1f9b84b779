#include "value_names.hpp"

#include <array>

namespace maxpos {
namespace {

struct Named {
    int64_t value;
    std::string_view text;
};
struct Table {
    uint16_t index;
    uint8_t sub;
    const Named* first;
    std::size_t count;
};

// IEC 61800-7-201 modes of operation (0x6060 / 0x6061).
constexpr Named kModes[] = {
    {0, "No mode"},
    {1, "Profile position mode"},
    {2, "Velocity mode"},
    {3, "Profile velocity mode"},
    {4, "Profile torque mode"},
    {6, "Homing mode"},
    {7, "Interpolated position mode"},
    {8, "Cyclic synchronous position mode"},
    {9, "Cyclic synchronous velocity mode"},
    {10, "Cyclic synchronous torque mode"},
};
// IEC 61800-7-201 0x605A quick stop option code.
constexpr Named kQuickStop[] = {
    {0, "Disable drive function"},
    {1, "Slow down on slow down ramp and transit into Switch On Disabled"},
    {2, "Slow down on quick stop ramp and transit into Switch On Disabled"},
    {3, "Slow down on current limit and transit into Switch On Disabled"},
    {4, "Slow down on voltage limit and transit into Switch On Disabled"},
    {5, "Slow down on slow down ramp and stay in Quick Stop Active"},
    {6, "Slow down on quick stop ramp and stay in Quick Stop Active"},
    {7, "Slow down on current limit and stay in Quick Stop Active"},
    {8, "Slow down on voltage limit and stay in Quick Stop Active"},
};
// 0x605B shutdown and 0x605C disable operation option codes.
constexpr Named kShutdown[] = {
    {0, "Disable drive function (switch off the power stage)"},
    {1, "Slow down with slow down ramp; then disable drive function"},
};
// 0x605D halt option code.
constexpr Named kHalt[] = {
    {1, "Slow down on slow down ramp and stay in Operation Enabled"},
    {2, "Slow down on quick stop ramp and stay in Operation Enabled"},
    {3, "Slow down on current limit and stay in Operation Enabled"},
    {4, "Slow down on voltage limit and stay in Operation Enabled"},
};
// 0x605E fault reaction option code; -1 is maxon's "signal only" (MAXPOS firmware specification).
constexpr Named kFaultReaction[] = {
    {-1, "Signal only (warning, no reaction)"}, {0, "Disable drive function, motor is free to rotate"},
    {1, "Slow down on slow down ramp"},         {2, "Slow down on quick stop ramp"},
    {3, "Slow down on current limit"},          {4, "Slow down on voltage limit"},
};
// 0x6098 homing methods: IEC 61800-7-201 1-37, maxon's current threshold methods -1..-4.
constexpr Named kHoming[] = {
    {-4, "Current threshold negative speed"},
    {-3, "Current threshold positive speed"},
    {-2, "Current threshold negative speed and index"},
    {-1, "Current threshold positive speed and index"},
    {1, "Negative limit switch and index"},
    {2, "Positive limit switch and index"},
    {7, "Home switch positive speed and index"},
    {11, "Home switch negative speed and index"},
    {17, "Negative limit switch"},
    {18, "Positive limit switch"},
    {23, "Home switch positive speed"},
    {27, "Home switch negative speed"},
    {33, "Index negative speed"},
    {34, "Index positive speed"},
    {35, "Actual position"},
    {37, "Actual position"},
};
// ETG.1020 0x1C32:01 / 0x1C33:01 synchronisation type.
constexpr Named kSyncOutputs[] = {
    {0, "Free Run"}, {1, "Synchronous with SM 2 event"},  {2, "DC SYNC0"},
    {3, "DC SYNC1"}, {34, "Synchronous with SM 3 event"},
};
constexpr Named kSyncInputs[] = {
    {0, "Free Run"}, {1, "Synchronous with SM 3 event"},  {2, "DC SYNC0"},
    {3, "DC SYNC1"}, {34, "Synchronous with SM 2 event"},
};
// IEC 61800-7-201 0x6402 motor type (the values the MAXPOS takes).
constexpr Named kMotorType[] = {
    {1, "Phase modulated DC motor"},
    {10, "Sinusoidal PM brushless motor"},
    {11, "Trapezoidal PM brushless motor"},
};

template <std::size_t N>
constexpr Table table(uint16_t index, uint8_t sub, const Named (&t)[N]) {
    return Table{index, sub, t, N};
}

constexpr std::array kTables{
    table(0x1C32, 1, kSyncOutputs),   table(0x1C33, 1, kSyncInputs), table(0x605A, 0, kQuickStop),
    table(0x605B, 0, kShutdown),      table(0x605C, 0, kShutdown),   table(0x605D, 0, kHalt),
    table(0x605E, 0, kFaultReaction), table(0x6060, 0, kModes),      table(0x6061, 0, kModes),
    table(0x6098, 0, kHoming),        table(0x6402, 0, kMotorType),
};

const Table* find(uint16_t index, uint8_t sub) {
    for (const Table& t : kTables)
        if (t.index == index && t.sub == sub) return &t;
    return nullptr;
}

}  // namespace

bool has_value_names(uint16_t index, uint8_t sub) {
    return find(index, sub) != nullptr;
}

std::string_view value_name(uint16_t index, uint8_t sub, int64_t value) {
    if (const Table* t = find(index, sub))
        for (std::size_t i = 0; i < t->count; ++i)
            if (t->first[i].value == value) return t->first[i].text;
    return {};
}

}  // namespace maxpos
