#pragma once
/// @file Counts heap allocations made by the calling thread, for tests that
/// prove a loop allocates nothing. Linking haptel_test_support replaces the
/// global operator new with a counting one.
#include <cstdint>

namespace haptel::test {

/// Allocations made so far by the calling thread.
uint64_t ThreadAllocations();
/// Allocations made so far by all threads.
uint64_t TotalAllocations();

}  // namespace haptel::test
