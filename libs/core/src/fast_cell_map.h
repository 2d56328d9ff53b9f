// Private to libs/core: integer lattice keys, an open-addressing hash map from a key to a dense
// index, and on it the one way the core bins points into cubic cells (CellGrid, binCells,
// listByCell), shared by the fast UPD's lattice, the grid normals, the voxel filter and the
// outlier filter's grid.
//
// std::unordered_map allocates a node per entry and chases a pointer per lookup; the fast
// paths look up a key per point, so they use a flat table with linear probing instead (keys
// and values in one array, load factor <= 1/2). Keys pack three signed 21-bit cell coordinates.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <initializer_list>
#include <string>
#include <vector>

namespace upd::core::detail {

constexpr std::uint32_t kNoIndex = 0xffffffffu;
constexpr std::int64_t kKeyBias = std::int64_t(1) << 20;  ///< coordinates in [-2^20, 2^20)

/// True when every coordinate fits the 21-bit key.
inline bool keyFits(std::int64_t x, std::int64_t y, std::int64_t z) {
  return x >= -kKeyBias && x < kKeyBias && y >= -kKeyBias && y < kKeyBias && z >= -kKeyBias &&
         z < kKeyBias;
}

/// True when every cell within Chebyshev distance margin of (x, y, z) fits the key.
inline bool keyFitsAround(const std::int32_t* xyz, std::int32_t margin) {
  return keyFits(std::int64_t{xyz[0]} - margin, std::int64_t{xyz[1]} - margin,
                 std::int64_t{xyz[2]} - margin) &&
         keyFits(std::int64_t{xyz[0]} + margin, std::int64_t{xyz[1]} + margin,
                 std::int64_t{xyz[2]} + margin);
}

/// Writes v to the 8 floats from each of ox, oy and oz (a run's padding): three 8-float moves
/// instead of a scalar loop (the three rows may alias as far as the compiler knows).
inline void fillEight(float v, float* ox, float* oy, float* oz) {
  const float e[8] = {v, v, v, v, v, v, v, v};
  std::memcpy(ox, e, sizeof e), std::memcpy(oy, e, sizeof e), std::memcpy(oz, e, sizeof e);
}

/// Copies the points [b, e) of coordinate rows (x, y, z), sorted by cell, to (ox, oy, oz), 8 at
/// a time: up to 7 values past e are read (the rows have that slack) and written (the caller
/// overwrites them: the next run or its padding).
inline void copyRunByEights(const float* x, const float* y, const float* z, std::uint32_t b,
                            std::uint32_t e, float* ox, float* oy, float* oz) {
  for (std::uint32_t t = b; t < e; t += 8) {
    const std::size_t o = t - b;
    std::memcpy(ox + o, x + t, sizeof(float) * 8);
    std::memcpy(oy + o, y + t, sizeof(float) * 8);
    std::memcpy(oz + o, z + t, sizeof(float) * 8);
  }
}

inline std::uint64_t packKey(std::int64_t x, std::int64_t y, std::int64_t z) {
  return static_cast<std::uint64_t>(x + kKeyBias) |
         (static_cast<std::uint64_t>(y + kKeyBias) << 21) |
         (static_cast<std::uint64_t>(z + kKeyBias) << 42);
}

/// What packKey(x + dx, y + dy, z + dz) adds to packKey(x, y, z) where both fit the key (each
/// 21-bit field stays within its bits: the sum carries into no other field).
inline std::uint64_t keyOffset(std::int64_t dx, std::int64_t dy, std::int64_t dz) {
  return static_cast<std::uint64_t>(dx + dy * (std::int64_t(1) << 21) +
                                    dz * (std::int64_t(1) << 42));
}

/// floor(a / b) of possibly negative lattice coordinates for a fixed divisor b > 0, without an
/// integer division: floor((a + 0.5) / b) in double, which lies 0.5 / b or more from a whole
/// number, far more than the product's rounding.
class FloorDivider {
 public:
  explicit FloorDivider(std::int32_t b) : inv_(1.0 / b) {}
  std::int32_t operator()(std::int32_t a) const {
    const double t = (a + 0.5) * inv_;
    return static_cast<std::int32_t>(t) - (t < 0 ? 1 : 0);
  }

 private:
  double inv_;
};

/// Coordinate a of corner o of the cell at xyz (the 8 corners: +1 along axis a where bit a of o
/// is set).
inline std::int32_t cornerCoord(const std::int32_t* xyz, int o, int a) {
  return xyz[a] + ((o >> a) & 1);
}

class CellMap {
 public:
  explicit CellMap(std::size_t expected = 64) { rehash(capacityFor(expected)); }

  std::size_t size() const { return size_; }

  /// Empties the map for about `expected` keys, keeping its table when that has the size.
  void clear(std::size_t expected) {
    const std::size_t capacity = capacityFor(expected);
    size_ = 0;
    if (table_.size() == capacity) {
      std::fill(table_.begin(), table_.end(), Entry{});
    } else {
      table_.clear();
      rehash(capacity);
    }
  }

