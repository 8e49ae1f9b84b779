#pragma once
// What the firmware layers (ecat/, coe/, foe/) did that the person running the slave wants to know. They
// never print: the program behind them (tools/) implements this and decides where a line goes and at which
// level. Every method has an empty default, so a sink implements what it cares about. Called from the
// firmware's thread, rarely (never per frame or per cycle); nothing here may throw.
#include <cstdint>
#include <string_view>

#include "od/types.hpp"

namespace ecat {

class EventSink {
  public:
    virtual ~EventSink() = default;

    // ---- ecat/ ----------------------------------------------------------------------------------------
    // The AL state changed (a master's request, or a fall-back on a local error).
    virtual void state_changed(od::AlState /*from*/, od::AlState /*to*/) {}
    // A master's AL control request was refused: the error indication is set with this AL status code.
    // requested is the raw state of AL control bits 0-3 (an unknown value is refused too).
    virtual void state_refused(od::AlState /*current*/, uint8_t /*requested*/, uint16_t /*al_status_code*/) {}
    // A local error (watchdog, sync error, ...) set the error indication and left the device in `state`.
    virtual void local_error(od::AlState /*state*/, uint16_t /*al_status_code*/) {}
    // The process-data watchdog expired in Op (outputs were not refreshed in time); local_error follows.
    virtual void watchdog_expired(od::AlState /*state*/) {}

    // ---- foe/ -----------------------------------------------------------------------------------------
    // A file write over FoE ended: error_code 0 = stored, else the FoE error code sent and its text.
    virtual void foe_write(std::string_view /*name*/, uint64_t /*bytes*/, uint32_t /*error_code*/,
                           std::string_view /*error_text*/) {}
};

}  // namespace ecat
