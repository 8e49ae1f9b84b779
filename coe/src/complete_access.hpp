#pragma once
// Complete access (ETG.1000.6): a whole object as one byte image. Subindex 0 occupies 16 bits (8-bit value +
// 8-bit padding), entries follow packed at their bit lengths, entries of 8 bits and more start on a byte
// boundary (docs/decisions/coe.md "Complete access layout").
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "od/dictionary.hpp"

namespace coe::ca {

// Entries of an ARRAY are limited to its current subindex-0 value; a RECORD always shows all declared
// entries.
uint8_t upload_last_subindex(const od::Dictionary& dict, const od::Object& obj);

// Bytes of the image from subindex `first` (0 or 1) up to and including subindex `last`.
std::size_t image_size(const od::Object& obj, uint8_t first, uint8_t last);

// Largest image this object can produce (all declared entries, from subindex 0).
std::size_t max_image_size(const od::Object& obj);

// Reads the image into out (sized at least image_size); scratch must hold the largest single entry.
// size receives the image length.
od::Status upload(od::Dictionary& dict, const od::Object& obj, uint8_t first, od::AlState state,
                  std::span<uint8_t> out, std::size_t& size, std::span<uint8_t> scratch);

// Writes an image: subindex 0 is set to 0 first, then the entries, then subindex 0 to its new value, as
// masters do it by hand. On failure every touched entry gets its old value back. rollback is working
// memory (reserved by the caller, so this allocates nothing once warm); scratch as for upload.
od::Status download(od::Dictionary& dict, const od::Object& obj, uint8_t first, od::AlState state,
                    std::span<const uint8_t> data, std::vector<uint8_t>& rollback,
                    std::span<uint8_t> scratch);

}  // namespace coe::ca
