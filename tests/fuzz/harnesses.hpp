#pragma once
// Every fuzz harness of the tree: one function per harness (tests/fuzz/<name>_fuzz.cpp), what it feeds and
// where. docs/robustness.md describes the input formats, the seed corpora and how to run them.
#include <cstddef>
#include <cstdint>

// X(name): the list the replay test and the CMake targets follow.
#define SOFTECAT_FUZZ_HARNESSES(X) \
    X(esc_frame)                   \
    X(slave)                       \
    X(coe_mailbox)                 \
    X(foe_server)                  \
    X(sii)                         \
    X(device_config)               \
    X(loaders)                     \
    X(master_reply)                \
    X(control)                     \
    X(topology)                    \
    X(esi_reader)                  \
    X(eni_reader)                  \
    X(esi_line)

#define SOFTECAT_FUZZ_DECLARE(name)                      \
    namespace fuzz::name {                               \
    int fuzz_one(const uint8_t* data, std::size_t size); \
    }
SOFTECAT_FUZZ_HARNESSES(SOFTECAT_FUZZ_DECLARE)
#undef SOFTECAT_FUZZ_DECLARE
