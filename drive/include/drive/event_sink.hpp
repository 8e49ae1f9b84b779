#pragma once
// How the drive reports errors and diagnosis events to the communication side. The CoE layer implements it
// (emergency messages, diagnosis history 0x10F3); tests and drive-sim implement it to observe the drive.
// Calls come from inside Drive::cycle(): implementations must be quick and must not call back into the drive.
#include <array>
#include <cstdint>
#include <string_view>

namespace drive {

enum class Severity : uint8_t { Info = 0, Warning = 1, Error = 2 };

class EventSink {
  public:
    virtual ~EventSink() = default;
    // An error became active. 0x603F and 0x1001 already hold error_code and error_register.
    // mfr: the five manufacturer-specific bytes of the emergency message (here: the drive state and mode
    // at the moment of the error, see docs/decisions/drive.md).
    virtual void raise(uint16_t error_code, uint8_t error_register, const std::array<uint8_t, 5>& mfr) = 0;
    // An error (or warning) is no longer active: fault reset accepted or warning cause gone.
    // error_register is the new value of 0x1001 (0 when nothing remains: the "error reset" emergency).
    virtual void clear(uint16_t error_code, uint8_t error_register) = 0;
    // A diagnosis message that is not an error: state changes, warnings, homing results.
    // code is the CiA 402 / error code the text is about (0 if none); text is a static string.
    virtual void diag(Severity severity, uint16_t code, std::string_view text) = 0;
};

// A sink that drops everything; the default when nobody listens.
class NullEventSink final : public EventSink {
  public:
    void raise(uint16_t, uint8_t, const std::array<uint8_t, 5>&) override {}
    void clear(uint16_t, uint8_t) override {}
    void diag(Severity, uint16_t, std::string_view) override {}
};

}  // namespace drive
