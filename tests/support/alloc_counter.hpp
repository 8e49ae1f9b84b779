// Allocation counting for the "hot paths allocate nothing" tests. alloc_counter.cpp replaces the global
// operator new/delete with malloc/free and counts every operator new call; it is the one replacement in a
// test binary (the test_alloc_counter OBJECT library in tests/CMakeLists.txt, linked once per executable).
#pragma once

#include <cstdint>

namespace alloc_counter {

// Calls of the global operator new (single and array) since the program started, from any thread.
std::uint64_t total();

// Counts the allocations made while it lives: count() is the number since construction.
class Scope {
  public:
    Scope() : start_(total()) {}
    std::uint64_t count() const { return total() - start_; }

  private:
    std::uint64_t start_;
};

}  // namespace alloc_counter
