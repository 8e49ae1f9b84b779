#pragma once
// Little-endian field access for CoE frames (internal).
#include <cstddef>
#include <cstdint>
#include <span>

namespace coe::wire {

inline uint16_t get16(std::span<const uint8_t> b, std::size_t at) {
    return static_cast<uint16_t>(b[at] | (b[at + 1] << 8));
}
inline uint32_t get32(std::span<const uint8_t> b, std::size_t at) {
    return static_cast<uint32_t>(b[at]) | (static_cast<uint32_t>(b[at + 1]) << 8) |
           (static_cast<uint32_t>(b[at + 2]) << 16) | (static_cast<uint32_t>(b[at + 3]) << 24);
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

// CoE header (2 bytes): bits 8:0 number, bits 15:12 service.
enum class Service : uint8_t {
    Emergency = 1,
    SdoRequest = 2,
    SdoResponse = 3,
    TxPdo = 4,
    RxPdo = 5,
    TxPdoRemote = 6,
    RxPdoRemote = 7,
    SdoInfo = 8,
};
inline void put_coe_header(uint8_t* p, Service s, uint16_t number = 0) {
    put16(p, static_cast<uint16_t>((number & 0x01FF) | (static_cast<uint16_t>(s) << 12)));
}

}  // namespace coe::wire
