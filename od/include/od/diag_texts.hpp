#pragma once
// The texts of the drive's diagnosis messages (0x10F3, ETG.1020), declared once: the drive's event glue puts
// the text id into each message it knows here instead of the text (a 32-byte message has room for 14
// characters of text), the ESI lists them as DiagMessages (ETG.2000) so a configuration tool shows the whole
// text, and ecatctl diag names them. Ids are the device's own (ETG.2000: TextId of a DiagMessage).
#include <cstdint>
#include <span>
#include <string_view>

#include "od/wire/diag_text_table.hpp"

namespace od {

// Every text the drive (drive/) emits as a diagnosis message without an error code: the CiA 402 states it
// enters, homing progress, a refused fault reset.
std::span<const DiagText> drive_diag_texts();
// The id of a text (exact match); 0 if it has none.
uint16_t diag_text_id(std::string_view text);
// The text of an id; empty if the id is unknown.
std::string_view diag_text(uint16_t id);

}  // namespace od
