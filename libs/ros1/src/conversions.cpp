#include "upd/ros1/conversions.h"

#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace upd::ros1 {

namespace {

std::string sizeText(std::size_t w, std::size_t h) {
  return std::to_string(w) + " x " + std::to_string(h);
}

template <class T>
T readAt(const std::vector<std::uint8_t>& data, std::size_t offset) {
  T v;
  std::memcpy(&v, data.data() + offset, sizeof v);
  return v;
}

// The offset of a float32 field, or throws naming it.
std::uint32_t floatField(const sensor_msgs::PointCloud2& msg, const char* name) {
  for (const auto& f : msg.fields) {
    if (f.name != name) continue;
    if (f.datatype != sensor_msgs::PointField::FLOAT32 || f.count != 1) {
      throw MessageError(std::string("PointCloud2 field '") + name + "': datatype " +
                         std::to_string(f.datatype) + ", expected FLOAT32 (7)");
    }
    if (f.offset + 4 > msg.point_step) {
      throw MessageError(std::string("PointCloud2 field '") + name + "': offset " +
                         std::to_string(f.offset) + " beyond point_step " +
                         std::to_string(msg.point_step));
    }
    return f.offset;
  }
  throw MessageError(std::string("PointCloud2 has no field '") + name + "'");
}

}  // namespace

core::CameraIntrinsics intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& info) {
  if (info.width == 0 || info.height == 0) {
    throw MessageError("CameraInfo size " + sizeText(info.width, info.height) + ": must be > 0");
  }
  core::CameraIntrinsics K;
  K.width = static_cast<int>(info.width);
  K.height = static_cast<int>(info.height);
  K.fx = info.K[0];
  K.cx = info.K[2];
  K.fy = info.K[4];
  K.cy = info.K[5];
  if (!(K.fx > 0) || !(K.fy > 0) || !std::isfinite(K.cx) || !std::isfinite(K.cy)) {
    throw MessageError("CameraInfo K: fx = " + std::to_string(K.fx) + ", fy = " +
                       std::to_string(K.fy) + " (zero intrinsics: the camera is not calibrated)");
  }
  return K;
}

