// Private to the pre-processing sources: the range/box test, the voxel grid in one pass (with
// the cut-off fused into it) and the compaction of a cloud by a keep mask.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fast_cell_ranks.h"
#include "fast_simd.h"
#include "upd/core/point_cloud.h"
#include "upd/core/preprocess.h"

// A function kept out of its callers and from being specialized on its arguments: GCC's noipa;
// clang has no such attribute (it warns and ignores it), noinline is its nearest.
#if defined(__clang__)
#define UPD_NOIPA __attribute__((noinline))
#else
#define UPD_NOIPA __attribute__((noipa))
#endif

namespace upd::core::detail {

/// The test of cropRange for a finite point q: within the range of the sensor origin and inside
/// the box, each when enabled.
class RangeBoxTest {
 public:
  RangeBoxTest(const PreprocessParams& p, const Eigen::Vector3f& sensor_origin)
      : p_(p),
        origin_(sensor_origin),
        rmin2_(p.range_min_m * p.range_min_m),
        rmax2_(p.range_max_m * p.range_max_m) {}
  bool enabled() const { return p_.range_enabled || p_.box_enabled; }
  const PreprocessParams& params() const { return p_; }
  bool keeps(const Eigen::Vector3f& q) const {
    if (p_.range_enabled) {
      const double d2 = (q - origin_).cast<double>().squaredNorm();
      if (!(d2 >= rmin2_ && d2 <= rmax2_)) return false;
    }
    return !p_.box_enabled ||
           ((q.array() >= p_.box_min_m.array()).all() && (q.array() <= p_.box_max_m.array()).all());
  }

