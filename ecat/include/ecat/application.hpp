#pragma once
// What the slave stack asks of the device application (the drive glue implements it).
#include <cstdint>

#include "od/types.hpp"

namespace ecat {

class Application {
  public:
    virtual ~Application() = default;
    // Extra application checks on a requested transition up (I->P, P->S, S->O, I->B), after the stack's
    // own checks passed. Returns 0 to allow it or an AL status code (esc/wire/al.hpp) to refuse it.
    // Transitions down always succeed and are not asked about.
    virtual uint16_t check_transition(od::AlState /*from*/, od::AlState /*to*/) { return 0; }
    // The AL state changed (also on fall-backs with the error flag).
    virtual void on_state_change(od::AlState /*from*/, od::AlState /*to*/) {}
    // One application cycle: outputs were copied into the dictionary (Op only) before, inputs are copied
    // out of it after this returns. Called in Safe-Op and Op.
    virtual void on_cycle(uint64_t /*now_ns*/) {}
    // Outputs are no longer valid: process-data watchdog, sync loss or leaving Op (the drive's 0x6007
    // reaction). Called before on_state_change of the same event.
    virtual void on_outputs_lost() {}
    // Bootstrap -> Init, or an ESC reset (0x0040/0x0041, which resets everything behind the PDI): the
    // device restarts (e.g. loads a new firmware image). Called as the last thing
    // poll() does, after AL status shows Init; the application may schedule a restart of the whole firmware
    // but must not destroy the Stack from inside this call.
    virtual void on_restart() {}
};

}  // namespace ecat
