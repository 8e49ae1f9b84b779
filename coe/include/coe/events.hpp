#pragma once
// What the application's error and diagnosis events become on the wire: the glue between an application
// event interface (drive::EventSink: raise / clear / diag) and CoE. coe/ does not depend on drive/, so the
// glue's sink forwards its three calls here one to one.
//
//   raise(code, register, mfr) -> emergency (code, register, mfr) + 0x10F3 error message (diag code
//                                  0xE800 | code << 16, the text id of the code's text, the 5 manufacturer
//                                  bytes as a byte-array parameter)
//   clear(code, register)      -> when the last active error goes: the "no error" emergency (0x0000,
//                                  register); warnings and unknown codes send nothing
//   diag(type, code, text)     -> 0x10F3 message (0xE800 | code << 16, or 0xE000 manufacturer code when
//                                  code is 0) with the text's id, or the text as an ASCII parameter
// Time stamps come from `clock` (DC system time in ns). Nothing allocates; safe inside the drive's cycle.
#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string_view>
#include <vector>

#include "coe/diagnosis.hpp"
#include "coe/emergency.hpp"
#include "od/device.hpp"

namespace coe {

class EventReporter {
  public:
    static constexpr std::size_t kMaxActive = 32;
    static constexpr uint32_t kManufacturerDiagCode = 0x0000E000;

    // history may be null (no 0x10F3); clock may be empty (time stamp 0, flagged as local time).
    EventReporter(Emergency& emergency, DiagnosisHistory* history, std::function<uint64_t()> clock = {});

    // The device's diagnosis texts (od::DeviceDescription::diag_messages, ETG.1020 text ids listed in its
    // ESI's DiagMessages, ETG.2000), copied: a raise() of a code that a text names (error_code) and a diag()
    // whose text is one of them (exact match) are stored with that text id, a diag() without the text
    // parameter, so the master shows the whole text from the ESI instead of what fits into one message. The
    // raise() keeps its manufacturer bytes. Set before the cycle runs (it allocates once, here).
    void set_texts(std::span<const od::DiagMessageText> texts) { texts_.assign(texts.begin(), texts.end()); }

    // `text`: the error's name, if the application has one; the text id of the text that names the code, else
    // of the text equal to `text` (a device from an ESI whose DiagMessages has the error's name), else none.
    void raise(uint16_t error_code, uint8_t error_register, std::span<const uint8_t> mfr,
               std::string_view text = {});
    void clear(uint16_t error_code, uint8_t error_register);
    void diag(DiagType type, uint16_t code, std::string_view text);

    std::size_t active() const { return active_count_; }

  private:
    void record(uint32_t diag_code, DiagType type, std::span<const DiagParam> params, bool may_send_emergency,
                uint16_t text_id = 0);

    Emergency& emergency_;
    DiagnosisHistory* history_;
    std::function<uint64_t()> clock_;
    std::array<uint16_t, kMaxActive> active_{};
    std::size_t active_count_ = 0;
    uint16_t text_id_of(uint16_t error_code) const;
    uint16_t text_id_of(std::string_view text) const;

    std::vector<od::DiagMessageText> texts_;
};

}  // namespace coe
