#pragma once
// Counts the heap allocations made by the calling thread, for the tests that check that a hot
// loop (the haptic step) allocates nothing (CONVENTIONS.md):
//
//   { AllocationCounter counter;  ...code...;  EXPECT_EQ(counter.count(), 0); }
//
// Linking tests/allocation_counter.cc into a test executable replaces the global operator new
// and delete in every form (plain, array, nothrow, sized, aligned) and, on glibc, interposes
// malloc, calloc, realloc, aligned_alloc, posix_memalign and memalign, because Eigen allocates
// with std::malloc, not operator new. Link it only into the tests that use it
// (hapsim_add_test(name test.cc allocation_counter.cc)).
//
// Under a sanitizer the sanitizer owns the allocator and the replacement is compiled out:
// AllocationCounter::enabled() is then false and count() stays 0, so tests should skip their
// allocation checks (GTEST_SKIP) rather than pass vacuously.

#include <cstdint>

namespace hapsim {

class AllocationCounter {
 public:
  AllocationCounter();
  // Allocations by this thread since construction (or the last Reset).
  std::int64_t count() const;
  void Reset();
  // Whether allocations are counted in this build.
  static bool enabled();

 private:
  std::int64_t start_;
};

}  // namespace hapsim
