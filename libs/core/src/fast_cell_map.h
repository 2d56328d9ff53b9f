// Private to the fast paths: integer lattice keys and an open-addressing hash map from a key
// to a dense index.
//
// std::unordered_map allocates a node per entry and chases a pointer per lookup; the fast
// paths look up a key per point, so they use a flat table with linear probing instead (keys
// and values in one array, load factor <= 1/2). Keys pack three signed 21-bit cell coordinates.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace upd::detail {

constexpr std::uint32_t kNoIndex = 0xffffffffu;
constexpr std::int64_t kKeyBias = std::int64_t(1) << 20;  ///< coordinates in [-2^20, 2^20)

/// True when every coordinate fits the 21-bit key.
inline bool keyFits(std::int64_t x, std::int64_t y, std::int64_t z) {
  return x >= -kKeyBias && x < kKeyBias && y >= -kKeyBias && y < kKeyBias && z >= -kKeyBias &&
         z < kKeyBias;
}

inline std::uint64_t packKey(std::int64_t x, std::int64_t y, std::int64_t z) {
  return static_cast<std::uint64_t>(x + kKeyBias) |
         (static_cast<std::uint64_t>(y + kKeyBias) << 21) |
         (static_cast<std::uint64_t>(z + kKeyBias) << 42);
}

/// Floor division for possibly negative lattice coordinates.
inline std::int32_t floorDiv(std::int32_t a, std::int32_t b) {
  const std::int32_t q = a / b;
  return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

class CellMap {
 public:
  explicit CellMap(std::size_t expected = 64) { rehash(capacityFor(expected)); }

  std::size_t size() const { return size_; }

  /// The index stored for key, or kNoIndex.
  std::uint32_t find(std::uint64_t key) const {
    std::size_t slot = hash(key);
    while (true) {
      const Entry& e = table_[slot];
      if (e.value == kNoIndex) return kNoIndex;
      if (e.key == key) return e.value;
      slot = (slot + 1) & mask_;
    }
  }

  /// The index stored for key; when absent, stores size() (the next dense index) and sets
  /// inserted.
  std::uint32_t findOrInsert(std::uint64_t key, bool& inserted) {
    std::size_t slot = hash(key);
    while (true) {
      Entry& e = table_[slot];
      if (e.value == kNoIndex) break;
      if (e.key == key) {
        inserted = false;
        return e.value;
      }
      slot = (slot + 1) & mask_;
    }
    inserted = true;
    const auto value = static_cast<std::uint32_t>(size_);
    table_[slot] = {key, value};
    if (++size_ * 2 > table_.size()) rehash(table_.size() * 2);
    return value;
  }

 private:
  struct Entry {
    std::uint64_t key = 0;
    std::uint32_t value = kNoIndex;
  };
  static std::size_t capacityFor(std::size_t n) {
    std::size_t c = 64;
    while (c < 2 * n + 2) c *= 2;
    return c;
  }
  std::size_t hash(std::uint64_t key) const {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_);
  }
  void rehash(std::size_t capacity) {
    std::vector<Entry> old;
    old.swap(table_);
    table_.assign(capacity, Entry{});
    mask_ = capacity - 1;
    int bits = 0;
    while ((std::size_t(1) << bits) < capacity) ++bits;
    shift_ = 64 - bits;
    for (const Entry& e : old) {
      if (e.value == kNoIndex) continue;
      std::size_t slot = hash(e.key);
      while (table_[slot].value != kNoIndex) slot = (slot + 1) & mask_;
      table_[slot] = e;
    }
  }

  std::vector<Entry> table_;
  std::size_t mask_ = 0;
  int shift_ = 58;
  std::size_t size_ = 0;
};

}  // namespace upd::detail
