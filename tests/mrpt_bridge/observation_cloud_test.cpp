// Each MRPT observation type converts to a cloud in the robot frame (x forward, y left, z up).
#include "upd/mrpt_bridge/observation_cloud.h"
#include "temp_dir.h"
#include "test_data.h"
#include "upd/mrpt_bridge/pose_source.h"
#include "upd/mrpt_bridge/rawlog_reader.h"

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CColouredPointsMap.h>
#include <mrpt/maps/CPointsMapXYZI.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRotatingScan.h>
#include <mrpt/obs/CObservationVelodyneScan.h>
#include <mrpt/obs/VelodyneCalibration.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/serialization/CSerializable.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <filesystem>
#include <vector>

namespace core = upd::core;

namespace {

using upd::core::PointCloud;
using upd::mrpt_bridge::ObservationCloud;
using upd::mrpt_bridge::RawlogEntry;
using upd::mrpt_bridge::RawlogReader;
using upd::mrpt_bridge::SourceParams;
using upd::mrpt_bridge::toCloud;

std::shared_ptr<mrpt::obs::CObservation> firstObservation(const std::string& path) {
  RawlogReader reader(path);
  RawlogEntry e;
  if (!reader.next(e)) return nullptr;
  return e.observation;
}

// A 3D range scan with two points and no range image.
mrpt::obs::CObservation3DRangeScan twoPointScan() {
  mrpt::obs::CObservation3DRangeScan scan;
  scan.hasPoints3D = true;
  scan.resizePoints3DVectors(2);
  scan.points3D_x = {1.f, 2.f};
  scan.points3D_y = {0.f, 1.f};
  scan.points3D_z = {0.f, -1.f};
  return scan;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

TEST(ObservationCloud, RangeScanGroundFloorAtZeroInRobotFrame) {
  UPD_REQUIRE_SHARED_FILE(path, "mrpt/test-3d-obs-ground.rawlog");
  const auto obs = firstObservation(path);
  ASSERT_TRUE(obs);
  const auto& scan = dynamic_cast<const mrpt::obs::CObservation3DRangeScan&>(*obs);
  const ObservationCloud oc = toCloud(*obs);
  ASSERT_TRUE(oc.ok()) << oc.skipped_reason;
  EXPECT_EQ(oc.source_class, "CObservation3DRangeScan");
  const core::PointCloud& c = oc.cloud_in_robot;
  ASSERT_TRUE(oc.organized());
  EXPECT_EQ(c.width, 320u);
  EXPECT_EQ(c.height, 240u);
  // NaN exactly where the range image holds no return; pixel (u, v) is point v * 320 + u.
  std::size_t zero_ranges = 0;
  for (int v = 0; v < 240; ++v) {
    for (int u = 0; u < 320; ++u) {
      const bool invalid = scan.rangeImage(v, u) == 0;
      zero_ranges += invalid ? 1 : 0;
      EXPECT_EQ(invalid, !c.isFinite(static_cast<std::size_t>(v) * 320 + u));
    }
  }
  const std::size_t valid = c.countFinite();
  EXPECT_EQ(valid + zero_ranges, 320u * 240u);
  EXPECT_NEAR(static_cast<double>(valid), 37662.0, 200.0);
  std::vector<double> abs_z;
  std::size_t within = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!c.isFinite(i)) continue;
    abs_z.push_back(std::abs(c.z[i]));
    within += std::abs(c.z[i]) <= 0.05f ? 1 : 0;
  }
  EXPECT_LT(median(abs_z), 0.03);
  EXPECT_GE(static_cast<double>(within), 0.8 * static_cast<double>(valid));
  // The sensor sits 1.27 m above the floor, looking down and forward.
  EXPECT_NEAR(c.sensor_origin.z(), 1.273, 0.01);
  EXPECT_NEAR(oc.sensor_pose_on_robot.translation().z(), 1.273, 0.01);
  EXPECT_TRUE(c.hasColor());
}

