// The outlier filter's two inner steps, in every version the running CPU can run (AVX-512,
// AVX2, plain), against a reference in double: gatherWithin keeps exactly the points within the
// bound, in point order; selectMean gives the mean of the square roots of the want smallest (to
// float precision) and the want-th exactly, with ties, few candidates and many, whatever the
// guess of the want-th it is given; every version of the voxel grid's key pass gives the plain
// loop's keys; every version of the sensor-rate range cut keeps what RangeBoxTest keeps; the
// outlier filter's grid cells are the floors of the plain arithmetic. Fixed seeds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "../../libs/core/src/preprocess_internal.h"

namespace upd::core {
namespace {

// The squared distance in double (the kernels compute it in float, with or without a fused
// multiply-add: within a few float roundings of this).
double exactD2(float x, float y, float z, float qx, float qy, float qz) {
  const double dx = static_cast<double>(x) - qx, dy = static_cast<double>(y) - qy,
               dz = static_cast<double>(z) - qz;
  return dx * dx + dy * dy + dz * dz;
}

// Every version of a kernel the running CPU can run (AVX-512, AVX2, plain), and first the one
// the library calls, through its entry point.
template <class Fn>
std::vector<std::pair<Fn, std::string>> withTheCpus(
    const std::vector<detail::KernelVersion<Fn>>& versions, Fn entry) {
  std::vector<std::pair<Fn, std::string>> out{{entry, "the CPU's"}};
  for (const auto& v : versions) out.emplace_back(v.fn, v.name);
  return out;
}

TEST(PreprocessKernels, GatherWithinKeepsThePointsWithinTheBoundInOrder) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.1f, 0.1f);
  int checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const std::size_t n = 8 * (1 + static_cast<std::size_t>(trial % 50));
    std::vector<float> x(n), y(n), z(n);
    for (std::size_t j = 0; j < n; ++j) x[j] = u(rng), y[j] = u(rng), z[j] = 1.f + u(rng);
    if (trial % 3 == 0) x[n - 1] = y[n - 1] = z[n - 1] = 1e18f;  // padding, as a block has
    const float qx = u(rng), qy = u(rng), qz = 1.f + u(rng);
    std::vector<double> d2(n);
    for (std::size_t j = 0; j < n; ++j) d2[j] = exactD2(x[j], y[j], z[j], qx, qy, qz);
    std::vector<double> sorted = d2;
    std::sort(sorted.begin(), sorted.end());
    // Bounds halfway between two distances, clear of the kernels' rounding.
    const std::size_t kt = static_cast<std::size_t>(trial) % n;
    const double t = kt + 1 < n ? 0.5 * (sorted[kt] + sorted[kt + 1]) : 2 * sorted[kt];
    const auto clear = [&](double b) {
      for (const double d : d2) {
        if (std::abs(d - b) <= 1e-5 * b) return false;
      }
      return true;
    };
    if (!clear(t)) continue;
    ++checked;
    std::vector<double> want;
    for (std::size_t j = 0; j < n; ++j) {
      if (d2[j] <= t) want.push_back(d2[j]);
    }
    for (const auto& [gather, name] :
         withTheCpus(detail::gatherWithinVersions(), detail::gatherWithin)) {
      std::vector<float> cand(n, -1.f);  // (exactly n: a write past it is a sanitizer's error)
      const std::size_t c = gather(x.data(), y.data(), z.data(), n, qx, qy, qz,
                                   static_cast<float>(t), cand.data());
      ASSERT_EQ(c, want.size()) << "trial " << trial << ", " << name;
      for (std::size_t j = 0; j < c; ++j) {
        EXPECT_NEAR(cand[j], want[j], 1e-6 * want[j] + 1e-12)
            << "trial " << trial << ", " << j << ", " << name;
      }
    }
  }
  EXPECT_GT(checked, 300);
}

// selectMean in every version the CPU can run (on AVX-512 the sorting networks where c <= 32;
// AVX2; plain) of the candidates cand against the mean of the square roots of the want smallest
// in double, and the want-th; the incoming kth is the want-th times
// guess. (To within 2^-23 of the mean: the vector version takes its roots in float, each within
// 2^-24 of the double's.)
void expectSelectMean(const std::vector<float>& cand, std::size_t want, float guess, int trial) {
  const std::size_t c = cand.size();
  std::vector<double> sorted(cand.begin(), cand.end());
  std::sort(sorted.begin(), sorted.end());
  double sum = 0;
  for (std::size_t j = 0; j < want; ++j) sum += std::sqrt(sorted[j]);
  const double mean = sum / static_cast<double>(want - 1);
  for (const auto& [select, name] : withTheCpus(detail::selectMeanVersions(), detail::selectMean)) {
    std::vector<float> buf(c + 8);
    std::copy(cand.begin(), cand.end(), buf.begin());
    float kth = static_cast<float>(sorted[want - 1]) * guess;
    const double got = select(buf.data(), c, want, kth);
    EXPECT_NEAR(got, mean, 0x1p-23 * mean) << "trial " << trial << ", " << name;
    EXPECT_EQ(kth, static_cast<float>(sorted[want - 1])) << "trial " << trial << ", " << name;
  }
}

