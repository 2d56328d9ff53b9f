// Private to the fast UPD (fast_upd*.cpp; the method is described in upd/core/fast_upd.h): the
// lattice's data and the stages computeUpdFast runs in order, one source file each:
//   binning                     fast_upd_bins.cpp    points -> occupied cells and their sums
//   nodes, blocks, node sums,   fast_upd_nodes.cpp   ball sums at the cell corners; the cells
//   refined cells                                     whose nodes disagree, summed per point
//   interpolation               fast_upd_interp.cpp  every point from its cell's 8 nodes
//   exact band                  fast_upd_exact.cpp   exact sums near the label threshold
// Every stage deals the points out in the same chunks (PointChunks, fixed by the points), so
// that the result does not depend on the thread count; the binning and the interpolation take
// them dynamically, the others in static shares.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "fast_cell_map.h"
#include "fast_cell_ranks.h"
#include "fast_simd.h"
#include "upd/core/fast_upd.h"

namespace upd::core::detail {

// Per-cell sums over the points with a valid normal. Positions are relative to the cell's
// lower corner in cell units (in [0, 1)), so float keeps them exact enough anywhere.
struct CellSums {
  float count = 0;
  float nx = 0, ny = 0, nz = 0;
  float px = 0, py = 0, pz = 0;
  float pxx = 0, pxy = 0, pxz = 0, pyy = 0, pyz = 0, pzz = 0;

  void add(const CellSums& o) {
    count += o.count;
    nx += o.nx, ny += o.ny, nz += o.nz;
    px += o.px, py += o.py, pz += o.pz;
    pxx += o.pxx, pxy += o.pxy, pxz += o.pxz, pyy += o.pyy, pyz += o.pyz, pzz += o.pzz;
  }
};

// Four floats as one GCC vector (SSE everywhere): r_x, r_y, r_z, k.
typedef float Quad __attribute__((vector_size(4 * sizeof(float))));

// Ball sums at a node: (r_x, r_y, r_z, k), then their derivatives with respect to the node's
// x, y and z (cell units), four values each: the layout the interpolation reads.
struct NodeSums {
  Quad q[4];
};

// What a cell contributes to ball sums, once per cell: the centroid's offset from the cell's
// lower corner and the covariance of its points (cell units), the count of valid normals and
// their sum.
struct CellRow {
  enum Field { kMx, kMy, kMz, kCxx, kCxy, kCxz, kCyy, kCyz, kCzz, kCount, kNx, kNy, kNz, kFields };
  float f[kFields];
};

// The blend of a cell's 8 nodes as a polynomial in the position inside the cell
// (fast_upd_interp.cpp): the coefficients of its 20 monomials for each of the 4 values (r_x,
// r_y, r_z, k), and the cell's lower corner in lattice coordinates.
constexpr int kMonomials = 20;
struct CellPoly {
  Quad c[kMonomials];  // c[monomial][value]
  float corner[3];
};

// The points with a valid normal grouped by cell (counting sort; point order within a cell),
// positions relative to the lattice origin (as in Lattice: the differences stay exact where
// the input floats allow it, so a cloud far from the origin loses nothing): what the exact
// sums over a cut cell read (fast_upd_exact.cpp).
struct CellPoints {
  std::vector<std::uint32_t> start;  // n_cells + 1
  std::vector<float> x, y, z, nx, ny, nz;
};

struct Lattice {
  float rx = 0, ry = 0, rz = 0;  // world position of lattice point (0, 0, 0): the first point
  float inv_cell = 1.f;          // 1 / s

