// The libFuzzer entry of one harness: FUZZ_HARNESS names its namespace (see CMakeLists.txt).
#include <cstddef>
#include <cstdint>

#include "harnesses.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
    return fuzz::FUZZ_HARNESS::fuzz_one(data, size);
}