TEST(PreprocessKernels, SelectMeanIsTheMeanOfTheNearestWithTies) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.f, 0.01f);
  for (int trial = 0; trial < 600; ++trial) {
    const std::size_t want = 2 + static_cast<std::size_t>(trial % 50);  // (up to 9 vectors)
    // Mostly a few more candidates than wanted (the drop path), sometimes many (the selection).
    const std::size_t extra = trial % 7 == 0 ? 40 + static_cast<std::size_t>(trial % 50)
                                             : static_cast<std::size_t>(trial % 19);
    const std::size_t c = want + extra;
    std::vector<float> cand(c);
    for (float& d : cand) d = u(rng);
    cand[static_cast<std::size_t>(trial) % c] = 0.f;  // the point itself
    if (trial % 4 == 1) {  // ties, at the want-th among them
      std::vector<float> s = cand;
      std::sort(s.begin(), s.end());
      for (float& d : cand) {
        if (d >= s[want - 2] && d <= s[std::min(c - 1, want + 1)]) d = s[want - 1];
      }
    }
    // The incoming kth is a guess of the want-th (only the speed depends on it): near it, far
    // on either side, or none.
    const float guess[] = {-1.f, 0.2f, 0.6f, 1.f, 1.7f, 5.f,
                           std::numeric_limits<float>::infinity()};
    expectSelectMean(cand, want, guess[(trial / 7) % 7], trial);
  }
}

// The drop path takes the largest by value, all lanes equal to it at once, and where that
// takes more than it should (a value among those dropped twice, or tied with the want-th) it
// drops again one instance at a time: the same answer either way, wherever the ties fall.
TEST(PreprocessKernels, SelectMeanWithTiesAmongTheDropped) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(0.f, 0.01f);
  int tied = 0;
  for (int trial = 0; trial < 800; ++trial) {
    const std::size_t want = 2 + static_cast<std::size_t>(trial % 40);
    const std::size_t c = want + 1 + static_cast<std::size_t>(trial % 16);  // (the drop path)
    std::vector<float> cand(c);
    for (float& d : cand) d = u(rng);
    std::vector<float> s = cand;
    std::sort(s.begin(), s.end());
    // Two candidates share a value: among the dropped (above the want-th), straddling it, or
    // below it.
    const std::size_t at = (want - 1) + static_cast<std::size_t>(trial % 3) - 1;
    if (at + 1 < c) {
      for (float& d : cand) {
        if (d == s[at + 1]) d = s[at], ++tied;
      }
    }
    std::shuffle(cand.begin(), cand.end(), rng);
    expectSelectMean(cand, want, 1.f, trial);
  }
  EXPECT_GT(tied, 700);
}