  // Lattice coordinates of a world point. The cloud's coordinates are floats: their difference
  // from the first point is exact wherever both lie on a common binary grid (a cloud moved by
  // 10 km gives the same numbers), so float keeps everything the input holds.
  float gx(float x) const { return (x - rx) * inv_cell; }
  float gy(float y) const { return (y - ry) * inv_cell; }
  float gz(float z) const { return (z - rz) * inv_cell; }
};

// Largest |lattice coordinate| the keys hold (21 bits per axis), with a margin for the nodes.
constexpr float kMaxCoord = static_cast<float>(kKeyBias - 4);

// Squared nearest and farthest distance from a point to a unit cell whose lower corner lies at
// (ax, ay, az) from it. (Written as selects: GCC keeps the loops that call it branch-free and
// vectorizes them.)
inline void boxDistances2(float ax, float ay, float az, float& near2, float& far2) {
  const float bx = ax + 1.f, by = ay + 1.f, bz = az + 1.f;
  const float qx = ax > 0.f ? ax : (bx < 0.f ? -bx : 0.f);
  const float qy = ay > 0.f ? ay : (by < 0.f ? -by : 0.f);
  const float qz = az > 0.f ? az : (bz < 0.f ? -bz : 0.f);
  near2 = qx * qx + qy * qy + qz * qz;
  far2 = std::max(ax * ax, bx * bx) + std::max(ay * ay, by * by) + std::max(az * az, bz * bz);
}

inline void setUnscored(UpdResult& out, std::size_t i) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  out.rx[i] = out.ry[i] = out.rz[i] = out.zeta[i] = nan;
  out.k[i] = 0;
}

// The points [from, n) in count chunks of about equal numbers of finite points, cut at
// multiples of 256 points; count is a multiple of 4 (1 without a finite point). Fixed by the
// points alone, so the same for any number of threads (the binning merges its sums in chunk
// order), and a static schedule gives 1, 2 or 4 threads equal shares of the finite points,
// wherever in the frame they lie (a sky of NaN above, a near floor below).
struct PointChunks {
  std::size_t first_finite = 0;  // the first finite point at or after from (n: none)
  std::size_t count = 0;
  std::vector<std::size_t> bound;  // chunk c is [bound[c], bound[c + 1])

  static PointChunks of(const PointCloud& cloud, std::size_t from);
  std::size_t begin(std::size_t c) const { return bound[c]; }
  std::size_t end(std::size_t c) const { return bound[c + 1]; }
};

// The occupied cells of a run of points with their sums: what binning produces per chunk and
// after merging.
struct Bins {
  CellGrid grid;
  std::vector<CellSums> sums;

  // Out of line: binRange calls it once per run of points in one cell; inlined there, the fast
  // UPD ran ~2 % more instructions (callgrind, a full-resolution Kinect frame).
  __attribute__((noinline)) std::uint32_t cellOf(std::int32_t x, std::int32_t y, std::int32_t z) {
    bool inserted = false;
    const std::uint32_t id = grid.insert(x, y, z, inserted);
    if (inserted) sums.emplace_back();
    return id;
  }
};

// What the stages read about the frame being scored.
struct FastFrame {
  FastFrame(const PointCloud& c, const Normals& n, const UpdParams& p)
      : cloud(c), normals(n), params(p) {}

  const PointCloud& cloud;
  const Normals& normals;
  const UpdParams& params;
  Lattice lat;
  int m = 0;  // lattice cells per d_m
  PointChunks chunks;
  std::uint32_t* cell_of = nullptr;  // per point: its cell, or kNoIndex
};

// The lattice nodes (the 8 corners of every occupied cell) and the blocks of B^3 cells, B = m +
// 1, that group cells and nodes: every cell within d_m of a node lies in the 27 blocks around
// the node's block.
// The nodes are numbered by rank in a bit table over their box (on the team), or by the hash
// where that box is too sparse for one (far lone points).
struct LatticeIndex {
  std::int32_t B = 1;
  bool ranked = false;                        // the nodes by node_ranks, else by nodes
  RankedCells node_ranks;
  std::vector<std::int32_t> ranked_node_xyz;  // 3 per node, by id: the ranked nodes'
  CellGrid nodes;                             // the hashed nodes
  CellGrid blocks;
  std::vector<std::uint32_t> cell_block, node_block;
  CellLists block_cells, block_nodes;  // cells and nodes by block

