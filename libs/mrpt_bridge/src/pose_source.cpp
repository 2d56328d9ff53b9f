#include "upd/mrpt_bridge/pose_source.h"

#include "upd/core/params.h"
#include "upd/mrpt_bridge/rawlog_reader.h"

#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/poses/CPose3D.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace upd::mrpt_bridge {

Eigen::Isometry3d toIsometry(const mrpt::poses::CPose3D& pose) {
  const auto m = pose.getHomogeneousMatrixVal<mrpt::math::CMatrixDouble44>();
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) t.linear()(r, c) = m(r, c);
    t.translation()(r) = m(r, 3);
  }
  return t;
}

mrpt::poses::CPose3D toCPose3D(const Eigen::Isometry3d& pose) {
  mrpt::math::CMatrixDouble44 m;
  m.setIdentity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = pose.linear()(r, c);
    m(r, 3) = pose.translation()(r);
  }
  return mrpt::poses::CPose3D(m);
}

Eigen::Isometry3d sensorPoseOnRobot(const mrpt::obs::CObservation& obs) {
  mrpt::poses::CPose3D p;
  obs.getSensorPose(p);
  return toIsometry(p);
}

// ---------------------------------------------------------------------------------------------
// TUM trajectories

namespace {
constexpr double kMaxPositionM = 1e9;
}  // namespace

TumTrajectory TumTrajectory::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("ground-truth file " + path + ": not found or unreadable");
  return parse(in, path);
}

TumTrajectory TumTrajectory::parse(std::istream& in, const std::string& name) {
  TumTrajectory traj;
  std::string line;
  std::size_t line_no = 0;
  const auto fail = [&](const std::string& why) {
    throw std::runtime_error("ground-truth file " + name + ":" + std::to_string(line_no) + ": " +
                             why + " (a line is 't x y z qx qy qz qw')");
  };
  while (std::getline(in, line)) {
    ++line_no;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream is(line);
    std::vector<double> v;
    std::string token;
    while (is >> token) {
      try {
        std::size_t used = 0;
        const double d = std::stod(token, &used);
        if (used != token.size()) fail("'" + token + "' is not a number");
        v.push_back(d);
      } catch (const std::logic_error&) {
        fail("'" + token + "' is not a number");
      }
    }
    if (v.empty()) continue;
    if (v.size() != 8) fail(std::to_string(v.size()) + " values instead of 8");
    for (double d : v) {
      if (!std::isfinite(d)) fail("a value is not finite");
    }
    // Beyond any place on Earth (UTM northings are below 1e7 m): a damaged line, which the maps
    // would otherwise refuse later without the file's name.
    for (int k = 1; k <= 3; ++k) {
      if (std::abs(v[k]) > kMaxPositionM) {
        std::ostringstream os;
        os << "position " << "xyz"[k - 1] << " = " << v[k] << " m is farther than "
           << kMaxPositionM << " m from the origin";
        fail(os.str());
      }
    }
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (std::abs(q.norm() - 1.0) > 1e-2) {
      std::ostringstream os;
      os << "quaternion norm " << q.norm() << " is not 1";
      fail(os.str());
    }
    q.normalize();
    if (!traj.poses_.empty() && !(v[0] > traj.poses_.back().t_s)) {
      std::ostringstream os;
      os << std::setprecision(16) << "time " << v[0] << " does not increase (previous "
         << traj.poses_.back().t_s << ")";
      fail(os.str());
    }
    traj.poses_.push_back({v[0], Eigen::Vector3d(v[1], v[2], v[3]), q});
  }
  if (in.bad()) throw std::runtime_error("ground-truth file " + name + ": read error");
  return traj;
}

