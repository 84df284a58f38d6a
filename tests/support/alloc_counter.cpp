#include "alloc_counter.hpp"

#include <cstdlib>
#include <new>

namespace {
thread_local bool t_counting = false;
thread_local std::size_t t_count = 0;

void* counted_alloc(std::size_t n) {
  if (t_counting) ++t_count;
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t n) {
  return counted_alloc(n);
}
void* operator new[](std::size_t n) {
  return counted_alloc(n);
}
// The nothrow forms too (libzmq allocates with them): counted like the others, and freed by the
// same operator delete, so a sanitizer sees matching pairs.
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  if (t_counting) ++t_count;
  return std::malloc(n == 0 ? 1 : n);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  if (t_counting) ++t_count;
  return std::malloc(n == 0 ? 1 : n);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}

namespace tactile::testing {
AllocationScope::AllocationScope() {
  t_count = 0;
  t_counting = true;
}
AllocationScope::~AllocationScope() {
  t_counting = false;
}
std::size_t AllocationScope::count() const {
  return t_count;
}
}  // namespace tactile::testing
