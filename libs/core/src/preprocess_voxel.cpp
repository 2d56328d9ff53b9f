// The voxel grid in one pass over the input: the cut-off tested per point on the way, each
// point's voxel found from its left or upper neighbour's (organized frames: a voxel spans
// several pixels in a row and several rows) before the hash map is asked, the sums per voxel
// in point order. Its output is voxelDownsample's after cropRange, bit for bit.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "fast_cell_map.h"
#include "fast_simd.h"
#include "preprocess_internal.h"

namespace upd::core::detail {

namespace {

// Per voxel: the sums of the points relative to the anchor, of the colours, and the count.
struct VoxelSums {
  double sx = 0, sy = 0, sz = 0;
  double r = 0, g = 0, b = 0;
  std::uint32_t n = 0;
};

// The per-thread buffers of voxelize, kept from call to call (no allocation in a warm loop).
struct VoxelScratch {
  CellMap map;
  std::vector<VoxelSums> voxels;
  std::vector<std::uint64_t> row_key[2];  // the voxel key and id of each column, last two rows
  std::vector<std::uint32_t> row_id[2];
};

[[noreturn]] void throwSpan(double voxel_m) {
  throw std::invalid_argument(
      "PreprocessParams.voxel_m = " + std::to_string(voxel_m) +
      ": the cloud spans more than 2^20 voxels along an axis; use a larger voxel or a range "
      "cut-off");
}

// The first point of in that passes (finite, kept by test), or in.size().
std::size_t firstPassing(const PointCloud& in, const RangeBoxTest* test) {
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (in.isFinite(i) && (test == nullptr || test->keeps(in.point(i)))) return i;
  }
  return in.size();
}

// The centroids of s.voxels[0, n) (anchored at ref) into out, in voxel order.
void writeCentroids(const VoxelScratch& s, std::size_t n, const Eigen::Vector3d& ref,
                    bool colour, PointCloud& out) {
  out.x.resize(n), out.y.resize(n), out.z.resize(n);
  out.r.resize(colour ? n : 0), out.g.resize(colour ? n : 0), out.b.resize(colour ? n : 0);
  out.width = n, out.height = 1;
  for (std::size_t v = 0; v < n; ++v) {
    const VoxelSums& a = s.voxels[v];
    const Eigen::Vector3d c = ref + Eigen::Vector3d(a.sx, a.sy, a.sz) / a.n;
    out.x[v] = static_cast<float>(c.x());
    out.y[v] = static_cast<float>(c.y());
    out.z[v] = static_cast<float>(c.z());
    if (colour) {
      const auto avg = [&](double sum) { return static_cast<std::uint8_t>(std::lround(sum / a.n)); };
      out.r[v] = avg(a.r), out.g[v] = avg(a.g), out.b[v] = avg(a.b);
    }
  }
}

}  // namespace

namespace {

// One pass of voxelize: the sums of every passing point's voxel, in point order.
class VoxelPass {
 public:
  VoxelPass(VoxelScratch& s, const PointCloud& in, const Eigen::Vector3d& ref, double voxel_m,
            const RangeBoxTest* test)
      : s_(s), in_(in), ref_(ref), voxel_m_(voxel_m), inv_(1.0 / voxel_m), test_(test) {}

