// Robot poses: TUM ground truth, odometry from rawlogs, and the frame algebra.
#include "upd/mrpt_bridge/pose_source.h"
#include "test_data.h"
#include "upd/mrpt_bridge/rawlog_reader.h"

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/poses/CPoint3D.h>
#include <mrpt/poses/CPose3D.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <sstream>

namespace {

using upd::mrpt_bridge::PoseSourceKind;
using upd::mrpt_bridge::RawlogEntry;
using upd::mrpt_bridge::RobotPoseTracker;
using upd::mrpt_bridge::TumTrajectory;

TumTrajectory parse(const std::string& text) {
  std::istringstream in(text);
  return TumTrajectory::parse(in, "gt.txt");
}

double yawOf(const Eigen::Isometry3d& t) { return std::atan2(t.linear()(1, 0), t.linear()(0, 0)); }

TEST(TumTrajectory, ParsesCommentsAndInterpolates) {
  // yaw 0 at t = 10, yaw 90 deg at t = 11: quaternion (w, z) = (cos 45, sin 45).
  const double s = std::sqrt(0.5);
  std::ostringstream text;
  text << "# timestamp tx ty tz qx qy qz qw\n"
       << "\n"
       << "10.0 0 0 0 0 0 0 1   # start\n"
       << "11.0 2 4 1 0 0 " << s << " " << s << "\n"
       << "20.0 2 4 1 0 0 " << s << " " << s << "\n";
  const TumTrajectory traj = parse(text.str());
  ASSERT_EQ(traj.size(), 3u);
  const auto mid = traj.interpolate(10.5);
  ASSERT_TRUE(mid);
  EXPECT_TRUE(mid->translation().isApprox(Eigen::Vector3d(1, 2, 0.5), 1e-12));
  EXPECT_NEAR(yawOf(*mid), M_PI / 4, 1e-9);  // slerp halfway
  const auto quarter = traj.interpolate(10.25);
  ASSERT_TRUE(quarter);
  EXPECT_NEAR(yawOf(*quarter), M_PI / 8, 1e-9);
  // Exactly on a sample.
  const auto at = traj.interpolate(11.0);
  ASSERT_TRUE(at);
  EXPECT_TRUE(at->translation().isApprox(Eigen::Vector3d(2, 4, 1), 1e-12));
  // Clamped within the tolerance, empty beyond it.
  ASSERT_TRUE(traj.interpolate(9.97, 0.05));
  EXPECT_TRUE(traj.interpolate(9.97, 0.05)->translation().isZero());
  EXPECT_FALSE(traj.interpolate(9.9, 0.05));
  EXPECT_FALSE(traj.interpolate(20.2, 0.05));
  // No interpolation across the 9 s gap (max 1 s), but fine with a larger limit.
  EXPECT_FALSE(traj.interpolate(15.0, 0.05, 1.0));
  ASSERT_TRUE(traj.interpolate(19.99, 0.05, 1.0));  // next to a sample across the gap
  EXPECT_TRUE(traj.interpolate(19.99, 0.05, 1.0)->translation().isApprox(Eigen::Vector3d(2, 4, 1)));
  EXPECT_TRUE(traj.interpolate(15.0, 0.05, 10.0));
  EXPECT_FALSE(traj.interpolate(std::nan("")));
}

TEST(TumTrajectory, BadLinesNameFileAndLine) {
  const auto expectError = [](const std::string& text, const std::string& where,
                              const std::string& what) {
    try {
      parse(text);
      ADD_FAILURE() << "no error for: " << text;
    } catch (const std::runtime_error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(where), std::string::npos) << msg;
      EXPECT_NE(msg.find(what), std::string::npos) << msg;
    }
  };
  expectError("1 0 0 0 0 0 0 1\n2 0 0 0\n", "gt.txt:2", "4 values instead of 8");
  expectError("# c\n1 0 0 0 0 0 0 1\n2 0 zero 0 0 0 0 1\n", "gt.txt:3", "'zero' is not a number");
  expectError("1 0 0 0 0 0 0 2\n", "gt.txt:1", "quaternion norm");
  expectError("1 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", "gt.txt:2", "does not increase");
  expectError("1 0 0 0 0 0 0 1 7\n", "gt.txt:1", "9 values");
  expectError("1 nan 0 0 0 0 0 1\n", "gt.txt:1", "not finite");
  expectError("1 0 0 0 0 0 0 1\n2 0 1e30 0 0 0 0 1\n", "gt.txt:2",
              "position y = 1e+30 m is farther than 1e+09 m from the origin");
  try {
    TumTrajectory::load("/nonexistent/dir/gt.tum");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/gt.tum"), std::string::npos);
  }
}

