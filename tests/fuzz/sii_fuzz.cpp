// (5) The SII parser and decoder (esi/src/sii.cpp, decode side): any image, as a master reads it from an
// unknown slave or as `ecat-slave --eeprom` is given one. The contract: never throws, never reads outside the
// span, and the decoded text covers every category found.
#include <span>
#include <string>

#include "esi/sii.hpp"
#include "fuzz_support.hpp"
#include "harnesses.hpp"

namespace fuzz::sii {

int fuzz_one(const uint8_t* data, std::size_t size) {
    const std::span<const uint8_t> image(data, size);
    const esi::SiiInfo info = esi::parse_sii(image);
    FUZZ_CHECK(info.image_bytes == size);
    for (const esi::SiiCategory& c : info.categories)
        FUZZ_CHECK(c.word_offset * 2 < size);
    // Every string index the image can name resolves to a string or to "".
    for (unsigned i = 0; i < 256; ++i)
        (void)info.string_at(static_cast<uint8_t>(i));
    const std::string text = esi::decode_sii(image);
    FUZZ_CHECK(!text.empty());
    return 0;
}

}  // namespace fuzz::sii
