// (10) The ESI reader (esi/src/esi_reader.cpp): vendor XML is untrusted. Any bytes: either an EsiFile or a
// std::runtime_error; no entity is expanded, nothing is fetched (no DOCTYPE is accepted), libxml2's depth
// and amplification limits hold. A file read back has at least one device (read_doc refuses none).
#include <stdexcept>
#include <string>

#include "esi/esi_reader.hpp"
#include "fuzz_support.hpp"
#include "harnesses.hpp"

namespace fuzz::esi_reader {

int fuzz_one(const uint8_t* data, std::size_t size) {
    const std::string xml(reinterpret_cast<const char*>(data), size);
    try {
        const esi::EsiFile f = esi::read_esi_text(xml);
        for (const esi::EsiDevice& d : f.devices) {
            (void)d.mailbox_protocols();
            for (const auto& [index, object] : d.objects)
                FUZZ_CHECK(d.object(index) == &object);
        }
    } catch (const std::runtime_error& e) {
        FUZZ_CHECK(e.what() != nullptr);
    }
    return 0;
}

}  // namespace fuzz::esi_reader
