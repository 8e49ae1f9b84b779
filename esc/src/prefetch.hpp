#pragma once
// Asking the memory system for cache lines ahead of their use (Esc::prefetch): a hint that changes nothing,
// costs an instruction per line, and lets the misses of the next ESC of a walk overlap with this one's work.
#include <cstddef>
#include <cstdint>

namespace esc {

inline constexpr std::size_t kCacheLine = 64;

// Every cache line of [p, p + n), for writing (the walk writes most of what it reads).
inline void prefetch_lines(const void* p, std::size_t n) {
    const auto* b = static_cast<const char*>(p);
    const auto first = reinterpret_cast<std::uintptr_t>(b) & ~(kCacheLine - 1);
    const auto last = (reinterpret_cast<std::uintptr_t>(b) + (n == 0 ? 0 : n - 1)) & ~(kCacheLine - 1);
    for (std::uintptr_t a = first; a <= last; a += kCacheLine)
        __builtin_prefetch(b + (a - reinterpret_cast<std::uintptr_t>(b)), 1, 3);
}

}  // namespace esc
