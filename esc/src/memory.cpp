// The ESC's memory unit (memory.hpp).
#include "memory.hpp"

namespace esc {

Memory::Memory(uint32_t ram_kib) : ram(ram_kib * 1024, 0), ram_end(reg::kRamBase + ram_kib * 1024) {}

}  // namespace esc