  std::size_t nodeCount() const { return ranked ? node_ranks.size() : nodes.size(); }
  const std::int32_t* nodeXyz(std::size_t v) const {
    return ranked ? &ranked_node_xyz[3 * v] : nodes.xyz(v);
  }
  // The cells with valid normals in the 27 blocks around block b.
  void around(std::size_t b, const std::vector<CellSums>& sums,
              std::vector<std::uint32_t>& cells) const;
  void blockOrigin(std::size_t b, std::int32_t (&origin)[3]) const {
    for (int a = 0; a < 3; ++a) origin[a] = blocks.xyz(b)[a] * B;
  }
};

// The calling thread's per-frame tables, kept for the next frame so that a frame loop does not
// fault fresh pages in for them every frame. Every element read is written first. (The stages
// take them by reference: inside a parallel region the name of a thread_local would be another
// thread's buffer.)
struct FastUpdBuffers {
  std::vector<std::uint32_t> cell_of;     // per point
  std::vector<std::uint32_t> cell_nodes;  // 8 per cell
  std::vector<CellRow> rows;              // per cell
  std::vector<NodeSums> node_sums;        // per node
  std::vector<CellPoly> polys;            // per cell
  CellPoints points;
  Bins bins;                              // the cells and their sums
  LatticeIndex index;                     // the nodes and blocks
};

// --- Stages (in the order computeUpdFast runs them) ---

// fast_upd_bins.cpp: bins the frame's points (f.cell_of) at f.m cells per d_m, then at a finer
// lattice where the points are dense (fast_cells_per_point), updating f.m and f.lat; the cells
// into out (emptied first).
void binFrame(FastFrame& f, Bins& out);

// fast_upd_nodes.cpp: the nodes of the cells (cell_xyz, 3 a cell) into index and their ids into
// cell_nodes (8 a cell, corner o at +1 along axis a where bit a of o is set), by rank on the
// team (rankNodes: false, with nothing done, where their box is too sparse for the bit table)
// or by the hash (hashNodes); then with the blocks (indexLattice, either way).
bool rankNodes(const std::int32_t* cell_xyz, std::size_t n_cells, LatticeIndex& index,
               std::uint32_t* cell_nodes);
void hashNodes(const std::int32_t* cell_xyz, std::size_t n_cells, LatticeIndex& index,
               std::uint32_t* cell_nodes);
void indexLattice(const Bins& bins, int m, LatticeIndex& index,
                  std::vector<std::uint32_t>& cell_nodes);
void computeCellRows(const std::vector<CellSums>& sums, std::vector<CellRow>& rows);
void computeNodeSums(const LatticeIndex& index, const Bins& bins, const CellRow* rows, int m,
                     std::vector<NodeSums>& node_sums);
std::vector<char> cellsToRefine(const NodeSums* node_sums, const std::uint32_t* cell_nodes,
                                std::size_t n_cells, double spread);
std::size_t scoreRefinedCells(const FastFrame& f, const LatticeIndex& index, const Bins& bins,
                              const CellRow* rows, const std::vector<char>& refine, UpdResult& out,
                              std::size_t& refined_points);

// fast_upd_interp.cpp: every point not in a refined cell from the blend of its cell's nodes;
// returns the points left unscored.
std::size_t interpolateFrame(const FastFrame& f, const Bins& bins, FastUpdBuffers& buf,
                             const std::vector<char>& refine, UpdResult& out);

// fast_upd_exact.cpp: exact sums for the points whose zeta lies within fast_exact_band of
// zeta_threshold; returns the points so summed and adds those left unscored to invalid.
std::size_t scoreExactBand(const FastFrame& f, const LatticeIndex& index, const Bins& bins,
                           double zeta_threshold, CellPoints& pts, UpdResult& out,
                           std::size_t& invalid);

}  // namespace upd::core::detail
