// A point cloud as a structure of float arrays: the one data type every UPD algorithm reads.
//
// x, y, z are separate float vectors (as MRPT point maps and depth images give them), so
// algorithms can view the caller's buffers without copying. Colour is optional (empty vectors
// when absent). An organized cloud keeps its image layout (width x height, row-major) and marks
// invalid pixels with NaN coordinates; nothing is dropped. The sensor origin is where the rays
// start, in the cloud's frame: range cut-off and normal orientation use it.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace upd::core {

struct PointCloud {
  std::vector<float> x, y, z;
  std::vector<std::uint8_t> r, g, b;  ///< empty, or one entry per point
  std::size_t width = 0;              ///< columns when organized; else size()
  std::size_t height = 1;             ///< rows when organized; 1 when not
  Eigen::Vector3f sensor_origin = Eigen::Vector3f::Zero();  ///< [m], cloud frame

  std::size_t size() const { return x.size(); }
  bool empty() const { return x.empty(); }
  bool hasColor() const { return !r.empty() && r.size() == x.size(); }
  /// Invariant of an organized cloud: height > 1 and width * height == size().
  bool isOrganized() const { return height > 1 && width * height == x.size(); }

  Eigen::Vector3f point(std::size_t i) const { return {x[i], y[i], z[i]}; }
  bool isFinite(std::size_t i) const {
    return std::isfinite(x[i]) && std::isfinite(y[i]) && std::isfinite(z[i]);
  }

  void reserve(std::size_t n) {
    x.reserve(n);
    y.reserve(n);
    z.reserve(n);
  }
  void push_back(float px, float py, float pz) {
    x.push_back(px);
    y.push_back(py);
    z.push_back(pz);
    width = x.size();
    height = 1;
  }
  void push_back(float px, float py, float pz, std::uint8_t cr, std::uint8_t cg, std::uint8_t cb) {
    push_back(px, py, pz);
    r.push_back(cr);
    g.push_back(cg);
    b.push_back(cb);
  }
  /// n points: x, y and z, and r, g and b when with_colour (no colour otherwise); the values of
  /// the first min(n, size()) kept. The layout (width, height) is the caller's to set.
  void resize(std::size_t n, bool with_colour) {
    x.resize(n);
    y.resize(n);
    z.resize(n);
    r.resize(with_colour ? n : 0);
    g.resize(with_colour ? n : 0);
    b.resize(with_colour ? n : 0);
  }
  /// Makes the cloud an organized width x height image of NaN points (colour dropped).
  void resizeOrganized(std::size_t w, std::size_t h) {
    resizeOrganizedUnfilled(w, h);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::fill(x.begin(), x.end(), nan);
    std::fill(y.begin(), y.end(), nan);
    std::fill(z.begin(), z.end(), nan);
  }
  /// The same without the NaN: the points' values are left to a pass that writes every one.
  void resizeOrganizedUnfilled(std::size_t w, std::size_t h) {
    resize(w * h, false);
    width = w;
    height = h;
  }
  /// Number of points with finite coordinates (core::countFinite over the whole cloud).
  std::size_t countFinite() const;
};

/// The points of [begin, end) whose x, y and z are all finite (PointCloud::isFinite), counted
/// in a vector loop.
std::size_t countFinite(const PointCloud& cloud, std::size_t begin, std::size_t end);
/// The first point at or after from that is finite; size() when there is none. (A vector scan
/// a block at a time: an organized frame's NaN sky may fill a third of it.)
std::size_t firstFinite(const PointCloud& cloud, std::size_t from = 0);

/// out = in, reusing out's buffers; returns the number of finite points. The OpenMP team
/// copies the arrays in static shares, so that each thread writes the part of the cloud it
/// will read in the stages after: a serial copy rewrote the lines the other core had read in
/// the previous frame, at twice the cost of a copy on one core.
std::size_t copyCloud(const PointCloud& in, PointCloud& out);

/// Moves a cloud by a rigid transform: its points (NaN stays NaN; layout and colour kept) and
/// its sensor origin. Into out, reusing its buffers (a frame loop allocates nothing after the
/// first frame); out must not be cloud.
void transformCloud(const PointCloud& cloud, const Eigen::Isometry3d& transform, PointCloud& out);
PointCloud transformCloud(const PointCloud& cloud, const Eigen::Isometry3d& transform);

/// transformCloud in place: the cloud's points and sensor origin moved, its buffers kept (a
/// frame's results handed on without a copy; each thread moves the static share it wrote).
void transformInPlace(PointCloud& cloud, const Eigen::Isometry3d& transform);

/// (x_i, y_i, z_i) = rotation * (x_i, y_i, z_i) for n vectors, in place (normals, UPD vectors
/// r; NaN stays NaN). The three arrays must not overlap one another.
void rotateVectors(const Eigen::Matrix3f& rotation, std::size_t n, float* x, float* y, float* z);

/// Per-point ground truth and classification labels (values are stable: written to PLY files).
enum class Label : std::uint8_t { Traversable = 0, NonTraversable = 1, Unknown = 2 };

const char* toString(Label l);

}  // namespace upd::core
