#include "od/diag_texts.hpp"

namespace od {

std::span<const DiagText> drive_diag_texts() {
    return kDriveDiagTexts;
}

uint16_t diag_text_id(std::string_view text) {
    for (const DiagText& t : kDriveDiagTexts)
        if (t.text == text) return t.id;
    return 0;
}

std::string_view diag_text(uint16_t id) {
    return diag_text_of(id);
}

}  // namespace od
