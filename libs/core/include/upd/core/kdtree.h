// Exact neighbour search (paper eq. 1: all points within d_m, or the k nearest where data are
// sparse) over a PointCloud's own float buffers, without copying them.
//
// A static k-d tree in the spirit of nanoflann: results are indices into the cloud's x/y/z
// vectors, points with non-finite coordinates are never indexed, and every result equals a
// brute-force scan (tests check this). The tree keeps its own copy of the points, reordered
// leaf by leaf (cache locality) and relative to the bounding-box centre, so a cloud 10 km from
// the origin searches as precisely as one at the origin.
#pragma once

#include "upd/core/point_cloud.h"

#include <cstdint>
#include <vector>

namespace upd::core {

class KdTree {
 public:
  /// Indexes the finite points of cloud. The cloud must outlive the tree and stay unchanged.
  explicit KdTree(const PointCloud& cloud, int leaf_size = 16);

  /// Appends to out the indices of all indexed points p with |p - q|^2 <= radius_m^2
  /// (out is cleared first; the order is unspecified).
  void radiusSearch(const Eigen::Vector3f& q, float radius_m, std::vector<std::uint32_t>& out) const;

  /// The k nearest indexed points to q, nearest first (fewer when the cloud has fewer).
  /// dist_sq_m2 (optional) receives the squared distances.
  void knnSearch(const Eigen::Vector3f& q, int k, std::vector<std::uint32_t>& out,
                 std::vector<float>* dist_sq_m2 = nullptr) const;

  std::size_t indexedCount() const { return index_.size(); }
  const PointCloud& cloud() const { return cloud_; }

 private:
  struct Node {
    float split = 0.f;       // split value (inner nodes)
    std::uint32_t begin = 0;  // leaf: range in index_
    std::uint32_t end = 0;
    std::int32_t left = -1;  // -1 for a leaf
    std::int32_t right = -1;
    std::uint8_t axis = 0;
    Eigen::Vector3f lo, hi;  // bounding box of the node (local coordinates)
  };
  std::int32_t build(std::uint32_t begin, std::uint32_t end);
  Eigen::Vector3f local(std::uint32_t i) const { return pts_[i]; }

  const PointCloud& cloud_;
  int leaf_size_;
  Eigen::Vector3f centre_ = Eigen::Vector3f::Zero();
  std::vector<Eigen::Vector3f> pts_;  // local coordinates, indexed by position in index_
  std::vector<std::uint32_t> index_;  // cloud index of each entry of pts_
  std::vector<Node> nodes_;
};

}  // namespace upd::core
