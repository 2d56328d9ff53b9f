// The UPD observer: MRPT observation + robot pose in, scored points in the world frame out.
#include "upd/mrpt_bridge/upd_observer.h"
#include "test_data.h"
#include "upd/mrpt_bridge/ini_params.h"
#include "upd/mrpt_bridge/pose_source.h"
#include "upd/mrpt_bridge/rawlog_reader.h"

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <unistd.h>

namespace core = upd::core;

namespace {

using upd::core::Label;
using upd::mrpt_bridge::ObserverParams;
using upd::mrpt_bridge::ObserverResult;
using upd::mrpt_bridge::UpdObserver;

std::shared_ptr<mrpt::obs::CObservation> groundScan() {
  const std::string path = upd::test::sharedFile("mrpt/test-3d-obs-ground.rawlog");
  if (path.empty()) return nullptr;
  upd::mrpt_bridge::RawlogReader reader(path);
  upd::mrpt_bridge::RawlogEntry e;
  return reader.next(e) ? e.observation : nullptr;
}

#define REQUIRE_GROUND_SCAN(var)                                      \
  const auto var = groundScan();                                      \
  if (!var) {                                                         \
    GTEST_SKIP() << "mrpt/test-3d-obs-ground.rawlog not found under " \
                 << upd::test::sharedDataDir();                       \
  }

void expectConsistentSizes(const ObserverResult& r) {
  const std::size_t n = r.size();
  EXPECT_EQ(r.scored.normals_world.size(), n);
  EXPECT_EQ(r.scored.upd.size(), n);
  EXPECT_EQ(r.scored.upd.rx.size(), n);
  EXPECT_EQ(r.scored.classes.label.size(), n);
  EXPECT_EQ(r.scored.classes.cost.size(), n);
  EXPECT_EQ(r.scored.classes.slope_rad.size(), n);
  const upd::core::Classification& c = r.scored.classes;
  EXPECT_EQ(c.traversable + c.non_traversable + c.unknown, n);
}

TEST(UpdObserver, FloorIsTraversableAtTheRobotsWorldPosition) {
  REQUIRE_GROUND_SCAN(obs);
  const UpdObserver observer;
  const mrpt::poses::CPose3D robot(12.0, -3.0, 0.25, 30.0 * M_PI / 180.0, 0, 0);
  const ObserverResult r = observer.observe(*obs, robot);
  ASSERT_TRUE(r.ok()) << r.skipped_reason;
  EXPECT_EQ(r.source_class, "CObservation3DRangeScan");
  EXPECT_TRUE(r.organized_input);
  EXPECT_NEAR(static_cast<double>(r.points_input), 37662.0, 200.0);
  ASSERT_GT(r.size(), 1000u);
  expectConsistentSizes(r);
  // Every scored point is on the floor, now at the robot's z in the world, near the robot.
  std::size_t on_floor = 0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    const Eigen::Vector3f p = r.scored.cloud_world.point(i);
    on_floor += std::abs(p.z() - 0.25f) < 0.05f ? 1 : 0;
    EXPECT_LT((p.head<2>() - Eigen::Vector2f(12.f, -3.f)).norm(), 3.f);
  }
  EXPECT_GT(on_floor, r.size() * 9 / 10);
  // Normals point up in the world; the floor is traversable with zeta close to 1.
  std::size_t up = 0, valid = 0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    if (!r.scored.normals_world.isValid(i)) continue;
    ++valid;
    up += r.scored.normals_world.nz[i] > 0.95f ? 1 : 0;
  }
  EXPECT_GT(up, valid * 9 / 10);
  EXPECT_GT(r.scored.classes.traversable, r.size() * 8 / 10);
  // The sensor, 1.27 m above the robot origin, is 1.52 m above the world origin.
  EXPECT_NEAR(r.pose_world_sensor.translation().z(), 1.273 + 0.25, 0.01);
  EXPECT_TRUE(r.scored.cloud_world.sensor_origin.isApprox(
      r.pose_world_sensor.translation().cast<float>(), 1e-5f));
  EXPECT_GE(r.total_ms, r.convert_ms);
}