// Our organized conversion gives the same points as MRPT's own unprojectInto.
TEST(ObservationCloud, RangeScanMatchesMrptUnprojectInto) {
  UPD_REQUIRE_SHARED_FILE(path, "mrpt/tests_rgbd.rawlog");
  const auto obs = firstObservation(path);
  ASSERT_TRUE(obs);
  auto& scan = dynamic_cast<mrpt::obs::CObservation3DRangeScan&>(*obs);
  const mrpt::poses::CPose3D sensor_pose(0.1, -0.2, 0.5, 0.3, -0.2, 0.1);
  scan.sensorPose = sensor_pose;
  const ObservationCloud oc = toCloud(scan);
  ASSERT_TRUE(oc.ok()) << oc.skipped_reason;
  mrpt::maps::CSimplePointsMap reference;
  mrpt::obs::T3DPointsProjectionParams pp;
  pp.takeIntoAccountSensorPoseOnRobot = true;
  scan.unprojectInto(reference, pp);
  const auto& xs = reference.getPointsBufferRef_x();
  const auto& ys = reference.getPointsBufferRef_y();
  const auto& zs = reference.getPointsBufferRef_z();
  ASSERT_EQ(xs.size(), scan.points3D_idxs_x.size());
  ASSERT_EQ(oc.cloud_in_robot.countFinite(), xs.size());
  for (std::size_t k = 0; k < xs.size(); k += 97) {
    const std::size_t i =
        static_cast<std::size_t>(scan.points3D_idxs_y[k]) * 640 + scan.points3D_idxs_x[k];
    EXPECT_NEAR(oc.cloud_in_robot.x[i], xs[k], 1e-4);
    EXPECT_NEAR(oc.cloud_in_robot.y[i], ys[k], 1e-4);
    EXPECT_NEAR(oc.cloud_in_robot.z[i], zs[k], 1e-4);
  }
  EXPECT_TRUE(oc.cloud_in_robot.sensor_origin.isApprox(Eigen::Vector3f(0.1f, -0.2f, 0.5f), 1e-6f));
}

TEST(ObservationCloud, RgbdRawlogIsOrganized640x480) {
  UPD_REQUIRE_SHARED_FILE(path, "mrpt/tests_rgbd.rawlog");
  const auto obs = firstObservation(path);
  ASSERT_TRUE(obs);
  const ObservationCloud oc = toCloud(*obs);
  ASSERT_TRUE(oc.ok()) << oc.skipped_reason;
  const core::PointCloud& c = oc.cloud_in_robot;
  EXPECT_EQ(c.width, 640u);
  EXPECT_EQ(c.height, 480u);
  EXPECT_TRUE(oc.organized());
  const double valid = static_cast<double>(c.countFinite());
  EXPECT_NEAR(valid, 273225.0, 0.01 * 273225.0);
  // The sensor frame: x forward is depth, 1.6-2.6 m to the bookshelf.
  std::vector<double> xs;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (c.isFinite(i)) xs.push_back(c.x[i]);
  }
  const auto [lo, hi] = std::minmax_element(xs.begin(), xs.end());
  EXPECT_GT(*lo, 1.0);
  EXPECT_LT(*hi, 3.2);
  ASSERT_TRUE(c.hasColor());
  // Colours vary (a real RGB image mapped through the intensity camera).
  std::size_t distinct_red = 0;
  std::vector<bool> seen(256, false);
  for (std::size_t i = 0; i < c.size(); i += 7) {
    if (!c.isFinite(i) || seen[c.r[i]]) continue;
    seen[c.r[i]] = true;
    ++distinct_red;
  }
  EXPECT_GT(distinct_red, 50u);

  SourceParams no_color;
  no_color.color_enabled = false;
  EXPECT_FALSE(toCloud(*obs, no_color).cloud_in_robot.hasColor());
}

// One ObservationCloud reused across observations of different kinds (a colour RGB-D frame, an
// observation without points, a points-only scan, the RGB-D frame again) holds what a fresh
// conversion gives each time: nothing left over from the one before.
bool sameCloud(const core::PointCloud& a, const core::PointCloud& b) {
  if (a.size() != b.size() || a.width != b.width || a.height != b.height || a.r != b.r ||
      a.g != b.g || a.b != b.b || a.sensor_origin != b.sensor_origin) {
    return false;
  }
  for (std::size_t i = 0; i < a.size(); ++i) {
    const bool nan = std::isnan(a.x[i]);
    if (nan != std::isnan(b.x[i])) return false;
    if (!nan && (a.x[i] != b.x[i] || a.y[i] != b.y[i] || a.z[i] != b.z[i])) return false;
  }
  return true;
}