// The voxel grid's key pass in every version the CPU can run (AVX-512, AVX2) against the plain
// loop: the same key for every point (NaN, infinite, on the range's and
// the box's bounds, beyond the keys' range), the same answer on whether every passing point's
// voxel fits the key, the same count of finite points, at every length (the vector part and the
// rest).
TEST(PreprocessKernels, VoxelKeysAreThePlainLoopsKeys) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> u(-6.f, 6.f);
  const float nan = std::numeric_limits<float>::quiet_NaN(),
              inf = std::numeric_limits<float>::infinity();
  int refused = 0, passed = 0;
  for (int trial = 0; trial < 300; ++trial) {
    detail::KeyPassParams k{};
    k.ref_x = u(rng), k.ref_y = u(rng), k.ref_z = u(rng);
    k.inv = 1.0 / (trial % 10 == 9 ? 1e-6 : 0.005 + 0.05 * (trial % 5));  // (1e-6: keys overflow)
    k.ox = u(rng) * 0.1f, k.oy = u(rng) * 0.1f, k.oz = u(rng) * 0.1f;
    const bool range = trial % 3 != 0, box = trial % 4 == 1;
    k.rmin2 = range ? 0.16 : -std::numeric_limits<double>::infinity();
    k.rmax2 = range ? 25.0 : std::numeric_limits<double>::infinity();
    k.bx0 = box ? -3.f : -inf, k.by0 = box ? -2.f : -inf, k.bz0 = box ? -1.f : -inf;
    k.bx1 = box ? 3.f : inf, k.by1 = box ? 2.f : inf, k.bz1 = box ? 4.f : inf;
    const std::size_t n = static_cast<std::size_t>(trial % 70);
    std::vector<float> x(n), y(n), z(n);
    for (std::size_t j = 0; j < n; ++j) {
      x[j] = u(rng), y[j] = u(rng), z[j] = u(rng);
      switch ((j + static_cast<std::size_t>(trial)) % 11) {
        case 0: x[j] = nan; break;
        case 1: z[j] = -inf; break;
        case 2: x[j] = k.ox + 5.f, y[j] = k.oy, z[j] = k.oz; break;  // on the range's bound
        case 3: x[j] = k.bx0; break;                                // on the box's bound
        case 4: y[j] = static_cast<float>(k.ref_y + 7 / k.inv); break;  // on a voxel face
        default: break;
      }
    }
    std::size_t finite_want = 3;  // (the counts add to what they are given)
    for (std::size_t j = 0; j < n; ++j) {
      finite_want += std::isfinite(x[j]) && std::isfinite(y[j]) && std::isfinite(z[j]) ? 1 : 0;
    }
    const auto versions = withTheCpus(detail::voxelKeysVersions(), detail::voxelKeys);
    std::vector<std::uint64_t> want(n, 2);
    std::size_t finite_plain = 3;
    const bool ok_plain =
        versions.back().first(x.data(), y.data(), z.data(), n, k, want.data(), finite_plain);
    ASSERT_EQ(versions.back().second, "plain");
    ASSERT_EQ(finite_plain, finite_want) << "trial " << trial;
    refused += ok_plain ? 0 : 1;
    for (const auto& [keys_of, name] : versions) {
      std::vector<std::uint64_t> got(n, 1);
      std::size_t finite = 3;
      const bool ok = keys_of(x.data(), y.data(), z.data(), n, k, got.data(), finite);
      ASSERT_EQ(ok, ok_plain) << "trial " << trial << ", " << name;
      ASSERT_EQ(finite, finite_want) << "trial " << trial << ", " << name;
      if (!ok) continue;  // (the caller throws: the keys are not used)
      for (std::size_t j = 0; j < n; ++j) {
        ASSERT_EQ(got[j], want[j]) << "trial " << trial << ", point " << j << ", " << name;
      }
    }
    if (!ok_plain) continue;
    for (std::size_t j = 0; j < n; ++j) passed += want[j] != detail::kNoKey ? 1 : 0;
  }
  EXPECT_GT(refused, 10);
  EXPECT_GT(passed, 1000);
}

// The sensor-rate range cut: every version the CPU can run (AVX-512, AVX2, plain) keeps exactly
// the points RangeBoxTest keeps (points on the range's and the box's bounds, NaN and infinite
// coordinates, every length up to a few vectors), the others NaN, and counts them alike.
TEST(PreprocessKernels, CropCopyKeepsWhatRangeBoxTestKeeps) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(-6.f, 6.f);
  const float nan = std::numeric_limits<float>::quiet_NaN(),
              inf = std::numeric_limits<float>::infinity();
  std::size_t kept_total = 0, cut_total = 0;
  for (int trial = 0; trial < 300; ++trial) {
    PreprocessParams p;
    p.range_enabled = trial % 3 != 0;
    p.range_min_m = 0.4;
    p.range_max_m = 5.0;
    p.box_enabled = trial % 4 == 1;
    p.box_min_m = {-3.f, -2.f, -1.f};
    p.box_max_m = {3.f, 2.f, 4.f};
    const Eigen::Vector3f origin(u(rng) * 0.1f, u(rng) * 0.1f, u(rng) * 0.1f);
    const detail::KeyPassParams k = detail::rangeBoxBounds(&p, origin);
    const detail::RangeBoxTest test(p, origin);
    const std::size_t n = static_cast<std::size_t>(trial % 70);
    std::vector<float> x(n), y(n), z(n);
    for (std::size_t j = 0; j < n; ++j) {
      x[j] = u(rng), y[j] = u(rng), z[j] = u(rng);
      switch ((j + static_cast<std::size_t>(trial)) % 9) {
        case 0: x[j] = nan; break;
        case 1: z[j] = -inf; break;
        case 2: x[j] = origin.x() + 5.f, y[j] = origin.y(), z[j] = origin.z(); break;  // range
        case 3: x[j] = origin.x(), y[j] = origin.y() - 0.4f, z[j] = origin.z(); break;
        case 4: x[j] = -3.f; break;  // on the box's bound
        case 5: z[j] = 4.f; break;
        default: break;
      }
    }
    for (const auto& [crop, name] : withTheCpus(detail::cropCopyVersions(), detail::cropCopy)) {
      std::vector<float> ox(n, 7.f), oy(n, 7.f), oz(n, 7.f);
      const detail::CropCounts c =
          crop(x.data(), y.data(), z.data(), n, k, ox.data(), oy.data(), oz.data());
      std::size_t finite = 0, kept = 0;
      for (std::size_t j = 0; j < n; ++j) {
        const Eigen::Vector3f q(x[j], y[j], z[j]);
        const bool keeps = q.allFinite() && test.keeps(q);
        finite += q.allFinite() ? 1 : 0;
        kept += keeps ? 1 : 0;
        if (keeps) {
          ASSERT_EQ(ox[j], x[j]) << "trial " << trial << ", point " << j << ", " << name;
          ASSERT_EQ(oy[j], y[j]);
          ASSERT_EQ(oz[j], z[j]);
        } else {
          ASSERT_TRUE(std::isnan(ox[j]) && std::isnan(oy[j]) && std::isnan(oz[j]))
              << "trial " << trial << ", point " << j << ", " << name;
        }
      }
      EXPECT_EQ(c.finite, finite) << "trial " << trial << ", " << name;
      EXPECT_EQ(c.kept, kept) << "trial " << trial << ", " << name;
      if (crop == detail::cropCopy) kept_total += kept, cut_total += finite - kept;
    }
  }
  EXPECT_GT(kept_total, 1000u);
  EXPECT_GT(cut_total, 1000u);
}