  /// clear(expected) for a map that holds exactly the keys[0, n) (the caller's list of what it
  /// inserted): where the table keeps its size and those keys fill less than a quarter of it,
  /// only their probe runs are emptied instead of the whole table.
  void clearHeld(std::size_t expected, const std::uint64_t* keys, std::size_t n) {
    if (table_.size() != capacityFor(expected) || n != size_ || 4 * n > table_.size()) {
      clear(expected);
      return;
    }
    // (Every occupied slot lies in the run from its key's home slot on: emptying the runs from
    // every key's home slot empties the table.)
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t slot = hash(keys[i]); table_[slot].value != kNoIndex;
           slot = (slot + 1) & mask_) {
        table_[slot] = Entry{};
      }
    }
    size_ = 0;
  }

  /// Asks the CPU to fetch the slot where a look-up of key starts: a hint, no effect on the
  /// map.
  void prefetch(std::uint64_t key) const { __builtin_prefetch(&table_[hash(key)]); }

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

/// The occupied cells of an integer lattice: a dense id per cell in order of first sight, and
/// each cell's coordinates. Coordinates must fit the key (keyFits); find checks it.
class CellGrid {
 public:
  explicit CellGrid(std::size_t expected = 64) : map_(expected) {}

  std::size_t size() const { return map_.size(); }
  /// Empties the grid for about `expected` cells, keeping its storage.
  void clear(std::size_t expected) {
    map_.clear(expected);
    xyz_.clear();
  }
  /// Cell coordinates, 3 per cell in id order.
  const std::vector<std::int32_t>& coords() const { return xyz_; }
  const std::int32_t* xyz(std::size_t c) const { return &xyz_[3 * c]; }
  void reserve(std::size_t cells) { xyz_.reserve(3 * cells); }

  /// The id of cell (x, y, z), adding it when new (inserted says so).
  std::uint32_t insert(std::int32_t x, std::int32_t y, std::int32_t z, bool& inserted) {
    const std::uint32_t id = map_.findOrInsert(packKey(x, y, z), inserted);
    if (inserted) xyz_.insert(xyz_.end(), {x, y, z});
    return id;
  }
  std::uint32_t insert(std::int32_t x, std::int32_t y, std::int32_t z) {
    bool inserted = false;
    return insert(x, y, z, inserted);
  }
  /// The id of cell (x, y, z), or kNoIndex when it is not occupied.
  std::uint32_t find(std::int64_t x, std::int64_t y, std::int64_t z) const {
    return keyFits(x, y, z) ? map_.find(packKey(x, y, z)) : kNoIndex;
  }
  /// The id of the cell of a packed key, or kNoIndex.
  std::uint32_t findKey(std::uint64_t key) const { return map_.find(key); }
  /// The same for coordinates the caller knows to fit the key (no range test).
  std::uint32_t findFitting(std::int32_t x, std::int32_t y, std::int32_t z) const {
    return map_.find(packKey(x, y, z));
  }

 private:
  CellMap map_;
  std::vector<std::int32_t> xyz_;
};

/// Bins items [begin, end) into grid: coords(i, c) writes item i's cell coordinates to
/// std::int64_t c[3], or returns false for an item without a cell (cell_of[i] = kNoIndex).
/// cell_of[i] is then the item's cell id. Returns false, at the first item whose cell lies
/// beyond the key range, with the items from it on not binned.
template <class Coords>
bool binCells(std::size_t begin, std::size_t end, Coords&& coords, CellGrid& grid,
              std::uint32_t* cell_of) {
  for (std::size_t i = begin; i < end; ++i) {
    std::int64_t c[3];
    if (!coords(i, c)) {
      cell_of[i] = kNoIndex;
      continue;
    }
    if (!keyFits(c[0], c[1], c[2])) return false;
    cell_of[i] = grid.insert(static_cast<std::int32_t>(c[0]), static_cast<std::int32_t>(c[1]),
                             static_cast<std::int32_t>(c[2]));
  }
  return true;
}

/// Items grouped by cell: those of cell c are order[start[c], start[c + 1]), in item order.
struct CellLists {
  std::vector<std::uint32_t> start;  ///< n_cells + 1
  std::vector<std::uint32_t> order;  ///< item indices, grouped by cell

  bool empty(std::size_t c) const { return start[c] == start[c + 1]; }
  /// The most items in one cell (0 without cells): with the number of cells of a block, room
  /// for the block's items without counting them.
  std::uint32_t mostInACell() const {
    std::uint32_t most = 0;
    for (std::size_t c = 0; c + 1 < start.size(); ++c) most = std::max(most, start[c + 1] - start[c]);
    return most;
  }
};

/// Groups items [0, n_items) by their cell cell(i) in [0, n_cells) (a stable counting sort);
/// items whose cell is kNoIndex are left out.
template <class CellOfItem>
void listByCell(std::size_t n_items, std::size_t n_cells, CellOfItem&& cell, CellLists& out) {
  out.start.assign(n_cells + 1, 0);
  for (std::size_t i = 0; i < n_items; ++i) {
    const std::uint32_t c = cell(i);
    if (c != kNoIndex) ++out.start[c + 1];
  }
  for (std::size_t c = 0; c < n_cells; ++c) out.start[c + 1] += out.start[c];
  out.order.resize(out.start[n_cells]);
  std::vector<std::uint32_t> fill(out.start.begin(), out.start.end() - 1);
  for (std::size_t i = 0; i < n_items; ++i) {
    const std::uint32_t c = cell(i);
    if (c != kNoIndex) out.order[fill[c]++] = static_cast<std::uint32_t>(i);
  }
}

}  // namespace upd::core::detail