TEST(ObservationCloud, ReusedConversionEqualsAFreshOne) {
  UPD_REQUIRE_SHARED_FILE(path, "mrpt/tests_rgbd.rawlog");
  const auto rgbd = firstObservation(path);
  ASSERT_TRUE(rgbd);
  const mrpt::obs::CObservation3DRangeScan points_only = twoPointScan();
  mrpt::obs::CObservation2DRangeScan planar;
  const SourceParams params;
  ObservationCloud reused;
  const std::vector<const mrpt::obs::CObservation*> sequence = {rgbd.get(), &planar, &points_only,
                                                                rgbd.get()};
  for (std::size_t k = 0; k < sequence.size(); ++k) {
    const std::size_t capacity = reused.cloud_in_robot.x.capacity();
    toCloud(*sequence[k], params, reused);
    // A skipped observation (the planar scan) empties the cloud but keeps its buffers.
    if (!reused.ok()) {
      EXPECT_GE(reused.cloud_in_robot.x.capacity(), capacity) << "observation " << k;
    }
    const ObservationCloud fresh = toCloud(*sequence[k], params);
    EXPECT_EQ(reused.skipped_reason, fresh.skipped_reason) << "observation " << k;
    EXPECT_EQ(reused.source_class, fresh.source_class) << "observation " << k;
    EXPECT_TRUE(reused.sensor_pose_on_robot.isApprox(fresh.sensor_pose_on_robot));
    EXPECT_TRUE(sameCloud(reused.cloud_in_robot, fresh.cloud_in_robot)) << "observation " << k;
  }
  EXPECT_TRUE(reused.cloud_in_robot.hasColor());  // the last one is the colour frame
}

// A rawlog whose range and intensity images live in "<name>_Images/" next to it (what MRPT's
// grabbers write): the reader points MRPT there and the conversion loads them; a missing file
// is a skip with a reason, not a crash.
TEST(ObservationCloud, ExternallyStoredImagesAreLoaded) {
  UPD_REQUIRE_SHARED_FILE(path, "mrpt/test-3d-obs-ground.rawlog");
  const auto obs = firstObservation(path);
  ASSERT_TRUE(obs);
  const ObservationCloud reference = toCloud(*obs);
  ASSERT_TRUE(reference.ok());

  namespace fs = std::filesystem;
  const upd::test::TempDir tmp("external_images");
  const fs::path& dir = tmp.path();
  const fs::path images = dir / "ext_Images";
  fs::create_directories(images);
  const fs::path rawlog = dir / "ext.rawlog";
  {
    auto& scan = dynamic_cast<mrpt::obs::CObservation3DRangeScan&>(*obs);
    scan.rangeImage_convertToExternalStorage("ground_range.bin", images.string() + "/");
    ASSERT_TRUE(scan.intensityImage.saveToFile((images / "ground_ir.png").string()));
    scan.intensityImage.setExternalStorage("ground_ir.png");
    mrpt::io::CFileGZOutputStream out(rawlog.string());
    auto ar = mrpt::serialization::archiveFrom(out);
    ar << *obs;
  }
  ASSERT_TRUE(fs::exists(images / "ground_range.bin"));
  {
    RawlogReader reader(rawlog.string());
    EXPECT_EQ(fs::path(reader.imagesDirectory()), images);
    RawlogEntry e;
    ASSERT_TRUE(reader.next(e));
    const auto& scan = dynamic_cast<const mrpt::obs::CObservation3DRangeScan&>(*e.observation);
    ASSERT_TRUE(scan.rangeImage_isExternallyStored());
    ASSERT_TRUE(scan.intensityImage.isExternallyStored());
    const ObservationCloud oc = toCloud(*e.observation);
    ASSERT_TRUE(oc.ok()) << oc.skipped_reason;
    ASSERT_EQ(oc.cloud_in_robot.size(), reference.cloud_in_robot.size());
    EXPECT_EQ(oc.cloud_in_robot.countFinite(), reference.cloud_in_robot.countFinite());
    for (std::size_t i = 0; i < oc.cloud_in_robot.size(); i += 31) {
      if (!reference.cloud_in_robot.isFinite(i)) continue;
      EXPECT_TRUE(oc.cloud_in_robot.point(i).isApprox(reference.cloud_in_robot.point(i), 1e-6f));
    }
    EXPECT_TRUE(oc.cloud_in_robot.hasColor());
  }
  fs::remove(images / "ground_range.bin");
  {
    RawlogReader reader(rawlog.string());
    RawlogEntry e;
    ASSERT_TRUE(reader.next(e));
    const ObservationCloud oc = toCloud(*e.observation);
    EXPECT_FALSE(oc.ok());
    EXPECT_NE(oc.skipped_reason.find("externally stored"), std::string::npos) << oc.skipped_reason;
  }
}