// Moving or turning the robot on the ground changes nothing but where the points are.
TEST(UpdObserver, ScoresDoNotDependOnThePlanarRobotPose) {
  REQUIRE_GROUND_SCAN(obs);
  const UpdObserver observer;
  const Eigen::Isometry3d a = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d b =
      upd::mrpt_bridge::toIsometry(mrpt::poses::CPose3D(5000.0, -7000.0, 2.0, 2.5, 0, 0));
  const ObserverResult ra = observer.observe(*obs, a);
  const ObserverResult rb = observer.observe(*obs, b);
  ASSERT_EQ(ra.size(), rb.size());
  for (std::size_t i = 0; i < ra.size(); ++i) {
    ASSERT_EQ(ra.scored.classes.label[i], rb.scored.classes.label[i]);
    if (ra.scored.upd.isValid(i)) {
      ASSERT_EQ(ra.scored.upd.zeta[i], rb.scored.upd.zeta[i]);
      const Eigen::Vector3f r_rotated = b.linear().cast<float>() * ra.scored.upd.r(i);
      ASSERT_TRUE(r_rotated.isApprox(rb.scored.upd.r(i), 1e-4f));
    }
    const Eigen::Vector3d moved = b * ra.scored.cloud_world.point(i).cast<double>();
    ASSERT_LT((moved - rb.scored.cloud_world.point(i).cast<double>()).norm(), 2e-3);
  }
}

// A frame loop passes one result every frame: each call rewrites every field, as a fresh
// result would hold them, whatever the previous frame left there.
TEST(UpdObserver, ReusedResultEqualsAFreshOne) {
  REQUIRE_GROUND_SCAN(obs);
  const UpdObserver observer;
  // The first frame pitched by 30 deg: other slopes, labels and costs than the second.
  const Eigen::Isometry3d a =
      upd::mrpt_bridge::toIsometry(mrpt::poses::CPose3D(0, 0, 0, 0, 30.0 * M_PI / 180.0, 0));
  const Eigen::Isometry3d b =
      upd::mrpt_bridge::toIsometry(mrpt::poses::CPose3D(3.0, -2.0, 0.0, 1.0, 0, 0));
  ObserverResult reused;
  observer.observe(*obs, a, reused);
  observer.observe(*obs, b, reused);
  const ObserverResult fresh = observer.observe(*obs, b);
  ASSERT_EQ(reused.size(), fresh.size());
  ASSERT_GT(fresh.size(), 0u);
  EXPECT_EQ(reused.scored.cloud_world.x, fresh.scored.cloud_world.x);
  EXPECT_EQ(reused.scored.cloud_world.z, fresh.scored.cloud_world.z);
  EXPECT_TRUE(
      reused.scored.cloud_world.sensor_origin.isApprox(fresh.scored.cloud_world.sensor_origin));
  const auto same = [](const std::vector<float>& u, const std::vector<float>& v) {
    if (u.size() != v.size()) return false;
    for (std::size_t i = 0; i < u.size(); ++i) {
      if (!(u[i] == v[i] || (std::isnan(u[i]) && std::isnan(v[i])))) return false;
    }
    return true;
  };
  EXPECT_TRUE(same(reused.scored.normals_world.nx, fresh.scored.normals_world.nx));
  EXPECT_TRUE(same(reused.scored.upd.ry, fresh.scored.upd.ry));
  EXPECT_TRUE(same(reused.scored.upd.zeta, fresh.scored.upd.zeta));
  EXPECT_EQ(reused.scored.upd.k, fresh.scored.upd.k);
  EXPECT_EQ(reused.scored.classes.label, fresh.scored.classes.label);
  EXPECT_TRUE(same(reused.scored.classes.cost, fresh.scored.classes.cost));
  EXPECT_EQ(reused.scored.classes.traversable, fresh.scored.classes.traversable);
  EXPECT_EQ(reused.scored.upd.invalid, fresh.scored.upd.invalid);
  EXPECT_TRUE(reused.pose_world_sensor.isApprox(fresh.pose_world_sensor));
}

// A robot pitched 10 deg in the world sees its own floor tilted: slope measured against gravity.
TEST(UpdObserver, SlopeIsMeasuredAgainstGravity) {
  REQUIRE_GROUND_SCAN(obs);
  ObserverParams params;
  params.pipeline.classify.max_slope_rad = 25.0 * M_PI / 180.0;
  const UpdObserver observer(params);
  const double pitch = 10.0 * M_PI / 180.0;
  const ObserverResult flat = observer.observe(*obs, Eigen::Isometry3d::Identity());
  const ObserverResult tilted = observer.observe(
      *obs, upd::mrpt_bridge::toIsometry(mrpt::poses::CPose3D(0, 0, 0, 0, pitch, 0)));
  std::vector<float> sf, st;
  for (const float s : flat.scored.classes.slope_rad) {
    if (std::isfinite(s)) sf.push_back(s);
  }
  for (const float s : tilted.scored.classes.slope_rad) {
    if (std::isfinite(s)) st.push_back(s);
  }
  ASSERT_FALSE(sf.empty());
  ASSERT_FALSE(st.empty());
  std::nth_element(sf.begin(), sf.begin() + sf.size() / 2, sf.end());
  std::nth_element(st.begin(), st.begin() + st.size() / 2, st.end());
  EXPECT_LT(sf[sf.size() / 2], 3.0 * M_PI / 180.0);
  EXPECT_NEAR(st[st.size() / 2], pitch, 3.0 * M_PI / 180.0);
}

