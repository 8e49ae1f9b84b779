#pragma once
// The Process Data Interface: the only way the slave stack (firmware) reaches the ESC, as on silicon.
// Reads and writes have the side effects a real ESC gives PDI accesses (reading AL control clears the
// AL event, reading the last byte of a SyncManager buffer releases it, and so on).
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

namespace esc {

class Pdi {
  public:
    virtual ~Pdi() = default;
    virtual void read(uint16_t address, std::span<uint8_t> out) = 0;
    virtual void write(uint16_t address, std::span<const uint8_t> in) = 0;

    // Little-endian register helpers.
    template <typename T>
    T read_reg(uint16_t address) {
        uint8_t b[sizeof(T)];
        read(address, b);
        T v{};
        for (std::size_t i = 0; i < sizeof(T); ++i)
            v = static_cast<T>(v | (static_cast<T>(b[i]) << (8 * i)));
        return v;
    }
    template <typename T>
    void write_reg(uint16_t address, T value) {
        uint8_t b[sizeof(T)];
        for (std::size_t i = 0; i < sizeof(T); ++i)
            b[i] = static_cast<uint8_t>(static_cast<uint64_t>(value) >> (8 * i));
        write(address, b);
    }
};

}  // namespace esc
