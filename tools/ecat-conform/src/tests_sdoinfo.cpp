#include "testkit.hpp"
namespace conform {
void add_sdoinfo_tests(Catalogue& c) {
    (void)c;
}
}  // namespace conform