std::optional<Eigen::Isometry3d> TumTrajectory::interpolate(double t_s, double tolerance_s,
                                                            double max_gap_s) const {
  if (poses_.empty() || !std::isfinite(t_s)) return std::nullopt;
  const auto toIso = [](const Stamped& s) {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = s.rotation.toRotationMatrix();
    t.translation() = s.translation_m;
    return t;
  };
  if (t_s <= poses_.front().t_s) {
    if (poses_.front().t_s - t_s > tolerance_s) return std::nullopt;
    return toIso(poses_.front());
  }
  if (t_s >= poses_.back().t_s) {
    if (t_s - poses_.back().t_s > tolerance_s) return std::nullopt;
    return toIso(poses_.back());
  }
  const auto after = std::upper_bound(poses_.begin(), poses_.end(), t_s,
                                      [](double t, const Stamped& s) { return t < s.t_s; });
  const Stamped& b = *after;
  const Stamped& a = *(after - 1);
  if (b.t_s - a.t_s > max_gap_s) {
    // No interpolation across the gap, but a time next to either sample is that sample.
    if (t_s - a.t_s <= tolerance_s) return toIso(a);
    if (b.t_s - t_s <= tolerance_s) return toIso(b);
    return std::nullopt;
  }
  const double f = (t_s - a.t_s) / (b.t_s - a.t_s);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = a.rotation.slerp(f, b.rotation).normalized().toRotationMatrix();
  t.translation() = (1.0 - f) * a.translation_m + f * b.translation_m;
  return t;
}

// ---------------------------------------------------------------------------------------------
// Tracker

const char* toString(PoseSourceKind kind) {
  switch (kind) {
    case PoseSourceKind::None:
      return "none (identity)";
    case PoseSourceKind::OdometryActions:
      return "odometry actions";
    case PoseSourceKind::OdometryObservations:
      return "odometry observations";
    case PoseSourceKind::GroundTruth:
      return "ground truth";
  }
  return "unknown";
}

void GroundTruthParams::validate() const {
  core::requireParam(std::isfinite(time_tolerance_s) && time_tolerance_s >= 0, "GroundTruthParams",
               "time_tolerance_s", time_tolerance_s, "must be >= 0");
  core::requireParam(std::isfinite(max_time_gap_s) && max_time_gap_s > 0, "GroundTruthParams",
               "max_time_gap_s", max_time_gap_s, "must be > 0");
}

RobotPoseTracker::RobotPoseTracker(TumTrajectory ground_truth, GroundTruthParams params)
    : ground_truth_(std::move(ground_truth)),
      gt_params_(params),
      kind_(PoseSourceKind::GroundTruth) {
  gt_params_.validate();
  if (ground_truth_->empty()) throw std::invalid_argument("the ground-truth trajectory is empty");
}

RobotPose RobotPoseTracker::update(const RawlogEntry& entry) {
  const auto* odometry =
      dynamic_cast<const mrpt::obs::CObservationOdometry*>(entry.observation.get());
  RobotPose out;
  if (ground_truth_) {
    ignored_odometry_ += (entry.odometry_increment ? 1 : 0) + (odometry ? 1 : 0);
    out.source = PoseSourceKind::GroundTruth;
    if (!std::isfinite(entry.timestamp_s)) {
      out.missing_reason = "the observation has no timestamp to look the ground truth up";
      return out;
    }
    const auto pose = ground_truth_->interpolate(entry.timestamp_s, gt_params_.time_tolerance_s,
                                                 gt_params_.max_time_gap_s);
    if (!pose) {
      std::ostringstream os;
      os << std::fixed << std::setprecision(3)
         << "no ground-truth pose at t = " << entry.timestamp_s << " s (the trajectory covers "
         << ground_truth_->poses().front().t_s << " .. " << ground_truth_->poses().back().t_s
         << " s, gaps up to " << gt_params_.max_time_gap_s << " s)";
      out.missing_reason = os.str();
      return out;
    }
    out.pose_world_robot = *pose;
    return out;
  }

  if (entry.odometry_increment) {
    if (kind_ == PoseSourceKind::None || kind_ == PoseSourceKind::OdometryActions) {
      kind_ = PoseSourceKind::OdometryActions;
      pose_ = pose_ * *entry.odometry_increment;
    } else {
      ++ignored_odometry_;
    }
  }
  if (odometry) {
    if (kind_ == PoseSourceKind::None || kind_ == PoseSourceKind::OdometryObservations) {
      kind_ = PoseSourceKind::OdometryObservations;
      const auto& o = odometry->odometry;
      pose_ = Eigen::Isometry3d::Identity();
      pose_.linear() = Eigen::AngleAxisd(o.phi(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      pose_.translation() = Eigen::Vector3d(o.x(), o.y(), 0.0);
    } else {
      ++ignored_odometry_;
    }
  }
  out.pose_world_robot = pose_;
  out.source = kind_;
  return out;
}

}  // namespace upd::mrpt_bridge
