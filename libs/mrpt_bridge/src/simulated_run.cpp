#include "upd/mrpt_bridge/gz_output_stream.h"
#include "upd/mrpt_bridge/simulated_run.h"

#include "upd/io/atomic_file.h"
#include "upd/io/ros_map.h"
#include "upd/maps/grid_planner.h"
#include "upd/sim/render.h"
#include "upd/sim/terrain.h"
#include "upd/sim/truth_raster.h"

#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/datetime.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <random>
#include <stdexcept>

namespace upd::mrpt_bridge {

namespace fs = std::filesystem;

void SimulationParams::validate() const {
  body.validate();
  camera.validate();
  const char* s = "SimulationParams";
  core::requireParam(speed_mps > 0, s, "speed_mps", speed_mps, "must be > 0");
  core::requireParam(frame_spacing_m > 0, s, "frame_spacing_m", frame_spacing_m, "must be > 0");
  core::requireParam(clearance_m >= 0, s, "clearance_m", clearance_m, "must be >= 0");
  core::requireParam(odometry_sigma_ratio >= 0, s, "odometry_sigma_ratio", odometry_sigma_ratio,
               "must be >= 0");
  core::requireParam(truth_cell_m > 0, s, "truth_cell_m", truth_cell_m, "must be > 0");
  core::requireParam(seed >= 0, s, "seed", seed, "must be >= 0");
  core::requireParam(std::isfinite(distance_m) && distance_m >= 0, s, "distance_m", distance_m,
                     "must be >= 0");
}

namespace {

constexpr double kPlanCell_m = 0.1;      // cell of the route planner's raster of the truth
constexpr double kTimeOrigin_s = 1.7e9;  // timestamps since the epoch, as a real recording

// The truth rasterised for the planner: a cell is blocked where the truth is not Traversable
// (unknown included) and along the world's border, so the robot's body never leaves the world.
struct PlanRaster {
  sim::TruthRaster truth;
  std::vector<std::uint8_t> blocked;
  maps::PlannerGridView view;