TEST(PoseAlgebra, SensorPointLandsAtKnownWorldPosition) {
  // Robot at (10, 5, 0) facing +y (yaw 90 deg); sensor 0.5 m ahead, 1 m up, pitched 90 deg
  // down (MRPT: pitch > 0 turns +x towards -z). A point 1 m along the sensor's x is on the floor
  // right under the sensor: robot (0.5, 0, 0), world (10, 5.5, 0).
  const mrpt::poses::CPose3D robot(10, 5, 0, M_PI / 2, 0, 0);
  const mrpt::poses::CPose3D sensor(0.5, 0, 1.0, 0, M_PI / 2, 0);
  const Eigen::Isometry3d pose_world_sensor = upd::mrpt_bridge::composeSensorPose(
      upd::mrpt_bridge::toIsometry(robot), upd::mrpt_bridge::toIsometry(sensor));
  const Eigen::Vector3d p_world = pose_world_sensor * Eigen::Vector3d(1, 0, 0);
  EXPECT_TRUE(p_world.isApprox(Eigen::Vector3d(10, 5.5, 0), 1e-9)) << p_world.transpose();
  // Same as MRPT's own composition.
  const mrpt::poses::CPose3D mrpt_world_sensor = robot + sensor;
  double x, y, z;
  mrpt_world_sensor.composePoint(1, 0, 0, x, y, z);
  EXPECT_NEAR(x, p_world.x(), 1e-9);
  EXPECT_NEAR(y, p_world.y(), 1e-9);
  EXPECT_NEAR(z, p_world.z(), 1e-9);
}

TEST(PoseAlgebra, ConversionsAgreeWithMrptOnRandomPoses) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> t(-50, 50), a(-M_PI, M_PI), pitch(-1.5, 1.5);
  for (int i = 0; i < 200; ++i) {
    const mrpt::poses::CPose3D p(t(rng), t(rng), t(rng), a(rng), pitch(rng), a(rng));
    const mrpt::poses::CPose3D q(t(rng), t(rng), t(rng), a(rng), pitch(rng), a(rng));
    const Eigen::Isometry3d ip = upd::mrpt_bridge::toIsometry(p);
    const Eigen::Isometry3d iq = upd::mrpt_bridge::toIsometry(q);
    EXPECT_TRUE((ip * iq).isApprox(upd::mrpt_bridge::toIsometry(p + q), 1e-9));
    const mrpt::poses::CPose3D back = upd::mrpt_bridge::toCPose3D(ip);
    EXPECT_TRUE(upd::mrpt_bridge::toIsometry(back).isApprox(ip, 1e-9));
    EXPECT_TRUE(ip.inverse().isApprox(upd::mrpt_bridge::toIsometry(-p), 1e-9));
  }
}

TEST(RobotPoseTracker, SenaOdometryAccumulates) {
  UPD_REQUIRE_SHARED_FILE(path, "mrpt/2006-01ENE-21-SENA_Telecom_Faculty_one_loop_only.rawlog");
  upd::mrpt_bridge::RawlogReader reader(path);
  RobotPoseTracker tracker;
  RawlogEntry e;
  Eigen::Isometry3d expected = Eigen::Isometry3d::Identity();
  std::size_t n = 0;
  double max_dist = 0;
  while (reader.next(e)) {
    if (e.odometry_increment) expected = expected * *e.odometry_increment;
    const auto pose = tracker.update(e);
    ASSERT_TRUE(pose.valid());
    EXPECT_TRUE(pose.pose_world_robot.isApprox(expected, 1e-9));
    if (n == 0) {
      EXPECT_TRUE(pose.pose_world_robot.isApprox(Eigen::Isometry3d::Identity()));
    } else {
      EXPECT_EQ(pose.source, PoseSourceKind::OdometryActions);
    }
    EXPECT_NEAR(pose.pose_world_robot.translation().z(), 0.0, 1e-9);  // planar robot
    max_dist = std::max(max_dist, pose.pose_world_robot.translation().norm());
    // The 2D laser sits 0.78 m ahead of the robot origin.
    const Eigen::Isometry3d sensor = upd::mrpt_bridge::sensorPoseOnRobot(*e.observation);
    EXPECT_NEAR(sensor.translation().x(), 0.78, 1e-6);  // stored as float
    ++n;
  }
  EXPECT_EQ(n, 225u);
  EXPECT_TRUE(tracker.hadPoseInformation());
  EXPECT_EQ(tracker.kind(), PoseSourceKind::OdometryActions);
  EXPECT_GT(max_dist, 5.0);
}

