// A grid cell to int hash map and the cell of a coordinate, shared by the voxel cloud and the obstacle
// tracker (private to src/perception/).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

namespace occtrack::perception::detail {

// Open-addressing hash map from a grid cell to an int. Cleared in O(1) by bumping a generation stamp, so a
// scan costs only its own inserts; the table grows (allocates) only when a scan has more points than before.
class CellMap {
 public:
  static std::uint64_t key(std::int64_t ix, std::int64_t iy) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(ix)) << 32) |
           static_cast<std::uint64_t>(static_cast<std::uint32_t>(iy));
  }

  /// Empties the map and makes room for `expected` keys at a load factor of at most 1/2.
  void clear(std::size_t expected) {
    std::size_t capacity = 16;
    int bits = 4;
    while (capacity < 2 * expected) capacity *= 2, ++bits;
    if (capacity > slots_.size()) {
      slots_.assign(capacity, Slot{});
      shift_ = 64 - bits;
      generation_ = 0;
    }
    if (++generation_ == 0) {  // the stamp wrapped: forget every old entry explicitly, once in 2^32 scans
      for (Slot& slot : slots_) slot.generation = 0;
      generation_ = 1;
    }
  }

  /// The value stored for `key`; stores `value` first when the key is absent (*inserted tells which).
  int& find_or_insert(std::uint64_t key, int value, bool* inserted) {
    for (std::size_t i = index(key);; i = (i + 1) & (slots_.size() - 1)) {
      Slot& slot = slots_[i];
      if (slot.generation != generation_) {
        slot = Slot{key, generation_, value};
        *inserted = true;
        return slot.value;
      }
      if (slot.key == key) {
        *inserted = false;
        return slot.value;
      }
    }
  }

  /// The value stored for `key`, or nullptr.
  const int* find(std::uint64_t key) const {
    for (std::size_t i = index(key);; i = (i + 1) & (slots_.size() - 1)) {
      const Slot& slot = slots_[i];
      if (slot.generation != generation_) return nullptr;
      if (slot.key == key) return &slot.value;
    }
  }

 private:
  struct Slot {
    std::uint64_t key = 0;
    std::uint32_t generation = 0;
    int value = 0;
  };
  // Fibonacci hashing: the top bits of key * 2^64 / golden ratio.
  std::size_t index(std::uint64_t key) const {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_);
  }

  std::vector<Slot> slots_;
  std::uint32_t generation_ = 0;
  int shift_ = 60;
};

/// The cell of `coordinate` on a grid of edge `edge` (cells [k edge, (k + 1) edge)).
inline std::int64_t cell_of(double coordinate, double edge) {
  return static_cast<std::int64_t>(std::floor(coordinate / edge));
}

}  // namespace occtrack::perception::detail
