// computeUpdFast: the fast UPD's stages in order (fast_upd_internal.h lists them and their
// files; upd/core/fast_upd.h describes the method).
#include "upd/core/fast_upd.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "fast_upd_internal.h"

namespace upd::core {

namespace {

using detail::kNoIndex;

void checkInputs(const PointCloud& cloud, const Normals& normals, const UpdParams& params) {
  params.validate();
  requireParam(params.knn == 0, "UpdParams", "knn", params.knn,
               "the fast path sums over the radius d_m: it needs knn = 0");
  if (normals.size() != cloud.size()) {
    throw std::invalid_argument("computeUpdFast: " + std::to_string(normals.size()) +
                                " normals for " + std::to_string(cloud.size()) + " points");
  }
}

}  // namespace

namespace detail {

PointChunks PointChunks::of(const PointCloud& cloud, std::size_t from) {
  constexpr std::size_t kBlock = 256;
  const std::size_t n = cloud.size(), n_blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::uint32_t> finite(n_blocks);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t bb = 0; bb < static_cast<std::ptrdiff_t>(n_blocks); ++bb) {
    const auto b = static_cast<std::size_t>(bb);
    finite[b] = static_cast<std::uint32_t>(
        countFinite(cloud, std::max(from, b * kBlock), (b + 1) * kBlock));
  }
  PointChunks c;
  std::size_t total = 0;
  c.first_finite = n;
  for (std::size_t b = 0; b < n_blocks; ++b) {
    if (finite[b] > 0 && c.first_finite == n) {
      c.first_finite = firstFinite(cloud, std::max(from, b * kBlock));
    }
    total += finite[b];
  }
  constexpr std::size_t kFinitePerFour = std::size_t(1) << 16;  // ~2^14 a chunk
  c.count = total == 0 ? 1 : 4 * ((total + kFinitePerFour - 1) / kFinitePerFour);
  c.bound.assign(c.count + 1, n);
  c.bound[0] = from;
  std::size_t next = 1, seen = 0;
  for (std::size_t b = 0; b < n_blocks && next < c.count; ++b) {
    seen += finite[b];
    while (next < c.count && seen * c.count >= next * total) {
      c.bound[next++] = std::min(n, (b + 1) * kBlock);
    }
  }
  return c;
}

}  // namespace detail

int finerCellsPerRadius(int cells_per_radius, std::size_t cells, double valid_points,
                        double cells_per_point) {
  const int top = std::min(2 * cells_per_radius, 16);
  int m = cells_per_radius;
  // On a surface the occupied cells grow as the square of the cells per d_m.
  while (m < top) {
    const double ratio = static_cast<double>(m + 1) / cells_per_radius;
    if (static_cast<double>(cells) * ratio * ratio > cells_per_point * valid_points) break;
    ++m;
  }
  return m;
}

UpdResult computeUpdFast(const PointCloud& cloud, const Normals& normals, const UpdParams& params,
                         FastUpdStats* stats, double zeta_threshold) {
  UpdResult out;
  computeUpdFast(cloud, normals, params, out, stats, zeta_threshold);
  return out;
}

void computeUpdFast(const PointCloud& cloud, const Normals& normals, const UpdParams& params,
                    UpdResult& out, FastUpdStats* stats, double zeta_threshold) {
  checkInputs(cloud, normals, params);
  const std::size_t n_pts = cloud.size();
  // Every point's fields are written below (scored or NaN): no fill, and the caller's
  // buffers are reused from frame to frame.
  out.rx.resize(n_pts), out.ry.resize(n_pts), out.rz.resize(n_pts), out.zeta.resize(n_pts);
  out.k.resize(n_pts);
  out.invalid = 0;
  if (stats) *stats = FastUpdStats{};

  detail::FastFrame f(cloud, normals, params);
  f.m = params.fast_cells_per_radius;  // or finer (binFrame)
  f.lat.inv_cell = static_cast<float>(f.m / params.radius_m);
  // The chunks start at the first point: the binning gives the points without a cell
  // (non-finite ones) kNoIndex and the interpolation leaves them unscored.
  f.chunks = detail::PointChunks::of(cloud, 0);
  const std::size_t first = f.chunks.first_finite;
  if (first == n_pts) {
    for (std::size_t i = 0; i < n_pts; ++i) detail::setUnscored(out, i);
    out.invalid = n_pts;
    return;
  }
  f.lat.rx = cloud.x[first], f.lat.ry = cloud.y[first], f.lat.rz = cloud.z[first];
  static thread_local detail::FastUpdBuffers buffers;  // the calling thread's, kept
  detail::FastUpdBuffers& buf = buffers;
  buf.cell_of.resize(n_pts);
  f.cell_of = buf.cell_of.data();

  detail::binFrame(f, buf.bins);
  const detail::Bins& bins = buf.bins;
  const std::size_t n_cells = bins.sums.size();
  detail::LatticeIndex& index = buf.index;
  detail::indexLattice(bins, f.m, index, buf.cell_nodes);
  detail::computeCellRows(bins.sums, buf.rows);
  detail::computeNodeSums(index, bins, buf.rows.data(), f.m, buf.node_sums);
  const std::vector<char> refine = detail::cellsToRefine(
      buf.node_sums.data(), buf.cell_nodes.data(), n_cells, params.fast_refine_spread);
  std::size_t invalid = detail::interpolateFrame(f, bins, buf, refine, out);
  std::size_t refined_points = 0;
  if (params.fast_refine_spread > 0) {
    invalid +=
        detail::scoreRefinedCells(f, index, bins, buf.rows.data(), refine, out, refined_points);
  }
  std::size_t exact_points = 0;
  if (params.fast_exact_band > 0 && std::isfinite(zeta_threshold)) {
    exact_points = detail::scoreExactBand(f, index, bins, zeta_threshold, buf.points, out, invalid);
  }
  out.invalid = invalid;
  if (stats) {
    stats->exact_points = exact_points;
    stats->cells = n_cells;
    stats->nodes = index.nodeCount();
    stats->blocks = index.blocks.size();
    stats->refined_points = refined_points;
    stats->cells_per_radius = f.m;
  }
}

}  // namespace upd::core
