#include "playback_bag.h"

#ifdef UPD_HAVE_ROS1

#include "upd/mrpt_bridge/gz_output_stream.h"
#include "upd/io/atomic_file.h"
#include "upd/ros1/bag_reader.h"
#include "upd/sim/robot.h"

#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/serialization/CArchive.h>

#include <malloc.h>

#include <cmath>
#include <cstdio>
#include <sstream>

namespace upd::app {

namespace {

mrpt::poses::CPose3D toMrpt(const Eigen::Isometry3d& p) {
  mrpt::math::CMatrixDouble44 m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = p.matrix()(r, c);
  return mrpt::poses::CPose3D(m);
}

// A depth frame as a Kinect-like range scan (millimetres) whose sensorPose is the camera body
// frame (x forward, y left, z up: MRPT's convention) on the robot.
mrpt::obs::CObservation::Ptr rangeScanOf(const ros1::BagFrame& f) {
  auto obs = mrpt::obs::CObservation3DRangeScan::Create();
  obs->sensorLabel = f.sensor_frame;
  obs->hasRangeImage = true;
  obs->range_is_depth = true;
  obs->rangeUnits = 0.001f;
  obs->rangeImage_setSize(f.K.height, f.K.width);
  for (int v = 0; v < f.K.height; ++v) {
    for (int u = 0; u < f.K.width; ++u) {
      const float d = f.depth.at(u, v);
      obs->rangeImage(v, u) = d > 0.f && std::isfinite(d)
                                  ? static_cast<std::uint16_t>(std::lround(std::min(d, 65.f) * 1000.f))
                                  : 0;
    }
  }
  obs->cameraParams.ncols = f.K.width;
  obs->cameraParams.nrows = f.K.height;
  obs->cameraParams.setIntrinsicParamsFromValues(f.K.fx, f.K.fy, f.K.cx, f.K.cy);
  obs->cameraParamsIntensity = obs->cameraParams;
  Eigen::Isometry3d optical_to_body = Eigen::Isometry3d::Identity();
  optical_to_body.linear() = sim::opticalInMount().transpose();
  obs->sensorPose = toMrpt(f.pose_base_sensor * optical_to_body);
  return obs;
}

mrpt::obs::CObservation::Ptr pointCloudOf(const ros1::BagFrame& f) {
  auto obs = mrpt::obs::CObservationPointCloud::Create();
  obs->sensorLabel = f.sensor_frame;
  auto points = mrpt::maps::CSimplePointsMap::Create();
  for (std::size_t i = 0; i < f.cloud.size(); ++i) {
    if (f.cloud.isFinite(i)) points->insertPoint(f.cloud.x[i], f.cloud.y[i], f.cloud.z[i]);
  }
  obs->pointcloud = points;
  obs->sensorPose = toMrpt(f.pose_base_sensor);
  return obs;
}

std::string tumLine(double t, const Eigen::Isometry3d& p) {
  const Eigen::Quaterniond q(p.linear());
  char line[256];
  std::snprintf(line, sizeof line, "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", t,
                p.translation().x(), p.translation().y(), p.translation().z(), q.x(), q.y(),
                q.z(), q.w());
  return line;
}

}  // namespace

std::optional<BagInput> convertBagInput(const std::string& path,
                                        const std::filesystem::path& out_dir) {
  if (!ros1::isBagPath(path)) return std::nullopt;
  std::filesystem::create_directories(out_dir);
  BagInput in;
  in.rawlog = (out_dir / "bag.rawlog").string();
  std::ostringstream tum;
  double last_pose_t = -1e300;
  ros1::BagReadStats stats;
  io::writeFileAtomicallyVia(in.rawlog, [&](const std::string& tmp) {
    {
      mrpt_bridge::GzOutputStream file(tmp);
      auto archive = mrpt::serialization::archiveFrom(file);
      stats = ros1::readBag(path, ros1::BagTopics{}, [&](const ros1::BagFrame& f) {
        mrpt::obs::CObservation::Ptr obs = f.from_depth ? rangeScanOf(f) : pointCloudOf(f);
        obs->timestamp = mrpt::Clock::fromDouble(f.stamp_s);
        archive << *obs;
        if (f.pose_world_base && f.stamp_s > last_pose_t) {
          tum << tumLine(f.stamp_s, *f.pose_world_base);
          last_pose_t = f.stamp_s;
        }
      });
      file.close();
    }
    // The bag's chunks, kept decompressed for the read, are freed now; the heap keeps freed
    // blocks for the frame loop (main's mallopt), so hand these back to the kernel.
    malloc_trim(0);
    if (stats.frames == 0) {
      std::string why;
      for (const auto& [reason, n] : stats.skipped) {
        why += "; " + std::to_string(n) + " x " + reason;
      }
      throw std::runtime_error(path + ": no depth or PointCloud2 frame with a sensor transform (" +
                               std::to_string(stats.messages) + " messages on the frame topics" +
                               why + ")");
    }
  });
  if (!tum.str().empty()) {
    in.poses = (out_dir / "bag_poses.tum").string();
    const std::string text = tum.str();
    io::writeFileAtomically(*in.poses, [&](std::ostream& os) { os << text; });
  }
  in.summary = path + ": " + std::to_string(stats.frames) + " frames -> " + in.rawlog +
               (in.poses ? ", robot poses (" + stats.world_frame + ") -> " + *in.poses
                         : std::string(", no robot poses in tf"));
  for (const auto& [reason, n] : stats.skipped) {
    in.summary += "; skipped " + std::to_string(n) + ": " + reason;
  }
  return in;
}

}  // namespace upd::app

#else

#include <stdexcept>

namespace upd::app {

std::optional<BagInput> convertBagInput(const std::string& path, const std::filesystem::path&) {
  if (path.size() < 4 || path.compare(path.size() - 4, 4, ".bag") != 0) return std::nullopt;
  throw std::runtime_error(path + ": upd was built without ROS 1, so it cannot read bags "
                           "(install the packages scripts/setup.sh lists and rebuild)");
}

}  // namespace upd::app

#endif
