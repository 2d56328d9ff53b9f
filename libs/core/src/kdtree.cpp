#include "upd/core/kdtree.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace upd::core {

KdTree::KdTree(const PointCloud& cloud, int leaf_size) : cloud_(cloud), leaf_size_(leaf_size) {
  if (leaf_size < 1) throw std::invalid_argument("KdTree leaf_size must be >= 1");
  if (cloud.y.size() != cloud.size() || cloud.z.size() != cloud.size()) {
    throw std::invalid_argument("PointCloud x, y, z have different sizes");
  }
  if (cloud.size() >= std::numeric_limits<std::uint32_t>::max()) {
    throw std::invalid_argument("PointCloud too large for the k-d tree (>= 2^32 points)");
  }
  index_.reserve(cloud.size());
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.isFinite(i)) continue;
    index_.push_back(static_cast<std::uint32_t>(i));
    const Eigen::Vector3d p = cloud.point(i).cast<double>();
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  if (index_.empty()) return;
  centre_ = (0.5 * (lo + hi)).cast<float>();
  pts_.resize(index_.size());
  for (std::size_t j = 0; j < index_.size(); ++j) pts_[j] = cloud.point(index_[j]) - centre_;
  nodes_.reserve(2 * index_.size() / static_cast<std::size_t>(leaf_size_) + 1);
  build(0, static_cast<std::uint32_t>(index_.size()));
}

std::int32_t KdTree::build(std::uint32_t begin, std::uint32_t end) {
  Node node;
  node.lo = node.hi = pts_[begin];
  for (std::uint32_t j = begin + 1; j < end; ++j) {
    node.lo = node.lo.cwiseMin(pts_[j]);
    node.hi = node.hi.cwiseMax(pts_[j]);
  }
  node.begin = begin;
  node.end = end;
  const auto id = static_cast<std::int32_t>(nodes_.size());
  nodes_.push_back(node);
  if (end - begin <= static_cast<std::uint32_t>(leaf_size_)) return id;
  int axis = 0;
  (node.hi - node.lo).maxCoeff(&axis);
  if (node.hi[axis] - node.lo[axis] <= 0.f) return id;  // all points equal: one leaf

  // Split at the median: a balanced tree whatever the density.
  const std::uint32_t mid = begin + (end - begin) / 2;
  std::vector<std::uint32_t> order(end - begin);
  for (std::uint32_t j = 0; j < order.size(); ++j) order[j] = begin + j;
  std::nth_element(order.begin(), order.begin() + (mid - begin), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return pts_[a][axis] < pts_[b][axis]; });
  std::vector<Eigen::Vector3f> p(order.size());
  std::vector<std::uint32_t> idx(order.size());
  for (std::size_t j = 0; j < order.size(); ++j) {
    p[j] = pts_[order[j]];
    idx[j] = index_[order[j]];
  }
  std::copy(p.begin(), p.end(), pts_.begin() + begin);
  std::copy(idx.begin(), idx.end(), index_.begin() + begin);

  nodes_[id].axis = static_cast<std::uint8_t>(axis);
  nodes_[id].split = pts_[mid][axis];
  const std::int32_t left = build(begin, mid);
  const std::int32_t right = build(mid, end);
  nodes_[id].left = left;
  nodes_[id].right = right;
  return id;
}

namespace {
// Squared distance from q to the axis-aligned box [lo, hi].
inline float boxDistSq(const Eigen::Vector3f& q, const Eigen::Vector3f& lo,
                       const Eigen::Vector3f& hi) {
  const Eigen::Vector3f d = (lo - q).cwiseMax(q - hi).cwiseMax(0.f);
  return d.squaredNorm();
}
}  // namespace

void KdTree::radiusSearch(const Eigen::Vector3f& q_world, float radius_m,
                          std::vector<std::uint32_t>& out) const {
  out.clear();
  if (nodes_.empty() || !(radius_m >= 0.f)) return;
  const Eigen::Vector3f q = q_world - centre_;
  const float r2 = radius_m * radius_m;
  std::int32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (boxDistSq(q, n.lo, n.hi) > r2) continue;
    if (n.left < 0) {
      for (std::uint32_t j = n.begin; j < n.end; ++j) {
        if ((pts_[j] - q).squaredNorm() <= r2) out.push_back(index_[j]);
      }
      continue;
    }
    stack[top++] = n.left;
    stack[top++] = n.right;
  }
}

void KdTree::knnSearch(const Eigen::Vector3f& q_world, int k, std::vector<std::uint32_t>& out,
                       std::vector<float>* dist_sq_m2) const {
  out.clear();
  if (dist_sq_m2) dist_sq_m2->clear();
  if (nodes_.empty() || k <= 0) return;
  const Eigen::Vector3f q = q_world - centre_;
  // The best k so far (distance, tree position), sorted nearest first with ties broken by cloud
  // index (so results are deterministic), in a buffer of the calling thread kept between
  // queries. k is small: a new point is inserted by shifting the farther ones.
  static thread_local std::vector<std::pair<float, std::uint32_t>> best;
  best.clear();
  const auto k_size = static_cast<std::size_t>(k);
  const auto before = [&](float d, std::uint32_t j, const std::pair<float, std::uint32_t>& b) {
    return d < b.first || (d == b.first && index_[j] < index_[b.second]);
  };
  auto worst = [&] {
    return best.size() < k_size ? std::numeric_limits<float>::infinity() : best.back().first;
  };
  // Best-first descent: nearer child first, prune by box distance.
  std::pair<float, std::int32_t> stack[128];
  int top = 0;
  stack[top++] = {0.f, 0};
  while (top > 0) {
    const auto [d_box, id] = stack[--top];
    if (d_box > worst()) continue;
    const Node& n = nodes_[id];
    if (n.left < 0) {
      for (std::uint32_t j = n.begin; j < n.end; ++j) {
        const float d = (pts_[j] - q).squaredNorm();
        if (best.size() == k_size && !before(d, j, best.back())) continue;
        if (best.size() < k_size) best.emplace_back();
        std::size_t pos = best.size() - 1;
        for (; pos > 0 && before(d, j, best[pos - 1]); --pos) best[pos] = best[pos - 1];
        best[pos] = {d, j};
      }
      continue;
    }
    const float dl = boxDistSq(q, nodes_[n.left].lo, nodes_[n.left].hi);
    const float dr = boxDistSq(q, nodes_[n.right].lo, nodes_[n.right].hi);
    if (dl <= dr) {
      stack[top++] = {dr, n.right};
      stack[top++] = {dl, n.left};
    } else {
      stack[top++] = {dl, n.left};
      stack[top++] = {dr, n.right};
    }
  }
  out.reserve(best.size());
  for (const auto& [d, j] : best) {
    out.push_back(index_[j]);
    if (dist_sq_m2) dist_sq_m2->push_back(d);
  }
}

}  // namespace upd::core