TEST(ObservationCloud, RangeScanRangeIsNotDepth) {
  // One pixel at the image centre and one in a corner, ranges (not depths) of 2 m.
  mrpt::obs::CObservation3DRangeScan scan;
  scan.hasRangeImage = true;
  scan.rangeImage_setSize(3, 4);
  scan.rangeImage.setZero();
  scan.cameraParams.ncols = 4;
  scan.cameraParams.nrows = 3;
  scan.cameraParams.setIntrinsicParamsFromValues(2.0, 2.0, 1.5, 1.0);
  scan.rangeUnits = 0.001f;
  scan.rangeImage(1, 1) = 2000;  // u = 1, v = 1
  scan.rangeImage(0, 3) = 2000;  // u = 3, v = 0
  for (bool is_depth : {true, false}) {
    scan.range_is_depth = is_depth;
    const ObservationCloud oc = toCloud(scan);
    ASSERT_TRUE(oc.ok()) << oc.skipped_reason;
    const core::PointCloud& c = oc.cloud_in_robot;
    ASSERT_EQ(c.width, 4u);
    ASSERT_EQ(c.height, 3u);
    EXPECT_EQ(c.countFinite(), 2u);
    const std::size_t corner = 0 * 4 + 3;
    const Eigen::Vector3f p = c.point(corner);
    // Ray direction in the MRPT sensor frame: (1, -(u - cx) / fx, -(v - cy) / fy).
    const Eigen::Vector3f dir(1.f, -(3 - 1.5f) / 2.f, -(0 - 1.0f) / 2.f);
    if (is_depth) {
      EXPECT_NEAR(p.x(), 2.0, 1e-4);
      EXPECT_TRUE(p.isApprox(2.f * dir, 1e-4f));
    } else {
      EXPECT_NEAR(p.norm(), 2.0, 1e-4);
      EXPECT_TRUE(p.isApprox(2.f * dir.normalized(), 1e-4f));
    }
  }
  scan.cameraParams.ncols = 5;  // does not match the range image
  const ObservationCloud bad = toCloud(scan);
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.skipped_reason.find("4x3"), std::string::npos) << bad.skipped_reason;
  EXPECT_TRUE(bad.cloud_in_robot.empty());
}

TEST(ObservationCloud, RangeScanWithOnlyPoints3DIsUnorganized) {
  mrpt::obs::CObservation3DRangeScan scan = twoPointScan();
  scan.sensorPose = mrpt::poses::CPose3D(0, 0, 1.0, 0, 0, 0);
  const ObservationCloud oc = toCloud(scan);
  ASSERT_TRUE(oc.ok()) << oc.skipped_reason;
  EXPECT_FALSE(oc.organized());
  ASSERT_EQ(oc.cloud_in_robot.size(), 2u);
  EXPECT_TRUE(oc.cloud_in_robot.point(1).isApprox(Eigen::Vector3f(2.f, 1.f, 0.f)));
  mrpt::obs::CObservation3DRangeScan nothing;
  EXPECT_EQ(toCloud(nothing).skipped_reason,
            "CObservation3DRangeScan has neither a range image nor 3D points");
}

// A sensor pose that is not finite (a corrupt observation) skips the observation with a reason
// and an empty cloud, instead of making the map's inputs NaN; a finite one converts.
TEST(ObservationCloud, SensorPoseNotFiniteSkipsTheObservation) {
  for (const double bad : {std::nan(""), std::numeric_limits<double>::infinity()}) {
    mrpt::obs::CObservation3DRangeScan scan = twoPointScan();
    scan.sensorPose = mrpt::poses::CPose3D(0, bad, 1.0, 0, 0, 0);
    const ObservationCloud oc = toCloud(scan);
    EXPECT_EQ(oc.skipped_reason,
              "CObservation3DRangeScan: its sensor pose on the robot is not finite");
    EXPECT_TRUE(oc.cloud_in_robot.empty());
    scan.sensorPose = mrpt::poses::CPose3D(0, 0, 1.0, 0, 0, bad);
    EXPECT_FALSE(toCloud(scan).ok());
    scan.sensorPose = mrpt::poses::CPose3D(0, 0, 1.0, 0, 0, 0);
    EXPECT_TRUE(toCloud(scan).ok());
  }
}