  // Points [b, e) of one row (of an organized cloud: keys holds the row's voxel keys and ids
  // for the next row, above the previous row's; else both null).
  void row(std::size_t b, std::size_t e, std::uint64_t* keys, std::uint32_t* ids,
           const std::uint64_t* above_keys, const std::uint32_t* above_ids) {
    const bool colour = in_.hasColor();
    for (std::size_t i = b; i < e; ++i) {
      const std::size_t col = i - b;
      if (keys) keys[col] = kNone;
      if (!in_.isFinite(i) || (test_ && !test_->keeps(in_.point(i)))) continue;
      ++passed_;
      const double dx = static_cast<double>(in_.x[i]) - ref_.x(),
                   dy = static_cast<double>(in_.y[i]) - ref_.y(),
                   dz = static_cast<double>(in_.z[i]) - ref_.z();
      // Checked before the conversion to integers, which is undefined beyond 2^63 (1e30 m).
      if (!(std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) * inv_ < 1e15)) {
        throwSpan(voxel_m_);
      }
      const std::int64_t cx = floorToInt(dx * inv_), cy = floorToInt(dy * inv_),
                         cz = floorToInt(dz * inv_);
      if (!keyFits(cx, cy, cz)) throwSpan(voxel_m_);
      const std::uint64_t key = packKey(cx, cy, cz);
      if (key != last_key_) {
        // The pixel on the left (last_key_) or above mostly shares the voxel: no lookup.
        last_id_ = above_keys && above_keys[col] == key ? above_ids[col] : lookUp(key);
        last_key_ = key;
      }
      if (keys) keys[col] = key, ids[col] = last_id_;
      VoxelSums& a = s_.voxels[last_id_];
      a.sx += dx, a.sy += dy, a.sz += dz;
      ++a.n;
      if (colour) a.r += in_.r[i], a.g += in_.g[i], a.b += in_.b[i];
    }
  }
  std::size_t passed() const { return passed_; }
  std::size_t voxels() const { return n_voxels_; }

 private:
  static constexpr std::uint64_t kNone = ~std::uint64_t(0);  // no packed key has its top bit
  std::uint32_t lookUp(std::uint64_t key) {
    bool inserted = false;
    const std::uint32_t id = s_.map.findOrInsert(key, inserted);
    if (inserted) {
      if (s_.voxels.size() <= n_voxels_) s_.voxels.resize(2 * n_voxels_ + 64);
      s_.voxels[n_voxels_++] = VoxelSums{};
    }
    return id;
  }

  VoxelScratch& s_;
  const PointCloud& in_;
  Eigen::Vector3d ref_;
  double voxel_m_, inv_;
  const RangeBoxTest* test_;
  std::uint64_t last_key_ = kNone;
  std::uint32_t last_id_ = 0;
  std::size_t passed_ = 0, n_voxels_ = 0;
};

}  // namespace

std::size_t voxelize(const PointCloud& in, double voxel_m, const RangeBoxTest* test,
                     PointCloud& out) {
  thread_local VoxelScratch s;
  out.sensor_origin = in.sensor_origin;
  const std::size_t first = firstPassing(in, test);
  if (first == in.size()) {
    writeCentroids(s, 0, Eigen::Vector3d::Zero(), false, out);
    return 0;
  }
  // Keys and centroids relative to the first point: exact far from the origin.
  const Eigen::Vector3d ref = in.point(first).cast<double>();
  s.map.clear(in.size() / 4 + 16);
  VoxelPass pass(s, in, ref, voxel_m, test);
  if (!in.isOrganized()) {
    pass.row(first, in.size(), nullptr, nullptr, nullptr, nullptr);
  } else {
    const std::size_t w = in.width;
    for (int r = 0; r < 2; ++r) {
      s.row_key[r].assign(w, ~std::uint64_t(0));  // (no voxel has this key)
      s.row_id[r].resize(w);
    }
    for (std::size_t row = first / w; row < in.height; ++row) {
      const std::size_t cur = row & 1, above = cur ^ 1;
      // (The first row starts at the first passing point; the columns before it stay empty.)
      const std::size_t b = std::max(first, row * w), skip = b - row * w;
      pass.row(b, (row + 1) * w, s.row_key[cur].data() + skip, s.row_id[cur].data() + skip,
               s.row_key[above].data() + skip, s.row_id[above].data() + skip);
    }
  }
  writeCentroids(s, pass.voxels(), ref, in.hasColor(), out);
  return pass.passed();
}

void compactInPlace(PointCloud& c, const std::vector<char>& keep) {
  const bool colour = c.hasColor();
  std::size_t m = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!keep[i]) continue;
    c.x[m] = c.x[i], c.y[m] = c.y[i], c.z[m] = c.z[i];
    if (colour) c.r[m] = c.r[i], c.g[m] = c.g[i], c.b[m] = c.b[i];
    ++m;
  }
  c.x.resize(m), c.y.resize(m), c.z.resize(m);
  if (colour) c.r.resize(m), c.g.resize(m), c.b.resize(m);
  c.width = m, c.height = 1;
}

}  // namespace upd::core::detail
