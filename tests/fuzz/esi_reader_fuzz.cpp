// (10) The ESI reader (esi/src/esi_reader.cpp): vendor XML is untrusted. Any bytes: either an EsiFile or a
// std::runtime_error; no entity is expanded, nothing is fetched (no DOCTYPE is accepted), libxml2's depth
// and amplification limits hold. A file read back has at least one device (read_doc refuses none). Every
// device of it then goes through esi::load_product (esi/device): a product whose dictionary builds, or an
// esi::InputError naming the input.
#include <stdexcept>
#include <string>

#include "esi/device/product.hpp"
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
            try {
                const od::Product p = esi::load_product(f, d);
                (void)p.make_dictionary(p.description);
            } catch (const esi::InputError& e) {
                FUZZ_CHECK(std::string(e.what()).rfind("esi.xml", 0) == 0);
            }
        }
    } catch (const std::runtime_error& e) {
        FUZZ_CHECK(e.what() != nullptr);
    }
    return 0;
}

}  // namespace fuzz::esi_reader
