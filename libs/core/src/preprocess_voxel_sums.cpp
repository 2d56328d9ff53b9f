// The voxel grid's sums: every passing point's voxel found from its left or upper neighbour's
// (organized frames: a voxel spans several pixels in a row and several rows) before the hash
// map is asked, the sums per voxel in point order, the centroids in order of first appearance.
// Its output is voxelDownsample's after cropRange, bit for bit, on any number of threads.
//
// One thread takes a row at a time: the keys of its points (voxelKeys), then their sums. A
// team splits the rows: each thread sums its own rows into its own map, then the voxels a
// thread shares with the threads before it (a voxel across the rows where they meet) get its
// points added to the earliest thread's sums, one at a time in point order, as on one thread.
// The voxels are numbered by their first point, so the threads' voxels follow one another in
// the one thread's order.
#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "fast_cell_map.h"
#include "preprocess_internal.h"
#include "preprocess_voxel_team.h"
#include "upd/core/openmp.h"
#include "upd/core/vector_clones.h"

namespace upd::core::detail {

namespace {

// The per-thread buffers of voxelize, kept from call to call (no allocation in a warm loop).
struct VoxelScratch {
  CellMap map;
  std::vector<VoxelSums> voxels;
  std::vector<std::uint64_t> voxel_keys;   // the keys the map holds, by voxel id
  // (In a team:) each voxel's first and last point, and whether an earlier thread has it.
  std::vector<std::uint32_t> voxel_first, voxel_last;
  std::vector<char> merged;
  std::vector<std::uint32_t> own;          // (those not merged, whose centroids it stores)
  SharedVoxels shared;                     // (the voxels this thread merges)
  SeenKeys seen;                           // (in a team:) a bit for every key the map holds
  std::size_t held = 0;                    // (their number)
  std::size_t expected = 0;                // the voxels the map is sized for
  std::vector<std::uint64_t> row_key[2];   // the voxel key and id of each column, last two rows
  std::vector<std::uint32_t> row_id[2];
  std::vector<std::uint64_t> keys;  // the keys of the points of one row (unorganized: a chunk)
};

[[noreturn]] void throwSpan(double voxel_m) {
  throw std::invalid_argument(
      "PreprocessParams.voxel_m = " + std::to_string(voxel_m) +
      ": the cloud spans more than 2^20 voxels along an axis; use a larger voxel or a range "
      "cut-off");
}

// The first point of in that passes (finite, kept by test), or in.size(); the finite points
// before it added to finite.
// (The non-finite points, a camera's rows above the horizon, skipped by firstFinite's vector
// scan.)
std::size_t firstPassing(const PointCloud& in, const RangeBoxTest* test, std::size_t& finite) {
  for (std::size_t i = firstFinite(in); i < in.size(); i = firstFinite(in, i + 1)) {
    if (test == nullptr || test->keeps(in.point(i))) return i;
    ++finite;
  }
  return in.size();
}

// Where centroids go: out's points from at.
struct CentroidsOut {
  float *x, *y, *z;
  std::uint8_t *r, *g, *b;  // (null: no colour)
};

CentroidsOut centroidsOut(PointCloud& out, std::size_t at) {
  const bool colour = out.hasColor();
  return {out.x.data() + at, out.y.data() + at, out.z.data() + at,
          colour ? out.r.data() + at : nullptr, colour ? out.g.data() + at : nullptr,
          colour ? out.b.data() + at : nullptr};
}

// The centroids of the voxels a[ids[j]] (kListed; else a[j]), j in [0, n), anchored at ref, into
// out's points j: each coordinate the sum over the count plus the anchor's, each colour the
// mean rounded (lround's value: the quotient lies at least 1 / (2 n) from a half, far beyond its
// rounding, and is not negative). Blocks of voxels are copied out of their sums first, so that
// the divisions run in a loop over plain arrays, which a vector unit does 4 or 8 at a time (the
// same quotients bit for bit).
template <bool kListed>
__attribute__((always_inline)) inline void centroidsOf(const VoxelSums* a,
                                                       const std::uint32_t* ids, std::size_t n,
                                                       const double (&ref)[3],
                                                       const CentroidsOut& out) {
  constexpr std::size_t kBlock = 64;
  double sum[3][kBlock], count[kBlock];
  std::uint32_t rgb[3][kBlock];
  const bool colour = out.r != nullptr;
  float* __restrict xyz[3] = {out.x, out.y, out.z};
  std::uint8_t* __restrict channel[3] = {out.r, out.g, out.b};
  for (std::size_t j0 = 0; j0 < n; j0 += kBlock) {
    const std::size_t m = std::min(kBlock, n - j0);
    for (std::size_t k = 0; k < m; ++k) {
      const VoxelSums& v = a[kListed ? ids[j0 + k] : j0 + k];
      sum[0][k] = v.sx, sum[1][k] = v.sy, sum[2][k] = v.sz;
      count[k] = v.n;
      rgb[0][k] = v.r, rgb[1][k] = v.g, rgb[2][k] = v.b;
    }
    for (int c = 0; c < 3; ++c) {
      float* __restrict o = xyz[c] + j0;
      for (std::size_t k = 0; k < m; ++k) o[k] = static_cast<float>(ref[c] + sum[c][k] / count[k]);
    }
    if (!colour) continue;
    for (int c = 0; c < 3; ++c) {
      std::uint8_t* __restrict o = channel[c] + j0;
      for (std::size_t k = 0; k < m; ++k) {
        o[k] = static_cast<std::uint8_t>(static_cast<std::int32_t>(rgb[c][k] / count[k] + 0.5));
      }
    }
  }
}

// The centroids of the voxels a[0, n) (cloned for the vector units).
UPD_VECTOR_CLONES
void storeCentroids(const VoxelSums* a, std::size_t n, const double (&ref)[3],
                    const CentroidsOut& out) {
  centroidsOf<false>(a, nullptr, n, ref, out);
}

// The centroids of the voxels a[ids[0, n)].
UPD_VECTOR_CLONES
void storeListedCentroids(const VoxelSums* a, const std::uint32_t* ids, std::size_t n,
                          const double (&ref)[3], const CentroidsOut& out) {
  centroidsOf<true>(a, ids, n, ref, out);
}

// out resized to n centroids, unorganized.
void resizeCentroids(std::size_t n, bool colour, PointCloud& out) {
  out.resize(n, colour);
  out.width = n, out.height = 1;
}

// The map emptied and sized for the voxels of the last calls, not for the points: 64 Ki slots
// (1 MB) for a Kinect frame's ~30,000 voxels instead of 256 Ki (4 MB) for a quarter of its
// pixels, a table whose every new voxel's slot missed the cache. It grows within a call that
// has more voxels and is kept until a call has fewer than half of what it was sized for (no new
// table for every frame whose count crosses a power of two). (Where the keys fill less than a
// quarter of it, only their slots are emptied.)
void prepareMap(VoxelScratch& s) {
  if (s.held > s.expected || 2 * s.held < s.expected) {
    s.expected = std::max<std::size_t>(s.held, 1024);
  }
  s.map.clearHeld(s.expected, s.voxel_keys.data(), s.held);
  s.held = 0;
}

// One pass of voxelize: the sums of every passing point's voxel, in point order.
class VoxelPass {
 public:
  VoxelPass(VoxelScratch& s, const PointCloud& in, const Eigen::Vector3d& ref,
            const KeyPassParams& k)
      : s_(s), in_(in), ref_(ref), k_(k) {}