  explicit PlanRaster(const sim::Terrain& t) : truth(t, kPlanCell_m) {
    const int w = truth.sizeX(), h = truth.sizeY();
    blocked.resize(static_cast<std::size_t>(w) * h);
    for (int j = 0; j < h; ++j) {
      for (int i = 0; i < w; ++i) {
        const bool border = i == 0 || j == 0 || i == w - 1 || j == h - 1;
        blocked[static_cast<std::size_t>(j) * w + i] =
            border || truth.at(i, j) != core::Label::Traversable;
      }
    }
    view.width = w;
    view.height = h;
    view.cell_m = kPlanCell_m;
    view.blocked = blocked.data();
  }
  Eigen::Vector2i cellOf(const Eigen::Vector2d& p) const {
    return {static_cast<int>(std::floor((p.x() - truth.origin().x()) / kPlanCell_m)),
            static_cast<int>(std::floor((p.y() - truth.origin().y()) / kPlanCell_m))};
  }
};

// The straightened path between two world points keeping clearance_m from blocked cells.
std::vector<Eigen::Vector2d> planLeg(const PlanRaster& r, const Eigen::Vector2d& from,
                                     const Eigen::Vector2d& to, double clearance_m,
                                     const std::string& world) {
  maps::GridPlannerParams gp;
  gp.inflation_m = clearance_m;
  const Eigen::Vector2i s = r.cellOf(from), g = r.cellOf(to);
  const maps::GridPlan plan = maps::planGridPath(r.view, s, g, gp);
  const auto passable = [&](const Eigen::Vector2i& c) {
    return r.view.inside(c.x(), c.y()) && plan.passable[r.view.index(c.x(), c.y())];
  };
  const std::string clearance = std::to_string(clearance_m);
  if (!passable(s)) {
    throw std::invalid_argument("world '" + world + "': the start is closer than " + clearance +
                                " m to non-traversable ground");
  }
  if (!passable(g)) {
    throw std::invalid_argument("world '" + world + "': the goal is closer than " + clearance +
                                " m to non-traversable ground");
  }
  if (!plan.found) {
    throw std::invalid_argument("world '" + world + "': the goal cannot be reached with " +
                                clearance + " m clearance");
  }
  std::vector<Eigen::Vector2d> cells;
  for (const Eigen::Vector2i& c : plan.cells) cells.push_back(r.truth.cellCenter(c.x(), c.y()));
  cells.front() = from;
  if (cells.size() > 1) {
    cells.back() = to;
  } else {
    cells.push_back(to);
  }
  return maps::shortcutPath(r.view, plan.passable, r.truth.origin(), cells);
}

double wrapAngle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

// The polyline sampled every frame_spacing_m, turning in place (15 deg steps) at each corner
// so the camera never jumps; the body rests on the terrain at every pose.
std::vector<RoutePose> sampleRoute(const std::vector<Eigen::Vector2d>& way,
                                   const sim::WorldSpec& world, const SimulationParams& p) {
  std::vector<RoutePose> route;
  double yaw = world.start_xy_yaw.z(), t_s = 0;
  const double turn_step = 15.0 * core::kDegToRad;
  const double turn_rate = p.speed_mps / (0.5 * p.body.track_m);  // wheels at speed_mps
  auto emit = [&](const Eigen::Vector2d& xy) {
    const Eigen::Vector3d xy_yaw(xy.x(), xy.y(), yaw);
    route.push_back({t_s, sim::bodyPoseOnTerrain(world.terrain, xy_yaw, p.body), yaw});
  };
  emit(way.front());
  for (std::size_t k = 0; k + 1 < way.size(); ++k) {
    const Eigen::Vector2d a = way[k], b = way[k + 1];
    const double len = (b - a).norm();
    if (len < 1e-9) continue;
    const double heading = std::atan2(b.y() - a.y(), b.x() - a.x());
    double dyaw = wrapAngle(heading - yaw);
    while (std::abs(dyaw) > 1e-9) {
      const double step = std::clamp(dyaw, -turn_step, turn_step);
      yaw = wrapAngle(yaw + step);
      dyaw -= step;
      t_s += std::abs(step) / turn_rate;
      emit(a);
    }
    const int n = std::max(1, static_cast<int>(std::round(len / p.frame_spacing_m)));
    for (int s = 1; s <= n; ++s) {
      t_s += len / n / p.speed_mps;
      emit(a + (b - a) * (double(s) / n));
    }
  }
  return route;
}

std::string stemOf(const std::string& rawlog_path) {
  fs::path p(rawlog_path);
  return (p.parent_path() / p.stem()).string();
}

// Odometry between two route poses: the true planar increment, with noise proportional to the
// distance and a heading drift, as wheel odometry on a skid-steer rover. gauss: N(0, 1),
// drawn from rng (one distribution for the whole run: it keeps the second value of each pair).
mrpt::obs::CActionRobotMovement2D odometryStep(const RoutePose& from, const RoutePose& to,
                                               const SimulationParams& p, std::mt19937& rng,
                                               std::normal_distribution<double>& gauss) {
  const mrpt::poses::CPose2D a(from.pose_world_robot.translation().x(),
                               from.pose_world_robot.translation().y(), from.yaw_rad);
  const mrpt::poses::CPose2D b(to.pose_world_robot.translation().x(),
                               to.pose_world_robot.translation().y(), to.yaw_rad);
  mrpt::poses::CPose2D inc = b - a;
  const double dist = std::hypot(inc.x(), inc.y());
  const double scale = 1.0 + p.odometry_sigma_ratio * gauss(rng);
  inc.x(inc.x() * scale);
  inc.y(inc.y() * scale);
  inc.phi(inc.phi() + p.odometry_yaw_bias_rad_per_m * dist +
          0.2 * p.odometry_sigma_ratio * dist * gauss(rng));
  mrpt::obs::CActionRobotMovement2D::TMotionModelOptions motion;
  motion.modelSelection = mrpt::obs::CActionRobotMovement2D::mmGaussian;
  mrpt::obs::CActionRobotMovement2D act;
  act.computeFromOdometry(inc, motion);
  return act;
}

// A depth image as a Kinect's CObservation3DRangeScan (millimetre range units) mounted at
// sensor_on_robot.
mrpt::obs::CObservation3DRangeScan::Ptr rangeScan(const core::DepthImage& depth,
                                                  const core::CameraIntrinsics& K, double max_range_m,
                                                  const Eigen::Isometry3d& sensor_on_robot) {
  auto obs = mrpt::obs::CObservation3DRangeScan::Create();
  obs->sensorLabel = "KINECT";
  obs->hasRangeImage = true;
  obs->range_is_depth = true;
  obs->rangeUnits = 0.001f;
  obs->maxRange = static_cast<float>(max_range_m);
  obs->rangeImage_setSize(K.height, K.width);
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const float d = depth.at(u, v);
      obs->rangeImage(v, u) =
          d > 0.f && std::isfinite(d) ? static_cast<std::uint16_t>(std::lround(d * 1000.f)) : 0;
    }
  }
  obs->cameraParams.ncols = K.width;
  obs->cameraParams.nrows = K.height;
  obs->cameraParams.setIntrinsicParamsFromValues(K.fx, K.fy, K.cx, K.cy);
  obs->cameraParamsIntensity = obs->cameraParams;
  const Eigen::Vector3d ypr = sensor_on_robot.linear().eulerAngles(2, 1, 0);
  obs->sensorPose =
      mrpt::poses::CPose3D(sensor_on_robot.translation().x(), sensor_on_robot.translation().y(),
                           sensor_on_robot.translation().z(), ypr[0], ypr[1], ypr[2]);
  return obs;
}

