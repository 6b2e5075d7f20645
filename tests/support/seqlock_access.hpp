#pragma once
// Holds a Seqlock's store half done, as a writer pre-empted mid-store leaves
// it: the sequence number odd and the payload untouched until EndStore.
#include "haptel/core/seqlock.hpp"

namespace haptel {

struct SeqlockTestAccess {
  template <typename T>
  static void BeginStore(Seqlock<T>& lock) {
    lock.seq_.fetch_add(1, std::memory_order_acq_rel);
  }
  template <typename T>
  static void EndStore(Seqlock<T>& lock) {
    lock.seq_.fetch_add(1, std::memory_order_acq_rel);
  }
};

}  // namespace haptel