  // Points [b, e) of one row: their keys, then their sums (of an organized cloud: keys holds
  // the row's voxel keys and ids for the next row, above the previous row's; else all null).
  // kTeam: the keys given (the team computes them first), each voxel's first and last point
  // kept. False where a key overflows (the caller throws).
  template <bool kTeam>
  bool row(std::size_t b, std::size_t e, std::uint64_t* keys, std::uint32_t* ids,
           const std::uint64_t* above_keys, const std::uint32_t* above_ids) {
    const std::size_t n = e - b;
    if (!keys) {
      if (s_.keys.size() < n) s_.keys.resize(n);
      keys = s_.keys.data();
    }
    if (!kTeam && !voxelKeys(&in_.x[b], &in_.y[b], &in_.z[b], n, k_, keys, finite_)) return false;
    const bool colour = in_.hasColor();
    const float *x = &in_.x[b], *y = &in_.y[b], *z = &in_.z[b];
    const std::uint8_t* rgb[3] = {colour ? &in_.r[b] : nullptr, colour ? &in_.g[b] : nullptr,
                                  colour ? &in_.b[b] : nullptr};
    std::size_t col = 0;
    while (col < n) {
      const std::uint64_t key = keys[col];
      if (key == kNoKey) {
        ++col;
        // (Holes and the cut-off background come in runs: passed 4 at a time, where all 4 are
        // kNoKey, that is where their AND is.)
        while (col + 4 <= n &&
               (keys[col] & keys[col + 1] & keys[col + 2] & keys[col + 3]) == kNoKey) {
          col += 4;
        }
        continue;
      }
      if (key != last_key_) {
        // The slot of the voxel kAhead points on fetched now, its look-up's load not waited for
        // then (a new voxel's slot is not in the cache).
        if (col + kAhead < n && keys[col + kAhead] != kNoKey) s_.map.prefetch(keys[col + kAhead]);
        // The pixel on the left (last_key_) or above mostly shares the voxel: no lookup.
        last_id_ = above_keys && above_keys[col] == key ? above_ids[col]
                                                        : lookUp<kTeam>(key, b + col);
        last_key_ = key;
      }
      // A run of points in this voxel, its sums in registers from the voxel's and back: the
      // same additions in the same order as into the voxel point by point. (The colours are
      // integers, their sums exact in any order.)
      VoxelSums& a = s_.voxels[last_id_];
      double sx = a.sx, sy = a.sy, sz = a.sz;
      std::uint32_t sr = 0, sg = 0, sb = 0;
      std::size_t j = col;
      for (; j < n && keys[j] == key; ++j) {
        sx += static_cast<double>(x[j]) - ref_.x();
        sy += static_cast<double>(y[j]) - ref_.y();
        sz += static_cast<double>(z[j]) - ref_.z();
        if (ids) ids[j] = last_id_;
        if (colour) sr += rgb[0][j], sg += rgb[1][j], sb += rgb[2][j];
      }
      const auto run = static_cast<std::uint32_t>(j - col);
      a.sx = sx, a.sy = sy, a.sz = sz;
      a.n += run;
      if (colour) a.r += sr, a.g += sg, a.b += sb;
      if (kTeam) s_.voxel_last[last_id_] = static_cast<std::uint32_t>(b + j - 1);
      passed_ += run;
      col = j;
    }
    return true;
  }
  std::size_t passed() const { return passed_; }
  std::size_t finite() const { return finite_; }
  std::size_t voxels() const { return n_voxels_; }

