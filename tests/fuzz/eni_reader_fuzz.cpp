// (11) The ENI reader (esi/eni/src/eni_reader.cpp) and the ENI slave -> product conversion: an ENI is
// untrusted XML as an ESI is. Any bytes: either a Config or an EniError; a Config's every slave either
// converts into a product whose dictionary builds, or gives an EniError; nothing is fetched, no entity is
// expanded.
#include <stdexcept>
#include <string>

#include "esi/eni/eni_product.hpp"
#include "esi/eni/eni_reader.hpp"
#include "fuzz_support.hpp"
#include "harnesses.hpp"

namespace fuzz::eni_reader {

int fuzz_one(const uint8_t* data, std::size_t size) {
    const std::string xml(reinterpret_cast<const char*>(data), size);
    esi::eni::Config c;
    try {
        c = esi::eni::read_eni_text(xml, "fuzz.xml");
    } catch (const esi::eni::EniError& e) {
        FUZZ_CHECK(std::string(e.what()).rfind("fuzz.xml", 0) == 0);
        return 0;
    }
    for (std::size_t k = 0; k < c.slaves.size(); ++k) {
        FUZZ_CHECK(c.find_phys_addr(c.slaves[k].info.phys_addr) == static_cast<int>(k));
        try {
            const od::Product p = esi::eni::product_from_eni(c, k);
            const od::Dictionary d = p.make_dictionary(p.description);
            FUZZ_CHECK(d.find(0x1018) != nullptr);
        } catch (const esi::eni::EniError& e) {
            FUZZ_CHECK(std::string(e.what()).rfind("fuzz.xml:", 0) == 0);
        }
    }
    return 0;
}

}  // namespace fuzz::eni_reader
