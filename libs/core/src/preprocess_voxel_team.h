// Private to the voxel pass (preprocess_voxel_sums.cpp): each voxel's sums, and the two key
// sets a team of threads uses to merge the voxels its threads share (a voxel on the rows where
// two threads' shares meet).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fast_cell_map.h"

namespace upd::core::detail {

/// Per voxel: the sums of the points relative to the anchor, of the colours (exact: below 2^32
/// for any voxel of fewer than 2^24 points), and the count.
struct VoxelSums {
  double sx = 0, sy = 0, sz = 0;
  std::uint32_t r = 0, g = 0, b = 0;
  std::uint32_t n = 0;
};

/// A Bloom filter of one hash over the keys a thread's map holds (in a team): a later thread
/// asks it before it looks a voxel up in that map. Most of its voxels are not there, and each
/// probe of the other thread's map would miss the cache (another core filled it).
class SeenKeys {
 public:
  void clear() { bits_.assign(kWords, 0); }
  void add(std::uint64_t key) {
    const std::size_t i = slot(key);
    bits_[i >> 6] |= std::uint64_t{1} << (i & 63);
  }
  bool mayHold(std::uint64_t key) const {
    const std::size_t i = slot(key);
    return ((bits_[i >> 6] >> (i & 63)) & 1) != 0;
  }

 private:
  // (64 KB: ~3 % false positives at a Kinect frame's ~16,000 voxels a thread.)
  static constexpr int kBits = 19;
  static constexpr std::size_t kWords = (std::size_t{1} << kBits) / 64;
  static std::size_t slot(std::uint64_t key) {
    return static_cast<std::size_t>((key * 0xD6E8FEB86659FD93ull) >> (64 - kBits));
  }
  std::vector<std::uint64_t> bits_;
};

/// The voxels of a later thread that an earlier one also has (in a team's merge): by key, the
/// earliest holder's sums; and the span of their points in the cloud.
class SharedVoxels {
 public:
  void clear() {
    map_.clear(std::max<std::size_t>(sums_.size(), 16));  // (sized as last time: no new table)
    sums_.clear();
    lo_ = ~std::size_t{0}, hi_ = 0;
  }
  bool empty() const { return sums_.empty(); }
  /// A voxel (each key once) whose points lie in [first, last].
  void add(std::uint64_t key, VoxelSums* sums, std::size_t first, std::size_t last) {
    bool inserted = false;
    map_.findOrInsert(key, inserted);  // (its index: that of its sums)
    sums_.push_back(sums);
    lo_ = std::min(lo_, first), hi_ = std::max(hi_, last);
  }
  /// The earliest holder's sums of the voxel of key, or null.
  VoxelSums* find(std::uint64_t key) const {
    const std::uint32_t id = map_.find(key);
    return id == kNoIndex ? nullptr : sums_[id];
  }
  /// The points [lo, hi] hold every point of these voxels.
  std::size_t lo() const { return lo_; }
  std::size_t hi() const { return hi_; }

 private:
  CellMap map_;
  std::vector<VoxelSums*> sums_;
  std::size_t lo_ = 0, hi_ = 0;
};

}  // namespace upd::core::detail