 private:
  // (~16 runs of a Kinect frame's 1.9 points: a probe's miss under way when it is asked.)
  static constexpr std::size_t kAhead = 32;

  template <bool kTeam>
  std::uint32_t lookUp(std::uint64_t key, std::size_t point) {
    bool inserted = false;
    const std::uint32_t id = s_.map.findOrInsert(key, inserted);
    if (inserted) {
      if (s_.voxels.size() <= n_voxels_) {
        const std::size_t size = 2 * n_voxels_ + 64;
        s_.voxels.resize(size), s_.voxel_keys.resize(size);
        if (kTeam) s_.voxel_first.resize(size), s_.voxel_last.resize(size);
      }
      s_.voxel_keys[n_voxels_] = key;
      if (kTeam) {
        s_.voxel_first[n_voxels_] = static_cast<std::uint32_t>(point);
        s_.seen.add(key);
      }
      s_.voxels[n_voxels_++] = VoxelSums{};
      s_.held = n_voxels_;
    }
    return id;
  }

  VoxelScratch& s_;
  const PointCloud& in_;
  Eigen::Vector3d ref_;
  KeyPassParams k_;
  std::uint64_t last_key_ = kNoKey;
  std::uint32_t last_id_ = 0;
  std::size_t passed_ = 0, finite_ = 0, n_voxels_ = 0;
};

// The key-pass bounds of a voxelize call anchored at ref.
KeyPassParams keyPassParams(const PointCloud& in, const RangeBoxTest* test,
                            const Eigen::Vector3d& ref, double voxel_m) {
  KeyPassParams k = rangeBoxBounds(test ? &test->params() : nullptr, in.sensor_origin);
  k.ref_x = ref.x(), k.ref_y = ref.y(), k.ref_z = ref.z();
  k.inv = 1.0 / voxel_m;
  return k;
}

// Where a voxelize call starts: the first passing point, the finite points before it, the
// anchor of the keys and centroids (that point: exact far from the origin), the key pass's
// bounds.
struct Start {
  std::size_t first, finite_before;
  Eigen::Vector3d ref;
  KeyPassParams k;
  double voxel_m;
};

// voxelize on one thread with its scratch s (a function of its own, kept from inlining and
// from specializing on its argument: GCC computes a thread_local's address again, by a call
// into the dynamic linker, at each use in a function that names it).
UPD_NOIPA CropCounts voxelizeWith(VoxelScratch& s, const PointCloud& in, const Start& st,
                                  PointCloud& out) {
  const std::size_t first = st.first;
  const Eigen::Vector3d& ref = st.ref;
  prepareMap(s);
  VoxelPass pass(s, in, ref, st.k);
  if (!in.isOrganized()) {
    constexpr std::size_t kChunk = 4096;  // (the keys of a chunk stay in the cache)
    for (std::size_t b = first; b < in.size(); b += kChunk) {
      if (!pass.row<false>(b, std::min(in.size(), b + kChunk), nullptr, nullptr, nullptr, nullptr)) {
        throwSpan(st.voxel_m);
      }
    }
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
      if (!pass.row<false>(b, (row + 1) * w, s.row_key[cur].data() + skip,
                           s.row_id[cur].data() + skip, s.row_key[above].data() + skip,
                           s.row_id[above].data() + skip)) {
        throwSpan(st.voxel_m);
      }
    }
  }
  const bool colour = in.hasColor();
  resizeCentroids(pass.voxels(), colour, out);
  const double anchor[3] = {ref.x(), ref.y(), ref.z()};
  storeCentroids(s.voxels.data(), pass.voxels(), anchor, centroidsOut(out, 0));
  return {st.finite_before + pass.finite(), pass.passed()};
}

// What the threads of a team share: the cloud's keys, the cost of each row's sums (an
// unorganized cloud: of each chunk of kTeamChunk points), the first point of each thread's
// rows, each thread's scratch, voxel count and (of those no earlier thread has) the place of
// its first in the output.
struct Team {
  const PointCloud& in;
  const Start& st;
  std::uint64_t* keys;
  std::vector<std::uint32_t>& cost;
  std::vector<std::size_t>& starts;
  std::vector<VoxelScratch*>& scratch;
  std::vector<std::size_t>& voxels;
  std::vector<std::size_t>& offset;
  std::size_t w;  // the row's length (an unorganized cloud: kTeamChunk)
};
constexpr std::size_t kTeamChunk = 4096;

// (x | -x) >> 63: 1 where x is not 0 (shifts, which vectorize).
inline std::uint64_t nonZero(std::uint64_t x) { return (x | (0 - x)) >> 63; }

// The cost of summing a row of n keys k (not empty), up the row above's or null: its passing
// points, 5 more for each run of points in one voxel (a key unlike the one before), and 10 more
// for each run whose key is not the one above either (with no row above, every run: the hash
// map's look-ups, where the new voxels are). Weighed on the benchmark's frames by each thread's
// time on its rows: the longer of the two 0.8-1.15 ms with runs alone, 0.8-1.09 with the
// look-ups too (1.0 and 0.91 on average). (A key's top bit is set in kNoKey alone. Cloned: 4 or 8
// keys a vector on AVX2 / AVX-512, where the baseline's SSE2 takes 2.)
UPD_VECTOR_CLONES
std::uint64_t rowCost(const std::uint64_t* __restrict k, const std::uint64_t* __restrict up,
                      std::size_t n) {
  std::uint64_t points = ~k[0] >> 63, runs = points, looks = points;
  if (up) {
    looks &= nonZero(k[0] ^ up[0]);
    for (std::size_t i = 1; i < n; ++i) {
      const std::uint64_t pass = ~k[i] >> 63, start = pass & nonZero(k[i] ^ k[i - 1]);
      points += pass;
      runs += start;
      looks += start & nonZero(k[i] ^ up[i]);
    }
  } else {
    for (std::size_t i = 1; i < n; ++i) {
      const std::uint64_t pass = ~k[i] >> 63, start = pass & nonZero(k[i] ^ k[i - 1]);
      points += pass;
      runs += start;
    }
    looks = runs;
  }
  return points + 5 * runs + 10 * looks;
}

// The keys of thread me's share of the rows, and each row's cost; false where a key
// overflows.
bool teamKeys(const Team& t, int team, int me, std::size_t& finite) {
  const std::size_t n = t.in.size(), w = t.w, row0 = t.st.first / w, rows = (n + w - 1) / w;
  const std::size_t r0 = row0 + (rows - row0) * me / team, r1 = row0 + (rows - row0) * (me + 1) / team;
  bool fits = true;
  for (std::size_t row = r0; row < r1; ++row) {
    const std::size_t b = std::max(t.st.first, row * w), e = std::min(n, (row + 1) * w);
    fits &= voxelKeys(&t.in.x[b], &t.in.y[b], &t.in.z[b], e - b, t.st.k, t.keys + b, finite);
    // (Of an organized cloud, below the share's first row: the row above is this thread's.)
    const bool above = t.in.isOrganized() && row > r0;
    t.cost[row] = static_cast<std::uint32_t>(
        rowCost(t.keys + b, above ? t.keys + b - w : nullptr, e - b));
  }
  return fits;
}

// The first point of each thread's rows: rows of equal shares of the cost.
void splitRows(const Team& t, int team) {
  const std::size_t n = t.in.size(), w = t.w, row0 = t.st.first / w, rows = (n + w - 1) / w;
  std::size_t total = 0;
  for (std::size_t row = row0; row < rows; ++row) total += t.cost[row];
  t.starts[0] = t.st.first;
  std::size_t row = row0, sum = 0;
  for (int u = 1; u < team; ++u) {
    const std::size_t want = total * static_cast<std::size_t>(u) / static_cast<std::size_t>(team);
    while (row < rows && sum + t.cost[row] <= want) sum += t.cost[row++];
    t.starts[u] = std::max(t.st.first, std::min(n, row * w));
  }
  t.starts[team] = n;
}

// Thread me's rows [b, e) summed into its scratch s (noipa, as voxelizeWith), their keys
// computed.
UPD_NOIPA void sumShare(VoxelScratch& s, VoxelPass& pass, const Team& t, std::size_t b,
                        std::size_t e) {
  const PointCloud& in = t.in;
  if (!in.isOrganized()) {
    pass.row<true>(b, e, t.keys + b, nullptr, nullptr, nullptr);
    return;
  }
  const std::size_t w = in.width;
  for (int r = 0; r < 2; ++r) s.row_id[r].resize(w);
  for (std::size_t row = b / w; row * w < e; ++row) {
    const std::size_t cur = row & 1, above = cur ^ 1;
    const std::size_t rb = std::max(b, row * w), skip = rb - row * w;
    const bool top = rb == b;  // (the share's first row: the row above is another's)
    pass.row<true>(rb, std::min(e, (row + 1) * w), t.keys + rb, s.row_id[cur].data() + skip,
                   top ? nullptr : t.keys + rb - w, s.row_id[above].data() + skip);
  }
}

// The voxels [v0, v1) of thread `later` that an earlier thread also has: their points added to
// the earliest one's sums (after the earlier threads' own and those of the threads between,
// merged before), in point order, by one pass over the span of their points. (A voxel on the
// rows where the threads meet spans two rows or more: a scan of each voxel's span would read
// ~1,200 points a voxel, and those voxels come first in the later thread's order, so all in the
// first thread's share of them.) merged set for them; shared: the calling thread's own.
void mergeInto(const Team& t, int later, std::size_t v0, std::size_t v1, SharedVoxels& shared) {
  VoxelScratch& s = *t.scratch[later];
  shared.clear();
  for (std::size_t v = v0; v < v1; ++v) {
    const std::uint64_t key = s.voxel_keys[v];
    s.merged[v] = 0;
    for (int u = 0; u < later; ++u) {
      VoxelScratch& e = *t.scratch[u];
      if (!e.seen.mayHold(key)) continue;
      const std::uint32_t id = e.map.find(key);
      if (id == kNoIndex) continue;
      shared.add(key, &e.voxels[id], s.voxel_first[v], s.voxel_last[v]);
      s.merged[v] = 1;
      break;
    }
  }
  if (shared.empty()) return;
  const bool colour = t.in.hasColor();
  const Eigen::Vector3d& ref = t.st.ref;
  std::uint64_t last_key = kNoKey;
  VoxelSums* a = nullptr;
  for (std::size_t i = shared.lo(); i <= shared.hi(); ++i) {
    const std::uint64_t key = t.keys[i];
    if (key != last_key) a = key == kNoKey ? nullptr : shared.find(key), last_key = key;
    if (a == nullptr) continue;
    a->sx += static_cast<double>(t.in.x[i]) - ref.x();
    a->sy += static_cast<double>(t.in.y[i]) - ref.y();
    a->sz += static_cast<double>(t.in.z[i]) - ref.z();
    if (colour) a->r += t.in.r[i], a->g += t.in.g[i], a->b += t.in.b[i];
    ++a->n;
  }
}

// This thread's part of a team's voxelize with its scratch s: its share of the keys, then the
// sums of its rows, then its share of each later thread's voxels merged, in turn. Returns the
// points its rows passed, the finite ones of its keys through finite; fits false where a key
// overflows.
std::size_t sumTeamVoxels(VoxelScratch& s, const Team& t, int team, int me, std::size_t& finite,
                          bool& fits) {
  fits = teamKeys(t, team, me, finite);
  prepareMap(s);
  s.seen.clear();
#pragma omp barrier
#pragma omp single
  splitRows(t, team);
  VoxelPass pass(s, t.in, t.st.ref, t.st.k);
  sumShare(s, pass, t, t.starts[me], t.starts[me + 1]);
  t.scratch[me] = &s;
  t.voxels[me] = pass.voxels();
  if (s.merged.size() < pass.voxels()) s.merged.resize(s.voxels.size());
#pragma omp barrier
  for (int later = 1; later < team; ++later) {
    const std::size_t n = t.voxels[later];
    mergeInto(t, later, n * me / team, n * (me + 1) / team, s.shared);
#pragma omp barrier
  }
  return pass.passed();
}

// This thread's voxels that no earlier thread has, their centroids into out from its offset.
void storeTeamCentroids(const Team& t, int me, PointCloud& out) {
  VoxelScratch& s = *t.scratch[me];
  const double anchor[3] = {t.st.ref.x(), t.st.ref.y(), t.st.ref.z()};
  if (me == 0) {
    storeCentroids(s.voxels.data(), t.voxels[me], anchor, centroidsOut(out, t.offset[me]));
    return;
  }
  s.own.clear();
  for (std::size_t v = 0; v < t.voxels[me]; ++v) {
    if (!s.merged[v]) s.own.push_back(static_cast<std::uint32_t>(v));
  }
  storeListedCentroids(s.voxels.data(), s.own.data(), s.own.size(), anchor,
                       centroidsOut(out, t.offset[me]));
}

VoxelScratch& teamScratch() {
  thread_local VoxelScratch s;  // (apart from the one-thread scratch: its map keeps its size)
  return s;
}

// voxelize by the OpenMP team (at most 64 threads), for clouds of fewer than 2^32 points.
CropCounts voxelizeTeam(const PointCloud& in, const Start& st, PointCloud& out) {
  const std::size_t first = st.first;
  thread_local std::vector<std::uint64_t> keys;  // (of the whole cloud)
  if (keys.size() < in.size()) keys.resize(in.size());
  if (in.isOrganized()) {  // (the first row's columns before first: the row above the next)
    std::fill(keys.begin() + first / in.width * in.width, keys.begin() + first, kNoKey);
  }
  thread_local std::vector<VoxelScratch*> scratch;
  thread_local std::vector<std::size_t> voxels, offset, starts;
  thread_local std::vector<std::uint32_t> cost;
  const std::size_t w = in.isOrganized() ? in.width : kTeamChunk;
  cost.resize((in.size() + w - 1) / w);
  const Team t{in, st, keys.data(), cost, starts, scratch, voxels, offset, w};
  std::size_t finite = st.finite_before, passed = 0;
  bool fits = true;
  const int most = std::min(openmp::maxThreads(), 64);
  scratch.assign(most, nullptr), voxels.assign(most, 0), offset.assign(most, 0);
  starts.assign(most + 1, 0);
#pragma omp parallel num_threads(most) reduction(+ : finite, passed) reduction(&& : fits)
  {
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    passed += sumTeamVoxels(teamScratch(), t, team, me, finite, fits);
#pragma omp single
    {
      // (t's vectors, not scratch, voxels and offset: those name this thread's thread_local.
      // So do the team's other uses of them, through t.)
      std::size_t total = 0;
      for (int u = 0; u < team; ++u) {
        t.offset[u] = total;
        const VoxelScratch& s = *t.scratch[u];
        for (std::size_t v = 0; v < t.voxels[u]; ++v) total += u == 0 || !s.merged[v] ? 1 : 0;
      }
      resizeCentroids(total, in.hasColor(), out);
    }
    storeTeamCentroids(t, me, out);
  }
  if (!fits) throwSpan(st.voxel_m);
  return {finite, passed};
}

}  // namespace

CropCounts voxelize(const PointCloud& in, double voxel_m, const RangeBoxTest* test,
                    PointCloud& out) {
  out.sensor_origin = in.sensor_origin;
  std::size_t finite_before = 0;
  const std::size_t first = firstPassing(in, test, finite_before);
  if (first == in.size()) {
    resizeCentroids(0, false, out);
    return {finite_before, 0};
  }
  const Eigen::Vector3d ref = in.point(first).cast<double>();
  const Start st{first, finite_before, ref, keyPassParams(in, test, ref, voxel_m), voxel_m};
  // (A team from 65,536 points, as the cut-off of an organized frame.)
  if (in.size() > 65536 && in.size() < (std::size_t(1) << 32) && openmp::maxThreads() > 1) {
    return voxelizeTeam(in, st, out);
  }
  thread_local VoxelScratch s;
  return voxelizeWith(s, in, st, out);
}

}  // namespace upd::core::detail