TEST(ObservationCloud, VelodyneGroundBelowTheSensor) {
  UPD_REQUIRE_SHARED_FILE(path, "mrpt/test_velodyne_VLP16.rawlog");
  const auto obs = firstObservation(path);
  ASSERT_TRUE(obs);
  const ObservationCloud oc = toCloud(*obs);
  ASSERT_TRUE(oc.ok()) << oc.skipped_reason;
  EXPECT_EQ(oc.source_class, "CObservationVelodyneScan");
  const core::PointCloud& c = oc.cloud_in_robot;
  EXPECT_FALSE(oc.organized());
  EXPECT_GT(c.countFinite(), 5000u);
  EXPECT_NEAR(c.sensor_origin.z(), 0.09, 1e-6);  // sensorPose z on the robot
  // z up: the ring of the lowest beam (-15 deg) hits the ground below the sensor, so the
  // lowest points are well below it and most points lie within the beams' +-15 deg fan.
  std::vector<double> z;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (c.isFinite(i)) z.push_back(c.z[i] - c.sensor_origin.z());
  }
  std::sort(z.begin(), z.end());
  EXPECT_LT(z[z.size() / 20], -0.5);  // the 5 % lowest: ground, below the sensor
  std::size_t in_fan = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!c.isFinite(i)) continue;
    const Eigen::Vector3f d = c.point(i) - c.sensor_origin;
    const double el = std::atan2(d.z(), std::hypot(d.x(), d.y()));
    in_fan += std::abs(el) < 16.0 * M_PI / 180.0 ? 1 : 0;
  }
  EXPECT_EQ(in_fan, c.countFinite());
  // The range limits apply.
  SourceParams near;
  near.lidar_max_range_m = 5.0;
  const core::PointCloud cn = toCloud(*obs, near).cloud_in_robot;
  EXPECT_LT(cn.size(), c.size());
  for (std::size_t i = 0; i < cn.size(); ++i) {
    EXPECT_LE((cn.point(i) - cn.sensor_origin).norm(), 5.0f + 1e-3f);
  }
}

TEST(ObservationCloud, PointCloudObservationRoundTripsWithSensorPose) {
  auto map = mrpt::maps::CColouredPointsMap::Create();
  map->insertPointRGB(1.f, 0.f, 0.f, 1.f, 0.f, 0.f);
  map->insertPointRGB(0.f, 2.f, 0.f, 0.f, 1.f, 0.f);
  map->insertPointRGB(0.f, 0.f, 3.f, 0.f, 0.f, 1.f);
  mrpt::obs::CObservationPointCloud obs;
  obs.pointcloud = map;
  // Sensor 1 m up, yawed 90 deg: its +x is the robot's +y.
  obs.sensorPose = mrpt::poses::CPose3D(0.5, 0.0, 1.0, M_PI / 2, 0.0, 0.0);
  // Through serialization, as it would come from a rawlog.
  mrpt::io::CMemoryStream buf;
  auto ar = mrpt::serialization::archiveFrom(buf);
  ar << obs;
  buf.Seek(0);
  mrpt::serialization::CSerializable::Ptr back;
  ar >> back;
  const auto read = std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(back);
  ASSERT_TRUE(read);
  const ObservationCloud oc = toCloud(*read);
  ASSERT_TRUE(oc.ok()) << oc.skipped_reason;
  const core::PointCloud& c = oc.cloud_in_robot;
  ASSERT_EQ(c.size(), 3u);
  EXPECT_FALSE(oc.organized());
  EXPECT_TRUE(c.point(0).isApprox(Eigen::Vector3f(0.5f, 1.f, 1.f), 1e-5f));
  EXPECT_TRUE(c.point(1).isApprox(Eigen::Vector3f(-1.5f, 0.f, 1.f), 1e-5f));
  EXPECT_TRUE(c.point(2).isApprox(Eigen::Vector3f(0.5f, 0.f, 4.f), 1e-5f));
  EXPECT_TRUE(c.sensor_origin.isApprox(Eigen::Vector3f(0.5f, 0.f, 1.f), 1e-6f));
  ASSERT_TRUE(c.hasColor());
  EXPECT_EQ(c.r[0], 255);
  EXPECT_EQ(c.g[1], 255);
  EXPECT_EQ(c.b[2], 255);
  EXPECT_EQ(c.r[1], 0);

  mrpt::obs::CObservationPointCloud empty;
  EXPECT_FALSE(toCloud(empty).ok());
}

