// The robot pose of each rawlog entry, and the frame algebra around it.
//
// Poses are rigid transforms named pose_<to>_<from>: pose_world_robot maps robot coordinates to
// world coordinates, so a point seen by a sensor lands in the world at
//   p_world = pose_world_robot * sensor_pose_on_robot * p_sensor
// i.e. pose_world_sensor = pose_world_robot (+) sensor_pose_on_robot in MRPT's notation. The world
// and robot frames are z-up (MRPT's convention); the robot frame is x forward, y left.
//
// Three sources of robot poses:
//  (a) odometry actions of an "actions + sensory frames" rawlog (CActionRobotMovement2D/3D),
//      accumulated from identity: pose_k = pose_{k-1} * increment_k;
//  (b) CObservationOdometry entries (absolute odometry; the latest one holds until the next);
//  (c) a ground-truth trajectory file in the TUM format, one pose per line
//      `t x y z qx qy qz qw` (t in seconds, translation in metres, unit quaternion; `#` starts a
//      comment), interpolated at the entry's timestamp (linear in translation, slerp in
//      rotation).
// With (a) and (b) the first kind met in the file is used and the other is counted as ignored.
// A rawlog without any pose information leaves every pose at identity; hadPoseInformation()
// says so and the caller reports it.
#pragma once

#include <Eigen/Geometry>

#include <cstddef>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace mrpt::poses {
class CPose3D;
}
namespace mrpt::obs {
class CObservation;
}

namespace upd::mrpt_bridge {

struct RawlogEntry;

/// MRPT pose -> rigid transform (same meaning: maps the pose's local frame to its parent).
Eigen::Isometry3d toIsometry(const mrpt::poses::CPose3D& pose);
/// Rigid transform -> MRPT pose. The rotation part must be orthonormal.
mrpt::poses::CPose3D toCPose3D(const Eigen::Isometry3d& pose);
/// The observation's sensor pose on the robot (CObservation::getSensorPose).
Eigen::Isometry3d sensorPoseOnRobot(const mrpt::obs::CObservation& obs);
/// pose_world_sensor = pose_world_robot (+) sensor_pose_on_robot.
inline Eigen::Isometry3d composeSensorPose(const Eigen::Isometry3d& pose_world_robot,
                                           const Eigen::Isometry3d& sensor_pose_on_robot) {
  return pose_world_robot * sensor_pose_on_robot;
}

/// A ground-truth trajectory (TUM format), sorted by time.
class TumTrajectory {
 public:
  struct Stamped {
    double t_s;
    Eigen::Vector3d translation_m;
    Eigen::Quaterniond rotation;  ///< unit quaternion
  };

  /// Reads path; throws std::runtime_error naming the file (and the line for a bad line: not
  /// 8 numbers, a non-finite value, a quaternion far from unit norm, or a time that does not
  /// increase).
  static TumTrajectory load(const std::string& path);
  /// Same rules, from a stream; name appears in the errors.
  static TumTrajectory parse(std::istream& in, const std::string& name);

  std::size_t size() const { return poses_.size(); }
  bool empty() const { return poses_.empty(); }
  const std::vector<Stamped>& poses() const { return poses_; }

  /// Pose at t_s: interpolated between the two samples around it. Within tolerance_s of a
  /// sample that has no neighbour to interpolate with (the ends, or across a gap longer than
  /// max_gap_s), that sample. Empty otherwise: outside the trajectory, or inside a gap.
  std::optional<Eigen::Isometry3d> interpolate(double t_s, double tolerance_s = 0.05,
                                               double max_gap_s = 1.0) const;

 private:
  std::vector<Stamped> poses_;
};

enum class PoseSourceKind {
  None,                  ///< nothing known: identity
  OdometryActions,       ///< accumulated CActionRobotMovement2D/3D increments
  OdometryObservations,  ///< CObservationOdometry
  GroundTruth,           ///< a TUM trajectory file
};
const char* toString(PoseSourceKind kind);

struct RobotPose {
  Eigen::Isometry3d pose_world_robot = Eigen::Isometry3d::Identity();
  PoseSourceKind source = PoseSourceKind::None;  ///< None: identity (no information so far)
  std::string missing_reason;  ///< non-empty: no pose for this entry; the caller skips it
  bool valid() const { return missing_reason.empty(); }
};

struct GroundTruthParams {
  double time_tolerance_s = 0.05;  ///< entries this far outside the trajectory are clamped [s]
  double max_time_gap_s = 1.0;     ///< no interpolation across a larger gap between samples [s]

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("time_tolerance_s", time_tolerance_s,
      "entries this far outside the trajectory are clamped [s]");
    v("max_time_gap_s", max_time_gap_s, "no interpolation across a larger gap between samples [s]");
  }
};

/// Follows the robot along a rawlog, entry by entry (feed every entry, in file order).
class RobotPoseTracker {
 public:
  /// Poses from the rawlog's own odometry (actions or CObservationOdometry).
  RobotPoseTracker() = default;
  /// Poses from a ground-truth trajectory; the rawlog's odometry is ignored (and counted).
  explicit RobotPoseTracker(TumTrajectory ground_truth, GroundTruthParams params = {});

  /// Takes the entry's odometry into account and returns the robot pose at the entry.
  RobotPose update(const RawlogEntry& entry);

  PoseSourceKind kind() const { return kind_; }
  /// False while (and if, at the end, never) any pose information was met: poses were identity.
  bool hadPoseInformation() const { return kind_ != PoseSourceKind::None; }
  /// Odometry readings not used because another source was chosen.
  std::size_t ignoredOdometry() const { return ignored_odometry_; }

 private:
  std::optional<TumTrajectory> ground_truth_;
  GroundTruthParams gt_params_;
  PoseSourceKind kind_ = PoseSourceKind::None;
  Eigen::Isometry3d pose_ = Eigen::Isometry3d::Identity();
  std::size_t ignored_odometry_ = 0;
};

}  // namespace upd::mrpt_bridge
