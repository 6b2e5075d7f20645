#pragma once
/// @file Tests' view of the allocation counter (haptel/core/alloc_counter.hpp).
#include "haptel/core/alloc_counter.hpp"

namespace haptel::test {
using haptel::alloc::ThreadAllocations;
using haptel::alloc::TotalAllocations;
}  // namespace haptel::test