 private:
  const PreprocessParams& p_;
  Eigen::Vector3f origin_;
  double rmin2_, rmax2_;
};

/// What cropCopy and voxelize count: the finite points, and those of them that passed.
struct CropCounts {
  std::size_t finite = 0, kept = 0;
};

/// The voxel grid of the finite points of in that test keeps (every finite point when test is
/// null) into out (unorganized; its buffers reused): one centroid per voxel, in order of first
/// appearance, colour averaged. Returns the number of finite points and of those that passed.
CropCounts voxelize(const PointCloud& in, double voxel_m, const RangeBoxTest* test,
                    PointCloud& out);

/// No packed voxel key has its top bit: the key of a point that does not pass.
constexpr std::uint64_t kNoKey = ~std::uint64_t(0);

/// What the voxel grid's key pass needs: the anchor, the voxel's inverse edge and
/// RangeBoxTest's bounds (a test that is off has infinite bounds, which every finite point
/// passes).
struct KeyPassParams {
  double ref_x, ref_y, ref_z, inv;
  float ox, oy, oz;  // sensor origin
  double rmin2, rmax2;
  float bx0, by0, bz0, bx1, by1, bz1;  // box
};

/// The voxel key of each of the n points (x, y, z) that passes (finite, kept by the range and
/// box tests, each in RangeBoxTest's arithmetic) into keys, kNoKey for the others; the number
/// of finite points among them added to finite. Returns false when a passing point's voxel lies
/// beyond the keys' range. By intrinsics, 8 points at a time on AVX2, 16 on AVX-512; the plain
/// version is the compiler's vectorization of the plain loop. (voxelKeysVersions and the other
/// lists of versions below: KernelVersion, fast_simd.h.)
bool voxelKeys(const float* x, const float* y, const float* z, std::size_t n,
               const KeyPassParams& k, std::uint64_t* keys, std::size_t& finite);
using VoxelKeysFn = bool (*)(const float*, const float*, const float*, std::size_t,
                             const KeyPassParams&, std::uint64_t*, std::size_t&);
std::vector<KernelVersion<VoxelKeysFn>> voxelKeysVersions();

/// KeyPassParams' sensor origin and range and box bounds from p (null: every test off; the
/// key fields zero).
KeyPassParams rangeBoxBounds(const PreprocessParams* p, const Eigen::Vector3f& sensor_origin);

/// The range and box cut of n points (x, y, z) into (ox, oy, oz): a point that passes (finite,
/// kept by the range and box tests of k, each in RangeBoxTest's arithmetic) is copied, any
/// other becomes NaN; cropRange's points of an organized cloud. One pass, by intrinsics 8
/// points at a time on AVX2, 16 on AVX-512. The output arrays must not overlap the input ones.
CropCounts cropCopy(const float* x, const float* y, const float* z, std::size_t n,
                    const KeyPassParams& k, float* ox, float* oy, float* oz);
using CropCopyFn = CropCounts (*)(const float*, const float*, const float*, std::size_t,
                                  const KeyPassParams&, float*, float*, float*);
std::vector<KernelVersion<CropCopyFn>> cropCopyVersions();

/// out takes in's layout, colour and sensor origin, its point arrays resized to in's but not
/// written (the colour copied by the OpenMP team in static shares).
void copyAllButPoints(const PointCloud& in, PointCloud& out);

/// The outlier filter's candidates: the squared distances from (qx, qy, qz) to the n points
/// (x, y, z)[j] (n a multiple of 8) that lie within t, in point order, into cand (room for n).
/// Returns their number. On AVX2 (AVX-512) a vector of 8 (16) distances at a time, its lanes
/// within t packed to the front (no branch per point).
std::size_t gatherWithin(const float* x, const float* y, const float* z, std::size_t n, float qx,
                         float qy, float qz, float t, float* cand);

/// The mean distance of a point to its k = want - 1 nearest others from the c >= want squared
/// distances cand[0, c) to the points within a bound (the point itself among them, at 0; the
/// caller knows that no other point is nearer than the want-th); the want-th (squared) into kth.
/// cand has room for c rounded up to a multiple of 8 and is reordered. On AVX-512, up to 32
/// candidates are sorted (selectMeanSorted), more first narrowed as below. On AVX2, where c - want
/// is small, the c - want largest are dropped one at a time; where it is not, the candidates
/// are first narrowed to a bound near the incoming kth (a guess: the previous point's; only the
/// speed depends on it), then, if still many, a partial selection.
double selectMean(float* cand, std::size_t c, std::size_t want, float& kth);

/// The versions of the two the running CPU can run.
using GatherWithinFn = std::size_t (*)(const float*, const float*, const float*, std::size_t,
                                       float, float, float, float, float*);
using SelectMeanFn = double (*)(float*, std::size_t, std::size_t, float&);
std::vector<KernelVersion<GatherWithinFn>> gatherWithinVersions();
std::vector<KernelVersion<SelectMeanFn>> selectMeanVersions();

/// selectMean by sorting networks (preprocess_outlier_avx512.cpp) for want <= c <= 32, on a CPU
/// with AVX-512F (the caller checks): the candidates sorted in two vectors of 16, the want
/// smallest then taken by lane. cand is read, not reordered.
double selectMeanSorted(const float* cand, std::size_t c, std::size_t want, float& kth);
/// gatherWithin 16 candidates at a time, on a CPU with AVX-512F, FMA and POPCNT (the caller
/// checks; preprocess_outlier_avx512.cpp): AVX2's distances, packed by a compress.
std::size_t gatherWithinAvx512(const float* x, const float* y, const float* z, std::size_t n,
                               float qx, float qy, float qz, float t, float* cand);
/// selectMeanSorted of two points at once (their networks interleaved: each waits on its own
/// chain of steps, the two chains overlap), each with want <= c <= 32.
void selectMeansSorted(const float* cand0, std::size_t c0, const float* cand1, std::size_t c1,
                       std::size_t want, float& kth0, float& kth1, double& mean0,
                       double& mean1);
/// Whether selectMean is selectMeanSorted where c <= 32 (the CPU has AVX-512F), so that the
/// outlier filter's search may take its points two at a time.
bool selectsSorted();
/// Where selectsSorted: the candidates cand[0, c) within the smallest of a few bounds around
/// guess (a guess of the want-th) that keeps at least want of them, packed to the front in
/// order; returns their number (c where no bound keeps want). Elsewhere c, cand unchanged.
/// cand has room for c rounded up to a multiple of 8.
std::size_t narrowCandidates(float* cand, std::size_t c, std::size_t want, float guess);

/// The outlier filter's grid cells: of each point i = finite[f], f < n, the cell
/// (cx, cy, cz)[f] of edge 1 / inv_h anchored at (ox, oy, oz): floor(double(x[i] - ox) * inv_h),
/// clamped to +-2^30 (beyond the keys' range either way). cellCoordsDense is the same for
/// finite[f] = f, on AVX2 by intrinsics 8 points at a time; cellCoordsDensePlain its plain loop,
/// whatever the CPU.
void cellCoords(const float* x, const float* y, const float* z, const std::uint32_t* finite,
                std::size_t n, float ox, float oy, float oz, double inv_h, std::int32_t* cx,
                std::int32_t* cy, std::int32_t* cz);
void cellCoordsDense(const float* x, const float* y, const float* z, std::size_t n, float ox,
                     float oy, float oz, double inv_h, std::int32_t* cx, std::int32_t* cy,
                     std::int32_t* cz);
void cellCoordsDensePlain(const float* x, const float* y, const float* z, std::size_t n, float ox,
                          float oy, float oz, double inv_h, std::int32_t* cx, std::int32_t* cy,
                          std::int32_t* cz);

/// The least and the greatest of v[0, n) into lo and hi (n > 0).
void minMax(const std::int32_t* v, std::size_t n, std::int32_t& lo, std::int32_t& hi);

/// The outlier filter's grid cells of a cloud's finite points (the calling thread's buffers).
/// Each step runs on the team from kTeamPoints points, with the one-thread result.
struct CellCoords {
  static constexpr std::size_t kTeamPoints = 16384;
  std::vector<std::int32_t> x, y, z;  ///< by finite point
  RankedCells marked;                 ///< (countCells' table)

  /// The cells of the points finite (not empty) of in at edge 1 / inv_h, anchored at the first.
  void compute(const PointCloud& in, const std::vector<std::uint32_t>& finite, double inv_h);
  /// Their box [lo, hi] (in cells).
  void box(std::int32_t (&lo)[3], std::int32_t (&hi)[3]) const;
  /// The number of distinct cells, the box being [lo, hi] and fitting the keys: by a table of a
  /// bit per cell over the box (gridCellEdge's first guess has about one cell of the box per
  /// point), by a hash where the box is too large for one.
  std::size_t countCells(const std::int32_t (&lo)[3], const std::int32_t (&hi)[3]);
};

/// Keeps the points of c where keep[i], in order, in place (an unorganized cloud).
void compactInPlace(PointCloud& c, const std::vector<char>& keep);

}  // namespace upd::core::detail