TEST(UpdObserver, UnsupportedObservationIsSkippedWithReason) {
  const UpdObserver observer;
  mrpt::obs::CObservation2DRangeScan scan;
  const ObserverResult r = observer.observe(scan, Eigen::Isometry3d::Identity());
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.skipped_reason, "CObservation2DRangeScan has no 3D points (a planar laser scan)");
  EXPECT_EQ(r.size(), 0u);
  expectConsistentSizes(r);
}

TEST(UpdObserver, VelodyneScanIsScored) {
  UPD_REQUIRE_SHARED_FILE(path, "mrpt/test_velodyne_VLP16.rawlog");
  upd::mrpt_bridge::RawlogReader reader(path);
  upd::mrpt_bridge::RawlogEntry e;
  ASSERT_TRUE(reader.next(e));
  ObserverParams params;
  params.pipeline.preprocess.voxel_m = 0.1;
  params.pipeline.normals.radius_m = 0.5;
  params.pipeline.upd.radius_m = 1.0;
  const ObserverResult r =
      UpdObserver(params).observe(*e.observation, Eigen::Isometry3d::Identity());
  ASSERT_TRUE(r.ok()) << r.skipped_reason;
  EXPECT_FALSE(r.organized_input);
  EXPECT_GT(r.size(), 1000u);
  expectConsistentSizes(r);
  EXPECT_GT(r.scored.classes.traversable + r.scored.classes.non_traversable, r.size() / 4);
}

struct TempIni {
  std::filesystem::path path;
  explicit TempIni(const std::string& text) {
    path = std::filesystem::temp_directory_path() /
           ("upd_observer_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".ini");
    std::ofstream(path) << text;
  }
  ~TempIni() {
    std::error_code ec;
    std::filesystem::remove(path, ec);
  }
};

TEST(UpdObserver, ParamsFromIni) {
  const TempIni ini(
      "[PipelineParams]\nup = 0,0,1\n"
      "[UpdParams]\nradius_m = 0.7\n"
      "[SourceParams]\ncolor_enabled = false\nlidar_max_range_m = 40\n"
      "[StereoMatchParams]\nnum_disparities_px = 64\nblock_size_px = 7\n");
  ObserverParams p;
  upd::mrpt_bridge::loadObserverParams(ini.path.string(), p);
  EXPECT_DOUBLE_EQ(p.pipeline.upd.radius_m, 0.7);
  EXPECT_FALSE(p.source.color_enabled);
  EXPECT_DOUBLE_EQ(p.source.lidar_max_range_m, 40.0);
  EXPECT_EQ(p.source.stereo.num_disparities_px, 64);
  EXPECT_EQ(p.source.stereo.block_size_px, 7);

  // Shared file with other components' sections: the caller checks unknown keys at the end.
  const TempIni shared("[SourceParams]\nlidar_min_range_m = 2\n[SomebodyElse]\nkey = 1\n");
  upd::mrpt_bridge::IniReader reader(shared.path.string());
  ObserverParams q;
  upd::mrpt_bridge::loadObserverParams(reader, q);
  EXPECT_DOUBLE_EQ(q.source.lidar_min_range_m, 2.0);
  EXPECT_THROW(reader.checkAllKeysKnown(), std::invalid_argument);

  const TempIni tilted_up("[PipelineParams]\nup = 0,-1,0\n");
  try {
    ObserverParams r;
    upd::mrpt_bridge::loadObserverParams(tilted_up.path.string(), r);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(tilted_up.path.string()), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("pipeline.up"), std::string::npos) << e.what();
  }
  const TempIni typo("[SourceParams]\nlidar_max_rang_m = 4\n");
  ObserverParams s;
  EXPECT_THROW(upd::mrpt_bridge::loadObserverParams(typo.path.string(), s), std::invalid_argument);
  const TempIni bad_stereo("[StereoMatchParams]\nnum_disparities_px = 50\n");
  EXPECT_THROW(upd::mrpt_bridge::loadObserverParams(bad_stereo.path.string(), s),
               std::invalid_argument);
}

}  // namespace
