#pragma once

// Counts heap allocations made by the calling thread while a Scope is alive. Link
// tactile::alloc_counter into a test executable of its own: it replaces global operator new.
#include <cstddef>

namespace tactile::testing {

class AllocationScope {
 public:
  AllocationScope();
  ~AllocationScope();
  AllocationScope(const AllocationScope&) = delete;
  AllocationScope& operator=(const AllocationScope&) = delete;
  std::size_t count() const;
};

}  // namespace tactile::testing