// Colours and intensities outside MRPT's [0, 1] are clamped; a NaN one (damage) is black. A NaN
// converted to a byte as it is would be undefined behaviour (UBSan's float-cast-overflow).
TEST(ObservationCloud, PointCloudColoursAreClampedAndNaNIsBlack) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  auto col = mrpt::maps::CColouredPointsMap::Create();
  col->insertPointRGB(1.f, 0.f, 0.f, nan, -inf, 2.f);
  col->insertPointRGB(2.f, 0.f, 0.f, inf, -1.f, 0.5f);
  mrpt::obs::CObservationPointCloud obs;
  obs.pointcloud = col;
  ObservationCloud oc = toCloud(obs);
  ASSERT_TRUE(oc.ok()) << oc.skipped_reason;
  ASSERT_TRUE(oc.cloud_in_robot.hasColor());
  const PointCloud& c = oc.cloud_in_robot;
  EXPECT_EQ(std::vector<int>({c.r[0], c.g[0], c.b[0]}), std::vector<int>({0, 0, 255}));
  EXPECT_EQ(std::vector<int>({c.r[1], c.g[1], c.b[1]}), std::vector<int>({255, 0, 128}));

  auto xyzi = mrpt::maps::CPointsMapXYZI::Create();
  xyzi->insertPointFast(1.f, 0.f, 0.f);
  xyzi->insertPointFast(2.f, 0.f, 0.f);
  xyzi->setPointIntensity(0, nan);
  xyzi->setPointIntensity(1, 0.25f);
  obs.pointcloud = xyzi;
  oc = toCloud(obs);
  ASSERT_TRUE(oc.ok()) << oc.skipped_reason;
  ASSERT_TRUE(oc.cloud_in_robot.hasColor());
  EXPECT_EQ(oc.cloud_in_robot.r[0], 0);
  EXPECT_EQ(oc.cloud_in_robot.r[1], 64);
}

// Where the intensity camera is apart from the depth camera, each point is projected into it. A
// damaged intensity calibration (NaN or huge focal length) projects nowhere: every point stays
// white, as MRPT leaves the points outside the image (converted to an integer first, such a
// projection became pixel 0).
TEST(ObservationCloud, RangeScanDamagedIntensityCalibrationColoursNothing) {
  UPD_REQUIRE_SHARED_FILE(path, "mrpt/test-3d-obs-ground.rawlog");
  const auto obs = firstObservation(path);
  ASSERT_TRUE(obs);
  auto& scan = dynamic_cast<mrpt::obs::CObservation3DRangeScan&>(*obs);
  // 2.5 cm to the side; the rotation is MRPT's from the depth frame (x forward) to a camera's.
  scan.relativePoseIntensityWRTDepth =
      mrpt::poses::CPose3D(0.0, 0.025, 0.0, -M_PI / 2, 0.0, -M_PI / 2);
  ASSERT_FALSE(scan.doDepthAndIntensityCamerasCoincide());
  const auto coloured = [](const PointCloud& c) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
      n += c.isFinite(i) && (c.r[i] != 255 || c.g[i] != 255 || c.b[i] != 255);
    }
    return n;
  };
  const ObservationCloud sound = toCloud(*obs);
  ASSERT_TRUE(sound.ok()) << sound.skipped_reason;
  ASSERT_TRUE(sound.cloud_in_robot.hasColor());
  EXPECT_GT(coloured(sound.cloud_in_robot), sound.cloud_in_robot.countFinite() / 2);
  for (const double fx : {std::numeric_limits<double>::quiet_NaN(), 1e30}) {
    scan.cameraParamsIntensity.fx(fx);
    const ObservationCloud oc = toCloud(*obs);
    ASSERT_TRUE(oc.ok()) << oc.skipped_reason;
    EXPECT_EQ(oc.cloud_in_robot.countFinite(), sound.cloud_in_robot.countFinite());
    ASSERT_TRUE(oc.cloud_in_robot.hasColor());
    EXPECT_EQ(coloured(oc.cloud_in_robot), 0u) << "fx " << fx;
  }
}