// The outlier filter's grid cells, on AVX2 and by the plain loops (dense and through the list of
// finite points), against floor(double(x - o) * inv_h) in plain arithmetic: points on cell
// faces, NaN and far points (clamped, beyond the keys' range either way), every length up to a
// few vectors.
TEST(PreprocessKernels, CellCoordsAreTheFloorsOfThePlainArithmetic) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> u(-3.f, 3.f);
  constexpr double kLimit = 1073741824.0;  // 2^30
  const auto expected = [&](float v, float o, double inv_h) {
    const double w = static_cast<double>(v - o) * inv_h;
    if (std::isnan(w)) return static_cast<std::int32_t>(-kLimit);
    return static_cast<std::int32_t>(std::floor(std::clamp(w, -kLimit, kLimit)));
  };
  for (int trial = 0; trial < 200; ++trial) {
    const std::size_t n = static_cast<std::size_t>(trial % 45);
    const double inv_h = trial % 2 ? 1.0 / 0.06 : 1.0 / 0.0173;
    const float o[3] = {u(rng), u(rng), u(rng)};
    std::vector<float> p[3];
    for (auto& a : p) a.resize(n);
    for (std::size_t j = 0; j < n; ++j) {
      for (int a = 0; a < 3; ++a) p[a][j] = u(rng);
      switch ((j + static_cast<std::size_t>(trial)) % 9) {
        case 0: p[1][j] = std::numeric_limits<float>::quiet_NaN(); break;
        case 1: p[0][j] = 3e12f; break;    // (clamped to 2^30)
        case 2: p[2][j] = -3e12f; break;
        case 3: p[0][j] = static_cast<float>(o[0] + 5 / inv_h); break;  // near a cell face
        default: break;
      }
    }
    std::vector<std::uint32_t> all(n);
    for (std::size_t j = 0; j < n; ++j) all[j] = static_cast<std::uint32_t>(j);
    std::vector<std::int32_t> got[3][3];  // by version and axis
    for (auto& v : got) {
      for (auto& a : v) a.assign(n, 7);
    }
    detail::cellCoordsDense(p[0].data(), p[1].data(), p[2].data(), n, o[0], o[1], o[2], inv_h,
                            got[0][0].data(), got[0][1].data(), got[0][2].data());
    detail::cellCoordsDensePlain(p[0].data(), p[1].data(), p[2].data(), n, o[0], o[1], o[2],
                                 inv_h, got[1][0].data(), got[1][1].data(), got[1][2].data());
    detail::cellCoords(p[0].data(), p[1].data(), p[2].data(), all.data(), n, o[0], o[1], o[2],
                       inv_h, got[2][0].data(), got[2][1].data(), got[2][2].data());
    for (std::size_t j = 0; j < n; ++j) {
      for (int a = 0; a < 3; ++a) {
        const std::int32_t want = expected(p[a][j], o[a], inv_h);
        for (int v = 0; v < 3; ++v) {
          ASSERT_EQ(got[v][a][j], want) << "trial " << trial << ", point " << j << ", axis " << a
                                        << ", version " << v;
        }
      }
    }
  }
}

}  // namespace
}  // namespace upd::core
