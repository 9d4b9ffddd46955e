#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace sdf_tracker {

/// An owning hash table from 64-bit keys to heap objects, laid out for lookups in the tracker's
/// inner loop: open addressing with linear probing over one flat array of (key, pointer) slots, a
/// power-of-two capacity kept at most half full, Fibonacci hashing. A lookup costs a multiply, a
/// shift and usually one cache line, where std::unordered_map costs a division and two pointer
/// chases. Removal shifts the following slots back, so no tombstones accumulate. Pointers to the
/// values stay valid until their key is removed; growing moves only the slots.
template <typename Value>
class BlockTable {
 public:
  BlockTable() = default;
  BlockTable(const BlockTable& other) { *this = other; }
  BlockTable& operator=(const BlockTable& other) {
    if (this == &other) return *this;
    clear();
    reserve(other.size_);
    other.forEach([this](uint64_t key, const Value& value) { insert(key, std::make_unique<Value>(value)); });
    return *this;
  }
  BlockTable(BlockTable&& other) noexcept { *this = std::move(other); }
  BlockTable& operator=(BlockTable&& other) noexcept {
    slots_ = std::move(other.slots_);
    size_ = other.size_;
    shift_ = other.shift_;
    other.clear();
    return *this;
  }

  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  /// Slots allocated (for memory accounting).
  size_t capacity() const { return slots_.size(); }
  static constexpr size_t slotBytes() { return sizeof(Slot); }

  const Value* find(uint64_t key) const {
    if (size_ == 0) return nullptr;
    for (size_t i = home(key);; i = next(i)) {
      const Slot& slot = slots_[i];
      if (!slot.value) return nullptr;
      if (slot.key == key) return slot.value.get();
    }
  }
  Value* find(uint64_t key) { return const_cast<Value*>(static_cast<const BlockTable*>(this)->find(key)); }

  /// The value under key; made by make() when there was none.
  template <typename Make>
  Value& findOrInsert(uint64_t key, Make&& make) {
    if (Value* value = find(key)) return *value;
    return insert(key, make());
  }

  /// Removes the key and its value; false when it was not there.
  bool erase(uint64_t key) {
    if (size_ == 0) return false;
    size_t hole = home(key);
    for (;; hole = next(hole)) {
      if (!slots_[hole].value) return false;
      if (slots_[hole].key == key) break;
    }
    slots_[hole].value.reset();
    --size_;
    // Move back every following slot of the run whose home does not lie cyclically in (hole, i].
    for (size_t i = next(hole); slots_[i].value; i = next(i)) {
      const size_t h = home(slots_[i].key);
      const bool home_after_hole = hole <= i ? (hole < h && h <= i) : (hole < h || h <= i);
      if (home_after_hole) continue;
      slots_[hole] = std::move(slots_[i]);
      hole = i;
    }
    return true;
  }

  void clear() {
    slots_.clear();
    size_ = 0;
    shift_ = 64;
  }

  /// Room for n keys without growing.
  void reserve(size_t n) {
    size_t capacity = kMinCapacity;
    while (capacity < 2 * n) capacity *= 2;
    if (capacity > slots_.size()) rehash(capacity);
  }

  /// Calls fn(key, value) for every entry, in no particular order.
  template <typename Fn>
  void forEach(Fn&& fn) {
    for (Slot& slot : slots_) {
      if (slot.value) fn(slot.key, *slot.value);
    }
  }
  template <typename Fn>
  void forEach(Fn&& fn) const {
    for (const Slot& slot : slots_) {
      if (slot.value) fn(slot.key, static_cast<const Value&>(*slot.value));
    }
  }

 private:
  struct Slot {
    uint64_t key = 0;
    std::unique_ptr<Value> value;  ///< null: the slot is free
  };
  static constexpr size_t kMinCapacity = 64;

  size_t home(uint64_t key) const { return static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_); }
  size_t next(size_t i) const { return (i + 1) & (slots_.size() - 1); }

  Value& insert(uint64_t key, std::unique_ptr<Value> value) {
    if (2 * (size_ + 1) > slots_.size()) rehash(slots_.empty() ? kMinCapacity : 2 * slots_.size());
    size_t i = home(key);
    while (slots_[i].value) i = next(i);
    slots_[i].key = key;
    slots_[i].value = std::move(value);
    ++size_;
    return *slots_[i].value;
  }

  void rehash(size_t capacity) {
    std::vector<Slot> old(capacity);
    old.swap(slots_);
    shift_ = 64;
    for (size_t c = capacity; c > 1; c >>= 1) --shift_;
    for (Slot& slot : old) {
      if (!slot.value) continue;
      size_t i = home(slot.key);
      while (slots_[i].value) i = next(i);
      slots_[i] = std::move(slot);
    }
  }

  std::vector<Slot> slots_;
  size_t size_ = 0;
  int shift_ = 64;  ///< 64 - log2(capacity): home() keeps the hash's top bits
};

}  // namespace sdf_tracker