// A VLP-16 looking at flat ground 1.5 m below it: every return lands on z = 0 in the robot frame.
TEST(ObservationCloud, RotatingScanOrganizedRingsOnFlatGround) {
  const auto& calib = mrpt::obs::VelodyneCalibration::LoadDefaultCalibration("VLP16");
  ASSERT_EQ(calib.laser_corrections.size(), 16u);
  mrpt::obs::CObservationRotatingScan scan;
  scan.lidarModel = "VLP-16";
  scan.rowCount = 16;
  scan.columnCount = 360;
  scan.rangeResolution = 0.002;
  scan.startAzimuth = -M_PI;
  scan.azimuthSpan = 2 * M_PI * 359.0 / 360.0;
  scan.minRange = 0.5;
  scan.maxRange = 100.0;
  const double height = 1.5;
  scan.sensorPose = mrpt::poses::CPose3D(0.2, 0.0, height, 0.0, 0.0, 0.0);
  scan.rangeImage.setZero(16, 360);
  std::size_t expected = 0;
  for (int r = 0; r < 16; ++r) {
    const double el = calib.laser_corrections[r].verticalCorrection * M_PI / 180.0;
    if (el >= 0) continue;  // upward beams see nothing
    const double range = height / std::sin(-el);
    for (int col = 0; col < 360; ++col) {
      scan.rangeImage(r, col) = static_cast<uint16_t>(std::lround(range / scan.rangeResolution));
      ++expected;
    }
  }
  const ObservationCloud oc = toCloud(scan);
  ASSERT_TRUE(oc.ok()) << oc.skipped_reason;
  const core::PointCloud& c = oc.cloud_in_robot;
  EXPECT_EQ(c.width, 360u);
  EXPECT_EQ(c.height, 16u);
  EXPECT_EQ(c.countFinite(), expected);
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (c.isFinite(i)) {
      EXPECT_NEAR(c.z[i], 0.0, 0.01) << i;
    }
  }
  // Column 90 of the first downward ring: azimuth -pi + 90 deg = -90 deg, i.e. to the right.
  for (int r = 0; r < 16; ++r) {
    const std::size_t i = static_cast<std::size_t>(r) * 360 + 90;
    if (!c.isFinite(i)) continue;
    EXPECT_LT(c.y[i], -1.0f);
    EXPECT_NEAR(c.x[i], 0.2f, 0.05f);
    break;
  }

  scan.lidarModel = "MysteryLidar";
  const ObservationCloud unknown = toCloud(scan);
  EXPECT_FALSE(unknown.ok());
  EXPECT_NE(unknown.skipped_reason.find("MysteryLidar"), std::string::npos);
}

TEST(ObservationCloud, UnsupportedTypesGiveAReason) {
  mrpt::obs::CObservation2DRangeScan scan2d;
  const ObservationCloud a = toCloud(scan2d);
  EXPECT_FALSE(a.ok());
  EXPECT_EQ(a.skipped_reason, "CObservation2DRangeScan has no 3D points (a planar laser scan)");
  EXPECT_TRUE(a.cloud_in_robot.empty());
  mrpt::obs::CObservationComment comment;
  const ObservationCloud b = toCloud(comment);
  EXPECT_FALSE(b.ok());
  EXPECT_EQ(b.source_class, "CObservationComment");
  EXPECT_NE(b.skipped_reason.find("CObservationComment"), std::string::npos);
}

TEST(ObservationCloud, SourceParamsValidate) {
  SourceParams p;
  EXPECT_NO_THROW(p.validate());
  p.lidar_max_range_m = 0.5;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = SourceParams();
  p.stereo_fx_px = 400;  // the rest of the override missing
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("SourceParams.stereo_fy_px"), std::string::npos);
  }
  p = SourceParams();
  p.stereo.num_disparities_px = 40;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

}  // namespace
