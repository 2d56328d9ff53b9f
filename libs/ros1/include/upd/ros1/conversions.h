// ROS 1 messages <-> the project's types. Pure functions: no node, no master, no clock.
//
// In: sensor_msgs/Image (depth, 16UC1 in millimetres or 32FC1 in metres, camera-optical frame
// as REP 103 states for *_optical_frame), or its sensor_msgs/CompressedImage by image_transport's
// compressedDepth plugin, with its sensor_msgs/CameraInfo becomes a depth image and intrinsics,
// then an organized core::PointCloud; sensor_msgs/PointCloud2 with float32
// x, y, z becomes a core::PointCloud (organized when height > 1). geometry_msgs transforms
// become Eigen isometries.
// Out: the traversability grid as nav_msgs/OccupancyGrid (0 traversable ... 100
// non-traversable: the cell's fused probability of being non-traversable in percent; -1
// unknown), the scored points of a frame as sensor_msgs/PointCloud2 with fields x y z zeta
// label cost (float32, label uint8: 0 traversable, 1 non-traversable, 2 unknown), and a route
// as visualization_msgs/MarkerArray (the path as a line strip, the waypoints as spheres).
// A malformed message (unknown encoding, sizes that do not match, zero intrinsics, a missing
// field) throws MessageError with one line naming the message, field and value.
#pragma once

#include "upd/core/camera.h"
#include "upd/core/frame_scorer.h"
#include "upd/core/point_cloud.h"
#include "upd/maps/traversability_grid.h"

#include <Eigen/Geometry>
#include <geometry_msgs/Transform.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/OccupancyGrid.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <visualization_msgs/MarkerArray.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace upd::ros1 {

/// A message the layer cannot convert; what() is one line naming the field and value.
class MessageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Intrinsics from CameraInfo's K (fx = K[0], cx = K[2], fy = K[4], cy = K[5]) and its size.
/// Throws MessageError for a zero size or a focal length that is not > 0.
core::CameraIntrinsics intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& info);
/// CameraInfo of a pinhole camera without distortion (plumb_bob, D = 0).
sensor_msgs::CameraInfo cameraInfoFromIntrinsics(const core::CameraIntrinsics& K);

/// Depth [m] of a 16UC1 (millimetres) or 32FC1 (metres) image; 0 and NaN stay invalid (0).
/// Throws MessageError for another encoding, a step or data size that does not match
/// width x height, or a big-endian image.
core::DepthImage depthFromImage(const sensor_msgs::Image& image);
/// The depth image [m] of a compressed depth image, as image_transport's compressedDepth plugin
/// writes it: format "<encoding>; compressedDepth png" or "...; compressedDepth rvl" (the older
/// "<encoding>; compressedDepth" is PNG), data a 12-byte header (the format code, then the two
/// float parameters of a 32FC1 image's inverse-depth quantization) and the PNG or RVL stream of
/// 16-bit codes. 16UC1: the codes are millimetres; 32FC1: depth = p0 / (code - p1), code 0 no
/// return. Invalid pixels are 0. Throws MessageError for another format or encoding, a header or
/// stream that is short or damaged, or a size beyond kMaxCompressedDepthPixels.
core::DepthImage depthFromCompressedDepth(const sensor_msgs::CompressedImage& image);
/// The most pixels depthFromCompressedDepth decodes (a side at most 2^15).
constexpr std::uint64_t kMaxCompressedDepthPixels = std::uint64_t{1} << 25;
/// The topic image_transport's compressedDepth plugin publishes beside a raw depth topic.
inline std::string compressedDepthTopic(const std::string& depth_topic) {
  return depth_topic + "/compressedDepth";
}
/// The image of a depth image: "16UC1" (rounded to millimetres, 0 = invalid) or "32FC1".
sensor_msgs::Image imageFromDepth(const core::DepthImage& depth, const std::string& encoding);

/// The organized cloud of a depth image in its camera-optical frame (sensor origin 0). Throws
/// MessageError when the image and the camera info disagree on the size.
core::PointCloud cloudFromDepthImage(const sensor_msgs::Image& image,
                                     const sensor_msgs::CameraInfo& info);
/// The same for a depth image already decoded (depthFromImage, depthFromCompressedDepth).
core::PointCloud cloudFromDepthImage(const core::DepthImage& depth,
                                     const sensor_msgs::CameraInfo& info);
/// The intrinsics of info for the depth image depth: intrinsicsFromCameraInfo, and MessageError
/// when the two disagree on the size.
core::CameraIntrinsics intrinsicsForDepth(const core::DepthImage& depth,
                                          const sensor_msgs::CameraInfo& info);

/// The points of a PointCloud2 with float32 fields x, y, z (other fields ignored; organized
/// when height > 1, NaN points kept). Throws MessageError for a missing or non-float32 x, y or
/// z, a big-endian cloud, or a data size that does not match.
core::PointCloud cloudFromPointCloud2(const sensor_msgs::PointCloud2& msg);
/// A cloud as a PointCloud2 with float32 x, y, z (organized when the cloud is).
sensor_msgs::PointCloud2 pointCloud2FromCloud(const core::PointCloud& cloud);

/// The scored points of a frame (world frame) with fields x y z zeta label cost.
sensor_msgs::PointCloud2 pointCloud2FromScored(const core::ScoredFrame& frame);

/// The occupancy value of a cell: -1 unknown, else round(100 * P(non-traversable)).
std::int8_t occupancyOf(const maps::GridCell& cell, const maps::GridParams& params);
/// The grid (world frame) as an OccupancyGrid: resolution = cell size, origin = the window's
/// lower-left corner, row-major from y min. The header is left to the caller.
nav_msgs::OccupancyGrid occupancyGridFromGrid(const maps::TraversabilityGrid& grid);

/// The route (world xy, z = 0) as a MarkerArray: marker 0 the path (LINE_STRIP), marker 1 the
/// waypoints (SPHERE_LIST), both in frame_id; with no path both are DELETE actions.
visualization_msgs::MarkerArray routeMarkers(const std::vector<Eigen::Vector2d>& path_world,
                                             const std::vector<Eigen::Vector2d>& waypoints,
                                             const std::string& frame_id);

Eigen::Isometry3d isometryFromTransform(const geometry_msgs::Transform& t);
geometry_msgs::Transform transformFromIsometry(const Eigen::Isometry3d& pose);
/// pose (child_frame in parent_frame) as the transform tf publishes, stamped at stamp.
geometry_msgs::TransformStamped stampedTransform(const Eigen::Isometry3d& pose,
                                                 const std::string& parent_frame,
                                                 const std::string& child_frame, const ros::Time& stamp);

}  // namespace upd::ros1
