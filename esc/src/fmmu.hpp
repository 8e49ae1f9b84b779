#pragma once
// FMMU unit: bit-exact mapping of logical addresses (LRD/LWR/LRW) onto the physical memory
// (ETG.1000.4 and ESC datasheet section I, FMMU; registers 0x0600 + 16n).
#include <array>
#include <cstdint>

#include "esc/wire/datagram.hpp"
#include "memory.hpp"

namespace esc {

// The physical memory as the FMMUs reach it (registers, RAM and SyncManager areas, ECAT side rules).
class PhysicalMemory {
  public:
    // read: inaccessible bytes of dst are left untouched, ok[] (optional) marks accessible bytes.
    // write: bm (optional) is a per-byte bit mask of the bits to write. Both return true if any byte was
    // accessible.
    virtual bool phys_read(uint32_t a, uint8_t* dst, uint8_t* ok, uint32_t n, Side side) = 0;
    virtual bool phys_write(uint32_t a, const uint8_t* src, const uint8_t* bm, uint32_t n, Side side) = 0;

  protected:
    ~PhysicalMemory() = default;
};

struct FmmuMap {
    uint64_t lbit_start = 0;  // first mapped logical bit (absolute bit address)
    uint64_t lbit_end = 0;    // one past the last mapped logical bit
    uint64_t pbit_start = 0;  // physical bit of lbit_start
    bool read = false;
    bool write = false;
};

class Fmmus {
  public:
    Fmmus(const Memory& m, PhysicalMemory& p, uint8_t count) : mem(m), phys(p), count_(count) {}
    // Re-decodes the FMMU registers into the active mappings.
    void rebuild();
    // Executes LRD, LWR or LRW of len bytes at logical address la on data in place.
    // Returns the working-counter increment.
    uint16_t logical(Command cmd, uint32_t la, uint8_t* data, uint16_t len);

  private:
    bool read(const FmmuMap& f, uint64_t b0, uint64_t b1, uint32_t la, uint8_t* data);
    bool write(const FmmuMap& f, uint64_t b0, uint64_t b1, uint32_t la, const uint8_t* data);

    const Memory& mem;
    PhysicalMemory& phys;
    uint8_t count_ = 0;
    std::array<FmmuMap, 16> map_{};
    uint8_t active_ = 0;
    // Per-datagram work areas (no allocation per frame).
    std::array<uint8_t, 2048> scratch_a{}, scratch_b{}, scratch_ok{}, lrw_src{};
};

}  // namespace esc
