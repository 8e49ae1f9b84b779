#pragma once
// Asking the memory system for cache lines ahead of their use (Esc::prefetch): a hint that changes nothing,
// costs an instruction per line, and lets the misses of the next ESC of a walk overlap with this one's work.
#include <cstddef>
#include <cstdint>

namespace esc {

inline constexpr std::size_t kCacheLine = 64;

// Every cache line of [p, p + n), for writing (the walk writes most of what it reads). The line addresses
// are integers made pointers, never pointer arithmetic: the first line may start before p, and a pointer
// moved outside its object is undefined behaviour (UBSan's pointer-overflow check) even if never read.
inline void prefetch_lines(const void* p, std::size_t n) {
    const auto begin = reinterpret_cast<std::uintptr_t>(p);
    const auto first = begin & ~(kCacheLine - 1);
    const auto last = (begin + (n == 0 ? 0 : n - 1)) & ~(kCacheLine - 1);
    for (std::uintptr_t a = first; a <= last; a += kCacheLine)
        __builtin_prefetch(reinterpret_cast<const void*>(a), 1, 3);
}

}  // namespace esc
