#pragma once
// Little-endian field access: EtherCAT, CoE, FoE, the SII and the project's own file formats store every
// multi-byte value least significant byte first (ETG.1000.4 §5.3 "transfer syntax"). One set of helpers
// for all of them; nothing here allocates except the vector appenders.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace util {

// ---- raw pointers (the caller checked the length) ----
inline uint16_t get16(const uint8_t* p) {
    return static_cast<uint16_t>(p[0] | (p[1] << 8));
}
inline uint32_t get32(const uint8_t* p) {
    return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
           (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}
inline uint64_t get64(const uint8_t* p) {
    return static_cast<uint64_t>(get32(p)) | (static_cast<uint64_t>(get32(p + 4)) << 32);
}
// The low n bytes (n <= 8) as an unsigned value.
inline uint64_t get_n(const uint8_t* p, std::size_t n) {
    uint64_t v = 0;
    for (std::size_t i = 0; i < n; ++i)
        v |= static_cast<uint64_t>(p[i]) << (8 * i);
    return v;
}
inline void put16(uint8_t* p, uint16_t v) {
    p[0] = static_cast<uint8_t>(v);
    p[1] = static_cast<uint8_t>(v >> 8);
}
inline void put32(uint8_t* p, uint32_t v) {
    for (int i = 0; i < 4; ++i)
        p[i] = static_cast<uint8_t>(v >> (8 * i));
}
inline void put64(uint8_t* p, uint64_t v) {
    for (int i = 0; i < 8; ++i)
        p[i] = static_cast<uint8_t>(v >> (8 * i));
}
// The low n bytes (n <= 8) of v.
inline void put_n(uint8_t* p, uint64_t v, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i)
        p[i] = static_cast<uint8_t>(v >> (8 * i));
}

// ---- spans with an offset (the caller checked the length) ----
inline uint16_t get16(std::span<const uint8_t> b, std::size_t at) {
    return get16(b.data() + at);
}
inline uint32_t get32(std::span<const uint8_t> b, std::size_t at) {
    return get32(b.data() + at);
}
inline uint64_t get64(std::span<const uint8_t> b, std::size_t at) {
    return get64(b.data() + at);
}
inline void put16(std::span<uint8_t> b, std::size_t at, uint16_t v) {
    put16(b.data() + at, v);
}
inline void put32(std::span<uint8_t> b, std::size_t at, uint32_t v) {
    put32(b.data() + at, v);
}
inline void put64(std::span<uint8_t> b, std::size_t at, uint64_t v) {
    put64(b.data() + at, v);
}

// ---- appending to a byte vector (builders of images, files and test frames) ----
inline void append16(std::vector<uint8_t>& b, uint16_t v) {
    b.push_back(static_cast<uint8_t>(v));
    b.push_back(static_cast<uint8_t>(v >> 8));
}
inline void append32(std::vector<uint8_t>& b, uint32_t v) {
    for (int i = 0; i < 4; ++i)
        b.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
inline void append64(std::vector<uint8_t>& b, uint64_t v) {
    for (int i = 0; i < 8; ++i)
        b.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
// The low n bytes of v as a new vector.
inline std::vector<uint8_t> le_bytes(uint64_t v, std::size_t n) {
    std::vector<uint8_t> b(n);
    put_n(b.data(), v, n);
    return b;
}

}  // namespace util