// The rawlog: per route pose an action collection (odometry from the previous pose; empty for
// the first) and a sensory frame with the rendered depth.
void writeRawlog(const std::vector<RoutePose>& route, const sim::WorldSpec& world,
                 const SimulationParams& p, const std::string& rawlog_path) {
  const core::CameraIntrinsics K = sim::simulatedIntrinsics(p.camera);
  const sim::DepthNoise noise;  // sigma = 1.2e-3 z^2, 0.4 .. 8 m, millimetre steps
  const Eigen::Isometry3d sensor_on_robot = sim::mountOnRobot(p.camera);
  Eigen::Isometry3d optical_in_sensor = Eigen::Isometry3d::Identity();
  optical_in_sensor.linear() = sim::opticalInMount();
  std::mt19937 rng(static_cast<std::uint32_t>(p.seed));
  std::normal_distribution<double> gauss(0.0, 1.0);
  io::writeFileAtomicallyVia(rawlog_path, [&](const std::string& tmp) {
    GzOutputStream out(tmp);
    auto arch = mrpt::serialization::archiveFrom(out);
    for (std::size_t k = 0; k < route.size(); ++k) {
      const RoutePose& rp = route[k];
      const auto stamp = mrpt::Clock::fromDouble(kTimeOrigin_s + rp.t_s);
      mrpt::obs::CActionCollection actions;
      if (k > 0) {
        mrpt::obs::CActionRobotMovement2D act = odometryStep(route[k - 1], rp, p, rng, gauss);
        act.timestamp = stamp;
        actions.insert(act);
      }
      arch << actions;
      const Eigen::Isometry3d pose_world_camera =
          rp.pose_world_robot * sensor_on_robot * optical_in_sensor;
      const core::DepthImage depth = sim::renderDepth(world.terrain, pose_world_camera, K, noise,
                                                static_cast<std::uint32_t>(p.seed * 100003 + k));
      auto obs = rangeScan(depth, K, noise.max_range_m, sensor_on_robot);
      obs->timestamp = stamp;
      mrpt::obs::CSensoryFrame sf;
      sf.insert(obs);
      arch << sf;
    }
    out.close();
  });
}

void writePoses(const std::vector<RoutePose>& route, const std::string& path) {
  io::writeFileAtomically(path, [&](std::ostream& os) {
    os << "# ground-truth poses of the robot (TUM: t x y z qx qy qz qw), world frame z up\n"
       << std::fixed << std::setprecision(6);
    for (const RoutePose& rp : route) {
      const Eigen::Quaterniond q(rp.pose_world_robot.linear());
      const Eigen::Vector3d t = rp.pose_world_robot.translation();
      os << kTimeOrigin_s + rp.t_s << " " << t.x() << " " << t.y() << " " << t.z() << " " << q.x()
         << " " << q.y() << " " << q.z() << " " << q.w() << "\n";
    }
  });
}

}  // namespace