sensor_msgs::CameraInfo cameraInfoFromIntrinsics(const core::CameraIntrinsics& K) {
  sensor_msgs::CameraInfo info;
  info.width = static_cast<std::uint32_t>(K.width);
  info.height = static_cast<std::uint32_t>(K.height);
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  info.K = {K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {K.fx, 0, K.cx, 0, 0, K.fy, K.cy, 0, 0, 0, 1, 0};
  return info;
}

core::DepthImage depthFromImage(const sensor_msgs::Image& image) {
  namespace enc = sensor_msgs::image_encodings;
  const bool mm = image.encoding == enc::TYPE_16UC1 || image.encoding == enc::MONO16;
  const bool metres = image.encoding == enc::TYPE_32FC1;
  if (!mm && !metres) {
    throw MessageError("depth Image encoding '" + image.encoding +
                       "': expected 16UC1 (millimetres) or 32FC1 (metres)");
  }
  if (image.is_bigendian) throw MessageError("depth Image is_bigendian = 1: not supported");
  const std::size_t px = mm ? 2 : 4;
  const std::size_t w = image.width, h = image.height;
  if (w == 0 || h == 0 || image.step < w * px || image.data.size() != image.step * h) {
    throw MessageError("depth Image " + sizeText(w, h) + " " + image.encoding + ": step " +
                       std::to_string(image.step) + " and " + std::to_string(image.data.size()) +
                       " bytes of data do not match");
  }
  core::DepthImage depth;
  depth.width = static_cast<int>(w);
  depth.height = static_cast<int>(h);
  depth.depth_m.resize(w * h);
  for (std::size_t v = 0; v < h; ++v) {
    for (std::size_t u = 0; u < w; ++u) {
      const std::size_t off = v * image.step + u * px;
      const float d = mm ? readAt<std::uint16_t>(image.data, off) * 0.001f
                         : readAt<float>(image.data, off);
      depth.depth_m[v * w + u] = std::isfinite(d) && d > 0 ? d : 0.f;
    }
  }
  return depth;
}

sensor_msgs::Image imageFromDepth(const core::DepthImage& depth, const std::string& encoding) {
  namespace enc = sensor_msgs::image_encodings;
  if (encoding != enc::TYPE_16UC1 && encoding != enc::TYPE_32FC1) {
    throw std::invalid_argument("imageFromDepth: encoding '" + encoding +
                                "', expected 16UC1 or 32FC1");
  }
  const bool mm = encoding == enc::TYPE_16UC1;
  const std::size_t px = mm ? 2 : 4;
  sensor_msgs::Image image;
  image.width = static_cast<std::uint32_t>(depth.width);
  image.height = static_cast<std::uint32_t>(depth.height);
  image.encoding = encoding;
  image.is_bigendian = 0;
  image.step = static_cast<std::uint32_t>(depth.width * px);
  image.data.resize(image.step * image.height);
  for (std::size_t i = 0; i < depth.depth_m.size(); ++i) {
    const float d = depth.depth_m[i];
    const bool valid = std::isfinite(d) && d > 0;
    if (mm) {
      const std::uint16_t v =
          valid ? static_cast<std::uint16_t>(std::min(65535.0f, std::round(d * 1000.f))) : 0;
      std::memcpy(image.data.data() + i * px, &v, px);
    } else {
      const float v = valid ? d : std::numeric_limits<float>::quiet_NaN();
      std::memcpy(image.data.data() + i * px, &v, px);
    }
  }
  return image;
}

core::PointCloud cloudFromDepthImage(const sensor_msgs::Image& image,
                                     const sensor_msgs::CameraInfo& info) {
  return cloudFromDepthImage(depthFromImage(image), info);
}

core::PointCloud cloudFromDepthImage(const core::DepthImage& depth,
                                     const sensor_msgs::CameraInfo& info) {
  return core::depthToCloud(depth, intrinsicsForDepth(depth, info));
}

core::CameraIntrinsics intrinsicsForDepth(const core::DepthImage& depth,
                                          const sensor_msgs::CameraInfo& info) {
  const core::CameraIntrinsics K = intrinsicsFromCameraInfo(info);
  if (depth.width != K.width || depth.height != K.height) {
    throw MessageError("depth image " + sizeText(depth.width, depth.height) +
                       " but CameraInfo " + sizeText(info.width, info.height));
  }
  return K;
}

core::PointCloud cloudFromPointCloud2(const sensor_msgs::PointCloud2& msg) {
  if (msg.is_bigendian) throw MessageError("PointCloud2 is_bigendian = 1: not supported");
  const std::uint32_t ox = floatField(msg, "x"), oy = floatField(msg, "y"),
                      oz = floatField(msg, "z");
  const std::size_t w = msg.width, h = msg.height;
  if (msg.row_step < w * msg.point_step || msg.data.size() != std::size_t{msg.row_step} * h) {
    throw MessageError("PointCloud2 " + sizeText(w, h) + ": point_step " +
                       std::to_string(msg.point_step) + ", row_step " +
                       std::to_string(msg.row_step) + " and " + std::to_string(msg.data.size()) +
                       " bytes of data do not match");
  }
  core::PointCloud cloud;
  cloud.x.resize(w * h);
  cloud.y.resize(w * h);
  cloud.z.resize(w * h);
  for (std::size_t v = 0; v < h; ++v) {
    for (std::size_t u = 0; u < w; ++u) {
      const std::size_t base = v * msg.row_step + u * msg.point_step, i = v * w + u;
      cloud.x[i] = readAt<float>(msg.data, base + ox);
      cloud.y[i] = readAt<float>(msg.data, base + oy);
      cloud.z[i] = readAt<float>(msg.data, base + oz);
    }
  }
  cloud.width = h > 1 ? w : w * h;
  cloud.height = h > 1 ? h : 1;
  return cloud;
}

sensor_msgs::PointCloud2 pointCloud2FromCloud(const core::PointCloud& cloud) {
  sensor_msgs::PointCloud2 msg;
  sensor_msgs::PointCloud2Modifier mod(msg);
  mod.setPointCloud2FieldsByString(1, "xyz");
  const bool organized = cloud.isOrganized();
  mod.resize(cloud.size());
  msg.width = static_cast<std::uint32_t>(organized ? cloud.width : cloud.size());
  msg.height = static_cast<std::uint32_t>(organized ? cloud.height : 1);
  msg.row_step = msg.width * msg.point_step;
  msg.is_dense = false;
  sensor_msgs::PointCloud2Iterator<float> it(msg, "x");
  for (std::size_t i = 0; i < cloud.size(); ++i, ++it) {
    it[0] = cloud.x[i];
    it[1] = cloud.y[i];
    it[2] = cloud.z[i];
  }
  return msg;
}

sensor_msgs::PointCloud2 pointCloud2FromScored(const core::ScoredFrame& frame) {
  using sensor_msgs::PointField;
  sensor_msgs::PointCloud2 msg;
  sensor_msgs::PointCloud2Modifier mod(msg);
  mod.setPointCloud2Fields(6, "x", 1, PointField::FLOAT32, "y", 1, PointField::FLOAT32, "z", 1,
                           PointField::FLOAT32, "zeta", 1, PointField::FLOAT32, "label", 1,
                           PointField::UINT8, "cost", 1, PointField::FLOAT32);
  const core::PointCloud& c = frame.cloud_world;
  mod.resize(c.size());
  msg.is_dense = false;
  // The label byte leaves every float after it unaligned (a point is 21 bytes): the floats are
  // copied in byte by byte (a float reference there is undefined behaviour; UBSan).
  using Bytes = sensor_msgs::PointCloud2Iterator<std::uint8_t>;
  Bytes xyz(msg, "x"), zeta(msg, "zeta"), cost(msg, "cost"), label(msg, "label");
  const auto put = [](Bytes& field, std::size_t k, float v) {
    std::memcpy(&field[k * sizeof(float)], &v, sizeof v);
  };
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const auto& cl = frame.classes;
  for (std::size_t i = 0; i < c.size(); ++i, ++xyz, ++zeta, ++cost, ++label) {
    put(xyz, 0, c.x[i]);
    put(xyz, 1, c.y[i]);
    put(xyz, 2, c.z[i]);
    put(zeta, 0, i < frame.upd.zeta.size() ? frame.upd.zeta[i] : nan);
    *label = static_cast<std::uint8_t>(i < cl.label.size() ? cl.label[i] : core::Label::Unknown);
    put(cost, 0, i < cl.cost.size() ? cl.cost[i] : nan);
  }
  return msg;
}

std::int8_t occupancyOf(const maps::GridCell& cell, const maps::GridParams& params) {
  const float p = maps::probabilityOf(cell, params);
  if (!std::isfinite(p)) return -1;
  return static_cast<std::int8_t>(std::lround(std::clamp(p, 0.f, 1.f) * 100.f));
}

nav_msgs::OccupancyGrid occupancyGridFromGrid(const maps::TraversabilityGrid& grid) {
  nav_msgs::OccupancyGrid msg;
  msg.info.resolution = static_cast<float>(grid.cellSize());
  msg.info.width = static_cast<std::uint32_t>(grid.sizeX());
  msg.info.height = static_cast<std::uint32_t>(grid.sizeY());
  msg.info.origin.position.x = grid.xMin();
  msg.info.origin.position.y = grid.yMin();
  msg.info.origin.orientation.w = 1.0;
  msg.data.resize(static_cast<std::size_t>(grid.sizeX()) * grid.sizeY());
  for (int cy = 0; cy < grid.sizeY(); ++cy) {
    for (int cx = 0; cx < grid.sizeX(); ++cx) {
      msg.data[static_cast<std::size_t>(cy) * grid.sizeX() + cx] =
          occupancyOf(grid.at(cx, cy), grid.params());
    }
  }
  return msg;
}

visualization_msgs::MarkerArray routeMarkers(const std::vector<Eigen::Vector2d>& path_world,
                                             const std::vector<Eigen::Vector2d>& waypoints,
                                             const std::string& frame_id) {
  visualization_msgs::MarkerArray array;
  const auto make = [&](int id, int type, const std::vector<Eigen::Vector2d>& pts) {
    visualization_msgs::Marker m;
    m.header.frame_id = frame_id;
    m.ns = "upd_route";
    m.id = id;
    m.type = type;
    m.action = pts.empty() ? visualization_msgs::Marker::DELETE : visualization_msgs::Marker::ADD;
    m.pose.orientation.w = 1.0;
    m.scale.x = m.scale.y = m.scale.z = type == visualization_msgs::Marker::LINE_STRIP ? 0.05 : 0.15;
    m.color.a = 1.0;
    m.color.b = type == visualization_msgs::Marker::LINE_STRIP ? 1.0 : 0.0;
    m.color.r = type == visualization_msgs::Marker::LINE_STRIP ? 0.0 : 1.0;
    for (const auto& p : pts) {
      geometry_msgs::Point q;
      q.x = p.x();
      q.y = p.y();
      m.points.push_back(q);
    }
    array.markers.push_back(m);
  };
  make(0, visualization_msgs::Marker::LINE_STRIP, path_world);
  make(1, visualization_msgs::Marker::SPHERE_LIST, waypoints);
  return array;
}

Eigen::Isometry3d isometryFromTransform(const geometry_msgs::Transform& t) {
  Eigen::Quaterniond q(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z);
  if (!(q.norm() > 1e-9)) throw MessageError("transform with a zero quaternion");
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = q.normalized().toRotationMatrix();
  pose.translation() = Eigen::Vector3d(t.translation.x, t.translation.y, t.translation.z);
  return pose;
}

geometry_msgs::TransformStamped stampedTransform(const Eigen::Isometry3d& pose,
                                                 const std::string& parent_frame,
                                                 const std::string& child_frame, const ros::Time& stamp) {
  geometry_msgs::TransformStamped s;
  s.header.frame_id = parent_frame;
  s.header.stamp = stamp;
  s.child_frame_id = child_frame;
  s.transform = transformFromIsometry(pose);
  return s;
}

geometry_msgs::Transform transformFromIsometry(const Eigen::Isometry3d& pose) {
  geometry_msgs::Transform t;
  const Eigen::Quaterniond q(pose.linear());
  t.translation.x = pose.translation().x();
  t.translation.y = pose.translation().y();
  t.translation.z = pose.translation().z();
  t.rotation.x = q.x();
  t.rotation.y = q.y();
  t.rotation.z = q.z();
  t.rotation.w = q.w();
  return t;
}

}  // namespace upd::ros1
