// SPDX-License-Identifier: BSD-3-Clause
// SlotCache: one value (a vector of floats) per slot, kept with the key it was made for, within a
// budget of bytes. A run's writer keeps each block's decoded model in it from one step to the
// next: a block that refers to the step before keeps the same payload (the same key), and its
// model is copied out instead of decoded again.
//
// Threads may use different slots at once (each slot has its own lock); the budget is shared: a
// value that would take the cache over it is not kept (the caller decodes it again next time).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

namespace afam {

class SlotCache {
 public:
  /// Empties the cache and gives it `slots` slots and at most `budgetBytes` bytes of values in
  /// all. Not while another thread uses it.
  void reset(size_t slots, size_t budgetBytes) {
    slots_ = std::make_unique<Slot[]>(slots);
    count_ = slots;
    budget_ = budgetBytes;
    bytes_.store(0, std::memory_order_relaxed);
  }

  size_t slots() const { return count_; }
  size_t bytes() const { return bytes_.load(std::memory_order_relaxed); }

  /// Copies slot's value into `out` when it was made for `key`; false otherwise.
  bool find(size_t slot, uint64_t key, std::vector<float>& out) const {
    Slot& s = at(slot);
    std::lock_guard<std::mutex> lock(s.mutex);
    if (!s.held || s.key != key) return false;
    out.assign(s.value.begin(), s.value.end());
    return true;
  }

  /// Keeps `value` for `key` in the slot (dropping what it held) when the budget has room for it.
  void put(size_t slot, uint64_t key, const std::vector<float>& value) {
    Slot& s = at(slot);
    std::lock_guard<std::mutex> lock(s.mutex);
    release(s);
    const size_t need = value.size() * sizeof(float);
    size_t used = bytes_.load(std::memory_order_relaxed);
    do {
      if (need > budget_ || used > budget_ - need) return;
    } while (!bytes_.compare_exchange_weak(used, used + need, std::memory_order_relaxed));
    s.value.assign(value.begin(), value.end());
    s.key = key;
    s.held = true;
  }

 private:
  struct Slot {
    std::mutex mutex;
    bool held = false;
    uint64_t key = 0;
    std::vector<float> value;
  };
  Slot& at(size_t slot) const { return slots_[slot]; }
  void release(Slot& s) {
    if (!s.held) return;
    bytes_.fetch_sub(s.value.size() * sizeof(float), std::memory_order_relaxed);
    s.held = false;
    std::vector<float>().swap(s.value);
  }

  std::unique_ptr<Slot[]> slots_;
  size_t count_ = 0, budget_ = 0;
  std::atomic<size_t> bytes_{0};
};

}  // namespace afam
