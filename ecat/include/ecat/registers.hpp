#pragma once
// ESC register addresses and bits the slave stack uses through the PDI. They are defined once, in the ESC
// register map (esc/wire/registers.hpp, namespace esc::reg); ecat::reg offers them under the stack's
// names, including the few it spells differently.
#include <cstdint>

#include "esc/wire/registers.hpp"

namespace ecat::reg {

using namespace esc::reg;

constexpr uint16_t kAlEventRequest = esc::reg::kAlEvent;
constexpr uint16_t kWatchdogDivider = esc::reg::kWdDivider;
constexpr uint16_t kWatchdogTimePd = esc::reg::kWdTimePd;
constexpr uint16_t kWatchdogStatusPd = esc::reg::kWdStatusPd;
constexpr uint16_t kDcSystemTimeOffset = esc::reg::kDcOffset;
constexpr uint16_t kDcCyclicUnitControl = esc::reg::kDcCyclicControl;
constexpr uint16_t kDcSync0CycleTime = esc::reg::kDcSync0Cycle;
constexpr uint16_t kDcSync1CycleTime = esc::reg::kDcSync1Cycle;
constexpr uint16_t kDcEcatBufferChangeTime =
    esc::reg::kDcEcatBufferChange;  // local time of the last ECAT SM buffer change

// AL event request bits (0x0220).
constexpr uint32_t kEvAlControl = esc::alev::kAlControl;
constexpr uint32_t kEvSync0 = esc::alev::kSync0;
constexpr uint32_t kEvSync1 = esc::alev::kSync1;
constexpr uint32_t kEvSmActivation = esc::alev::kSmActivation;
constexpr uint32_t kEvWatchdogPd = esc::alev::kWatchdogPd;
constexpr uint32_t ev_sm(unsigned n) {
    return esc::alev::sm(n);
}

}  // namespace ecat::reg
