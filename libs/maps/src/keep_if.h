// Private to libs/maps: a select the vectorizer takes, for the loops that compute cells and
// keys a vector of points at a time (grid_fusion.cpp, octree_insert.cpp).
#pragma once

#include <cstdint>
#include <cstring>

namespace upd::maps::detail {

// v where keep, +0 elsewhere: a select that the compiler cannot turn into a branch (which would
// stop the loop's vectorization), nor look through to fuse a product into a multiply-add.
inline double keepIf(bool keep, double v) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  bits &= 0 - static_cast<std::uint64_t>(keep);
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

}  // namespace upd::maps::detail