std::string groundTruthPosesPath(const std::string& rawlog_path) {
  return stemOf(rawlog_path) + ".gt.tum";
}
std::string truthMapPath(const std::string& rawlog_path) {
  return stemOf(rawlog_path) + ".truth.yaml";
}

namespace {

// The stops of the route: start, the course or the goal, and back to start when the route
// is closed (return_to_start, a course, or a run of distance_m).
std::vector<Eigen::Vector2d> routeStops(const sim::WorldSpec& world, const SimulationParams& p) {
  const Eigen::Vector2d start = world.start_xy_yaw.head<2>();
  std::vector<Eigen::Vector2d> stops = {start};
  if (world.course.empty()) {
    stops.push_back(world.goal_xy);
  } else {
    stops.insert(stops.end(), world.course.begin(), world.course.end());
  }
  if (p.return_to_start || !world.course.empty() || p.distance_m > 0) stops.push_back(start);
  return stops;
}

// The closed polyline `lap` repeated until it is distance_m long, cut there.
std::vector<Eigen::Vector2d> repeatTo(const std::vector<Eigen::Vector2d>& lap, double distance_m) {
  std::vector<Eigen::Vector2d> way = {lap.front()};
  double length = 0;
  for (std::size_t k = 1;; k = k % (lap.size() - 1) + 1) {
    const Eigen::Vector2d a = way.back(), b = lap[k];
    const double seg = (b - a).norm();
    if (length + seg >= distance_m) {
      way.push_back(a + (b - a) * ((distance_m - length) / seg));
      return way;
    }
    if (seg > 0) way.push_back(b);
    length += seg;
  }
}

}  // namespace

std::vector<RoutePose> planSimulatedRoute(const sim::WorldSpec& world, const SimulationParams& p) {
  p.validate();
  const PlanRaster raster(world.terrain);
  const std::vector<Eigen::Vector2d> stops = routeStops(world, p);
  std::vector<Eigen::Vector2d> way = {stops.front()};
  for (std::size_t k = 1; k < stops.size(); ++k) {
    const auto leg = planLeg(raster, stops[k - 1], stops[k], p.clearance_m, world.description);
    way.insert(way.end(), leg.begin() + 1, leg.end());
  }
  if (p.distance_m > 0) {
    double lap_m = 0;
    for (std::size_t k = 1; k < way.size(); ++k) lap_m += (way[k] - way[k - 1]).norm();
    if (!(lap_m > 0)) {
      throw std::invalid_argument("SimulationParams.distance_m: the route of world '" +
                                  world.description + "' has no length to repeat");
    }
    way = repeatTo(way, p.distance_m);
  }
  return sampleRoute(way, world, p);
}

void writeTruthMap(const sim::TruthRaster& truth, const std::string& yaml_path) {
  io::RosMap map;
  map.resolution_m = truth.cellSize();
  map.origin_xy = truth.origin();
  map.width = truth.sizeX();
  map.height = truth.sizeY();
  map.labels = truth.labels();
  io::writeRosMap(map, yaml_path);
}

SimulationSummary simulateRun(const sim::WorldSpec& world, const SimulationParams& p,
                              const std::string& rawlog_path, int max_frames) {
  p.validate();
  std::vector<RoutePose> route = planSimulatedRoute(world, p);
  if (max_frames > 0 && route.size() > static_cast<std::size_t>(max_frames)) {
    route.resize(static_cast<std::size_t>(max_frames));
  }
  SimulationSummary summary;
  summary.rawlog_path = rawlog_path;
  summary.poses_path = groundTruthPosesPath(rawlog_path);
  summary.truth_yaml_path = truthMapPath(rawlog_path);
  writeRawlog(route, world, p, rawlog_path);
  writePoses(route, summary.poses_path);
  writeTruthMap(sim::TruthRaster(world.terrain, p.truth_cell_m), summary.truth_yaml_path);

  summary.frames = route.size();
  for (std::size_t k = 1; k < route.size(); ++k) {
    summary.path_length_m +=
        (route[k].pose_world_robot.translation() - route[k - 1].pose_world_robot.translation())
            .head<2>()
            .norm();
  }
  summary.duration_s = route.empty() ? 0 : route.back().t_s;
  return summary;
}

}  // namespace upd::mrpt_bridge
