// The batched PCA normals (normalsFromMoments, eight at a time on AVX-512, four on AVX2, and as
// a CPU without AVX-512 runs them) give the scalar unitCovariance and normalFromUnitCovariance's
// answers bit for bit: the same validity, normal and curvature, on planes with noise, rounded
// edges, lines, isotropic blobs and degenerate covariances, in batches of every length (the
// vector lanes and the scalar tail). Fixed seeds.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "../../libs/core/src/fast_normals_internal.h"

namespace upd::core {
namespace {

// The moments of n points drawn with the given spreads along three random axes (some spreads
// zero: a line, a point), and now and then of no point at all or of an exact line along x (a
// covariance of one non-zero entry: its adjugate vanishes).
std::vector<detail::Moments> sampleMoments(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.f, 1.f);
  std::uniform_int_distribution<int> kind(0, 7);
  std::vector<detail::Moments> out;
  while (static_cast<int>(out.size()) < count) {
    const int k = kind(rng);
    // Spreads: a plane with noise, a rounded edge (l0 near l1), a line, a blob, a point.
    const float s[6][3] = {{1.f, 0.8f, 0.01f}, {1.f, 0.3f, 0.2f}, {1.f, 0.f, 0.f},
                           {1.f, 1.f, 1.f},    {0.f, 0.f, 0.f},  {1.f, 0.5f, 1e-4f}};
    detail::Moments m;
    if (k >= 6) {  // (no point; the two points (+-1, 0, 0))
      if (k == 7) m.n = 2, m.xx = 2;
      out.push_back(m);
      continue;
    }
    const Eigen::Matrix3f R =
        Eigen::Quaternionf(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
    const int n = 3 + static_cast<int>(rng() % 40);
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3f q =
          R * Eigen::Vector3f(s[k][0] * g(rng), s[k][1] * g(rng), s[k][2] * g(rng));
      const double x = q.x(), y = q.y(), z = q.z();
      m.n += 1, m.x += x, m.y += y, m.z += z;
      m.xx += x * x, m.xy += x * y, m.xz += x * z, m.yy += y * y, m.yz += y * z, m.zz += z * z;
    }
    out.push_back(m);
  }
  return out;
}

// One batched answer (ok, n, curvature) against the scalar one (ok1, n1, c1), bit for bit;
// counts it as valid or invalid.
void expectScalarsAnswer(std::uint8_t ok, const Eigen::Vector3f& n, float curvature, bool ok1,
                         const Eigen::Vector3f& n1, float c1, std::size_t at, int& valid,
                         int& invalid) {
  ASSERT_EQ(ok, ok1 ? 1 : 0) << "neighbourhood " << at;
  if (!ok1) {
    ++invalid;
    return;
  }
  ++valid;
  EXPECT_EQ(std::memcmp(n.data(), n1.data(), sizeof(float) * 3), 0)
      << "neighbourhood " << at << ": " << n.transpose() << " vs " << n1.transpose();
  EXPECT_EQ(std::memcmp(&curvature, &c1, sizeof c1), 0) << "neighbourhood " << at;
}

// normalsFromMoments (unitCovariance's arithmetic in vector lanes, then the batched normals)
// against unitCovariance and normalFromUnitCovariance one at a time: the same validity (no
// point, no spread, no plane), normal and curvature, bit for bit, in batches of every length,
// the moments as rows of a wider table.
TEST(FastNormalsBatch, NormalsFromMomentsAreTheScalarOnesBitForBit) {
  const std::vector<detail::Moments> moments = sampleMoments(2000, 9);
  int valid = 0, invalid = 0;
  std::size_t begin = 0;
  for (std::size_t len = 0; begin < moments.size(); len = len == 13 ? moments.size() : len + 1) {
    const std::size_t count = std::min(len, moments.size() - begin);
    const std::size_t stride = count + 3;
    std::vector<double> rows(10 * stride, -1.0);
    for (std::size_t j = 0; j < count; ++j) {
      const detail::Moments& m = moments[begin + j];
      const double f[10] = {m.n, m.x, m.y, m.z, m.xx, m.xy, m.xz, m.yy, m.yz, m.zz};
      for (std::size_t k = 0; k < 10; ++k) rows[k * stride + j] = f[k];
    }
    for (const auto solve : {detail::normalsFromMoments, detail::normalsFromMomentsWithoutAvx512}) {
      SCOPED_TRACE(solve == detail::normalsFromMoments ? "the CPU's" : "without AVX-512");
      std::vector<Eigen::Vector3f> n(count);
      std::vector<float> curvature(count);
      std::vector<std::uint8_t> ok(count, 7);
      solve(rows.data(), stride, count, n.data(), curvature.data(), ok.data());
      for (std::size_t j = 0; j < count; ++j) {
        double cov[6];
        Eigen::Vector3f n1;
        float c1 = 0.f;
        const bool ok1 = detail::unitCovariance(moments[begin + j], cov) &&
                         detail::normalFromUnitCovariance(cov, n1, c1);
        expectScalarsAnswer(ok[j], n[j], curvature[j], ok1, n1, c1, begin + j, valid, invalid);
      }
    }
    begin += count;
  }
  EXPECT_GT(valid, 1000);
  EXPECT_GT(invalid, 300);
}

}  // namespace
}  // namespace upd::core
