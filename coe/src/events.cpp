#include "coe/events.hpp"

#include <algorithm>

namespace coe {

EventReporter::EventReporter(Emergency& emergency, DiagnosisHistory* history, std::function<uint64_t()> clock)
    : emergency_(emergency), history_(history), clock_(std::move(clock)) {}

uint16_t EventReporter::text_id_of(uint16_t error_code) const {
    for (const od::DiagMessageText& t : texts_)
        if (t.error_code == error_code && t.error_code != 0) return t.text_id;
    return 0;
}

uint16_t EventReporter::text_id_of(std::string_view text) const {
    for (const od::DiagMessageText& t : texts_)
        if (t.text == text) return t.text_id;
    return 0;
}

void EventReporter::record(uint32_t diag_code, DiagType type, std::span<const DiagParam> params,
                           bool may_send_emergency, uint16_t text_id) {
    if (history_ == nullptr) return;
    DiagMessage m;
    m.code = diag_code;
    m.type = type;
    m.text_id = text_id;
    m.timestamp_ns = clock_ ? clock_() : 0;
    m.local_time = !clock_;
    m.params = params;
    history_->add(m, may_send_emergency);
}

void EventReporter::raise(uint16_t error_code, uint8_t error_register, std::span<const uint8_t> mfr,
                          std::string_view text) {
    const auto begin = active_.begin();
    const auto end = begin + static_cast<std::ptrdiff_t>(active_count_);
    if (std::find(begin, end, error_code) == end && active_count_ < kMaxActive)
        active_[active_count_++] = error_code;
    emergency_.send(error_code, error_register, mfr);
    const DiagParam params[] = {DiagParam::byte_array(mfr.first(std::min<std::size_t>(mfr.size(), 5)))};
    // The emergency for an error is sent above already: the history must not send a second one.
    uint16_t id = text_id_of(error_code);
    if (id == 0 && !text.empty()) id = text_id_of(text);
    record(DiagnosisHistory::from_emergency(error_code), DiagType::Error, params, false, id);
}

void EventReporter::clear(uint16_t error_code, uint8_t error_register) {
    const auto begin = active_.begin();
    const auto end = begin + static_cast<std::ptrdiff_t>(active_count_);
    const auto it = std::find(begin, end, error_code);
    if (it == end) return;  // a warning or an unknown code: no emergency was sent for it
    std::copy(it + 1, end, it);
    --active_count_;
    if (active_count_ == 0) emergency_.send(0x0000, error_register, {});
}

void EventReporter::diag(DiagType type, uint16_t code, std::string_view text) {
    const uint16_t id = text.empty() ? 0 : text_id_of(text);
    if (id != 0) {
        record(code == 0 ? kManufacturerDiagCode : DiagnosisHistory::from_emergency(code), type, {}, true,
               id);
        return;
    }
    const DiagParam params[] = {DiagParam::ascii(text)};
    record(code == 0 ? kManufacturerDiagCode : DiagnosisHistory::from_emergency(code), type,
           text.empty() ? std::span<const DiagParam>{} : std::span<const DiagParam>(params), true);
}

}  // namespace coe
