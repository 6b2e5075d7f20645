#pragma once
/// @file Counts heap allocations, to prove that a loop allocates nothing.
///
/// Linking the `haptel_alloc_counter` library replaces the global operator
/// new with one that counts (a relaxed atomic and a thread-local increment).
/// Only tests and `haptel bench` link it.
#include <cstdint>

namespace haptel::alloc {

/// Allocations made so far by the calling thread.
uint64_t ThreadAllocations();
/// Allocations made so far by all threads.
uint64_t TotalAllocations();

}  // namespace haptel::alloc
