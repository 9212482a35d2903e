#pragma once
// Fixed-capacity map from agent id to a dense slot, open addressing with linear probing and
// backward-shift deletion: no allocation after construction, O(1) per look-up.

#include <cstdint>
#include <vector>

namespace gk {

class IdSlotMap {
 public:
  explicit IdSlotMap(size_t capacity = 0) { reset(capacity); }
  void reset(size_t capacity) {
    size_t n = 16;
    while (n < 2 * capacity + 1) n *= 2;
    keys_.assign(n, kEmpty);
    slots_.assign(n, -1);
    mask_ = n - 1;
    free_.clear();
    for (size_t i = capacity; i-- > 0;) free_.push_back(static_cast<int32_t>(i));
    size_ = 0;
  }
  // Slot of id, or -1.
  int32_t find(uint32_t id) const {
    for (size_t i = hash(id);; i = (i + 1) & mask_) {
      if (keys_[i] == kEmpty) return -1;
      if (keys_[i] == id) return slots_[i];
    }
  }
  // Slot of id, taking a free one when new (*created = true); -1 when full.
  int32_t insert(uint32_t id, bool* created) {
    *created = false;
    size_t i = hash(id);
    for (;; i = (i + 1) & mask_) {
      if (keys_[i] == kEmpty) break;
      if (keys_[i] == id) return slots_[i];
    }
    if (free_.empty()) return -1;
    keys_[i] = id;
    slots_[i] = free_.back();
    free_.pop_back();
    ++size_;
    *created = true;
    return slots_[i];
  }
  void erase(uint32_t id) {
    size_t i = hash(id);
    for (;; i = (i + 1) & mask_) {
      if (keys_[i] == kEmpty) return;
      if (keys_[i] == id) break;
    }
    free_.push_back(slots_[i]);
    --size_;
    // Backward-shift the following cluster so look-ups never stop early.
    size_t j = i;
    for (;;) {
      j = (j + 1) & mask_;
      if (keys_[j] == kEmpty) break;
      const size_t home = hash(keys_[j]);
      const bool movable = (j > i) ? (home <= i || home > j) : (home <= i && home > j);
      if (movable) {
        keys_[i] = keys_[j];
        slots_[i] = slots_[j];
        i = j;
      }
    }
    keys_[i] = kEmpty;
    slots_[i] = -1;
  }
  size_t size() const { return size_; }
  // Visits every (id, slot).
  template <typename F>
  void for_each(F&& f) const {
    for (size_t i = 0; i < keys_.size(); ++i) {
      if (keys_[i] != kEmpty) f(keys_[i], slots_[i]);
    }
  }

 private:
  static constexpr uint32_t kEmpty = 0xffffffffu;
  size_t hash(uint32_t id) const { return (id * 2654435761u) & mask_; }
  std::vector<uint32_t> keys_;
  std::vector<int32_t> slots_;
  std::vector<int32_t> free_;
  size_t mask_ = 0;
  size_t size_ = 0;
};

}  // namespace gk