std::shared_ptr<mrpt::obs::CObservationOdometry> odometry(double x, double y, double phi) {
  auto o = std::make_shared<mrpt::obs::CObservationOdometry>();
  o->odometry = mrpt::poses::CPose2D(x, y, phi);
  return o;
}

TEST(RobotPoseTracker, OdometryObservationsAndFirstSourceWins) {
  RobotPoseTracker tracker;
  RawlogEntry scan;
  scan.observation = std::make_shared<mrpt::obs::CObservation2DRangeScan>();
  EXPECT_EQ(tracker.update(scan).source, PoseSourceKind::None);
  EXPECT_FALSE(tracker.hadPoseInformation());

  RawlogEntry odo;
  odo.observation = odometry(3, 4, M_PI / 2);
  const auto p = tracker.update(odo);
  EXPECT_EQ(p.source, PoseSourceKind::OdometryObservations);
  EXPECT_TRUE(p.pose_world_robot.translation().isApprox(Eigen::Vector3d(3, 4, 0)));
  EXPECT_NEAR(yawOf(p.pose_world_robot), M_PI / 2, 1e-12);
  // The latest odometry holds for the next observations.
  EXPECT_TRUE(tracker.update(scan).pose_world_robot.isApprox(p.pose_world_robot));
  // An action increment now is ignored (the first source met wins) and counted.
  RawlogEntry with_action;
  with_action.observation = scan.observation;
  with_action.odometry_increment = Eigen::Isometry3d(Eigen::Translation3d(1, 0, 0));
  EXPECT_TRUE(tracker.update(with_action).pose_world_robot.isApprox(p.pose_world_robot));
  EXPECT_EQ(tracker.ignoredOdometry(), 1u);
}

TEST(RobotPoseTracker, NoPoseInformationMeansIdentity) {
  RobotPoseTracker tracker;
  RawlogEntry scan;
  scan.observation = std::make_shared<mrpt::obs::CObservation2DRangeScan>();
  for (int i = 0; i < 3; ++i) {
    const auto p = tracker.update(scan);
    EXPECT_TRUE(p.valid());
    EXPECT_TRUE(p.pose_world_robot.isApprox(Eigen::Isometry3d::Identity()));
  }
  EXPECT_FALSE(tracker.hadPoseInformation());
  EXPECT_EQ(tracker.kind(), PoseSourceKind::None);
}

TEST(RobotPoseTracker, GroundTruthByTimestamp) {
  RobotPoseTracker tracker(parse("100 0 0 0 0 0 0 1\n101 1 0 0 0 0 0 1\n"));
  EXPECT_EQ(tracker.kind(), PoseSourceKind::GroundTruth);
  RawlogEntry e;
  e.observation = odometry(50, 50, 0);  // ignored: ground truth rules
  e.odometry_increment = Eigen::Isometry3d(Eigen::Translation3d(7, 0, 0));
  e.timestamp_s = 100.25;
  const auto p = tracker.update(e);
  ASSERT_TRUE(p.valid()) << p.missing_reason;
  EXPECT_TRUE(p.pose_world_robot.translation().isApprox(Eigen::Vector3d(0.25, 0, 0), 1e-12));
  EXPECT_EQ(tracker.ignoredOdometry(), 2u);
  e.timestamp_s = 105;
  const auto outside = tracker.update(e);
  EXPECT_FALSE(outside.valid());
  EXPECT_NE(outside.missing_reason.find("105.000"), std::string::npos) << outside.missing_reason;
  e.timestamp_s = std::nan("");
  EXPECT_FALSE(tracker.update(e).valid());
  EXPECT_THROW(RobotPoseTracker{TumTrajectory{}}, std::invalid_argument);
}

}  // namespace
