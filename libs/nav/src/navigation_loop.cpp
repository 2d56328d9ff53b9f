#include "upd/nav/navigation_loop.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace upd::nav {

namespace {

constexpr double kRouteLookahead_m = 4.0;  // the PTGs' reach
constexpr double kRouteTolerance_m = 0.4;
constexpr double kProgress_m = 0.2;  // a route this much shorter than the best so far is progress

// Distance from p to the polyline.
double distanceToPolyline(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& line) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 1 < line.size(); ++i) {
    const Eigen::Vector2d ab = line[i + 1] - line[i];
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - line[i]).dot(ab) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (p - (line[i] + t * ab)).norm());
  }
  if (line.size() == 1) best = (p - line[0]).norm();
  return best;
}

// A new route replaces the one being driven only when it leaves it (by more than
// tolerance_m within the next lookahead_m): re-issuing waypoints restarts MRPT's navigator, so
// a route that merely shifts by a cell must not.
bool routeDiffers(const Route& next, const Route& current, double lookahead_m, double tolerance_m) {
  if (!current.found) return true;
  double along = 0.0;
  for (std::size_t i = 0; i < next.path_world.size(); ++i) {
    if (i > 0) along += (next.path_world[i] - next.path_world[i - 1]).norm();
    if (along > lookahead_m) break;
    if (distanceToPolyline(next.path_world[i], current.path_world) > tolerance_m) return true;
  }
  return false;
}

// True when a cell of the route's path is NonTraversable on the grid.
bool routeBlocked(const maps::TraversabilityGrid& grid, const Route& route) {
  for (const Eigen::Vector2d& p : route.path_world) {
    if (maps::cellLabel(grid, p.x(), p.y()) == core::Label::NonTraversable) return true;
  }
  return false;
}

// Collision grids depend on the PTG file (PTGs, shape): cache them per file content so editing
// the file never reuses stale grids.
std::string cacheDirFor(const std::string& cache_root, const std::string& ptg_ini) {
  std::ifstream in(ptg_ini, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a
  for (const unsigned char c : os.str()) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return (fs::path(cache_root) / hex).string();
}

}  // namespace

core::FrameScorerParams loopScorerParams(const NavConfig& config, core::ObstacleDetector detector) {
  core::FrameScorerParams p;
  p.pipeline = config.pipeline;
  p.baseline = config.baseline;
  if (config.perception.upd_radius_m > 0) {
    // The baseline is compared at the UPD's neighbourhood (BaselineParams::radius_m is "the
    // same d_m as the UPD"): its band round obstacles, and its cost per frame, follow d_m.
    p.pipeline.upd.radius_m = config.perception.upd_radius_m;
    p.baseline.radius_m = config.perception.upd_radius_m;
  }
  p.detector = detector;
  p.obstacles_xy = true;  // the navigator's current-frame obstacles
  return p;
}

NavigationLoop::NavigationLoop(RobotBase& base, const NavConfig& config, core::ObstacleDetector detector,
                               const std::string& navlog_path)
    : base_(base),
      config_(config),
      scorer_(loopScorerParams(config, detector)),
      navlog_path_(navlog_path),
      grid_(config.grid),
      obstacles_(config.obstacles) {
  config_.validate();
  obstacles_.setMap(&grid_);
}

NavigationLoop::~NavigationLoop() = default;

const FrameEvidence& NavigationLoop::addFrame(const core::PointCloud& cloud_world, double time_s,
                                              double ground_z_m) {
  // The cloud is already in the world frame: scored there, as the identity pose says.
  if (labeller_) {
    labelFrame(cloud_world);
  } else {
    scorer_.score(cloud_world, Eigen::Isometry3d::Identity(), last_frame_);
  }
  const Pose2D pose = robotPose();
  const auto view = maps::viewPoints(last_frame_.cloud_world, last_frame_.classes,
                                     last_frame_.upd.zeta.empty() ? nullptr : &last_frame_.upd);
  const Eigen::Vector2d robot_xy(pose.x_m, pose.y_m);
  last_fusion_ = maps::integrateScan(grid_, view, robot_xy, time_s, config_.fusion);

  // Missing ground: gaps whose near side the map (this frame included) reads as traversable
  // ground are fused as NonTraversable evidence and act as obstacles at once.
  last_missing_ground_.clear();
  std::vector<float> gx, gy, gz;
  for (const GroundGap& gap : findGroundGaps(cloud_world, ground_z_m, config_.negative)) {
    if (maps::cellLabel(grid_, gap.near_world.x(), gap.near_world.y()) != core::Label::Traversable) {
      continue;
    }
    const auto pts = sampleGap(gap, 0.5 * grid_.cellSize());
    for (std::size_t k = 0; k < pts.size(); ++k) {
      const double t = pts.size() > 1 ? static_cast<double>(k) / (pts.size() - 1) : 0.0;
      gx.push_back(static_cast<float>(pts[k].x()));
      gy.push_back(static_cast<float>(pts[k].y()));
      gz.push_back(static_cast<float>((1 - t) * gap.near_world.z() + t * gap.far_world.z()));
      last_missing_ground_.push_back(pts[k]);
    }
  }
  fuseNonTraversable(gx, gy, gz, robot_xy, time_s);
  // Step edges and bumps: where the fused elevations jump by more than the robot can climb, or
  // rise as a low smooth rock (the UPD smooths both away); fused as NonTraversable evidence (at
  // the cell's elevation) and obstacles at once.
  last_step_edges_ = maps::findStepEdges(grid_, robot_xy, config_.step_edges);
  const std::vector<Eigen::Vector2d> bumps = maps::findBumps(grid_, robot_xy, config_.step_edges);
  last_step_edges_.insert(last_step_edges_.end(), bumps.begin(), bumps.end());
  std::vector<float> ex, ey, ez;
  for (const auto& c : last_step_edges_) {
    const maps::GridCell* cell = grid_.cellAt(c.x(), c.y());
    ex.push_back(static_cast<float>(c.x()));
    ey.push_back(static_cast<float>(c.y()));
    ez.push_back(cell != nullptr && std::isfinite(cell->elevation_m) ? cell->elevation_m : 0.0f);
  }
  fuseNonTraversable(ex, ey, ez, robot_xy, time_s);
  std::vector<Eigen::Vector2d> frame_obstacles = last_frame_.obstacles_world;
  frame_obstacles.insert(frame_obstacles.end(), last_missing_ground_.begin(),
                         last_missing_ground_.end());
  frame_obstacles.insert(frame_obstacles.end(), last_step_edges_.begin(), last_step_edges_.end());
  obstacles_.setFrameObstacles(std::move(frame_obstacles));
  return last_frame_;
}

void NavigationLoop::fuseNonTraversable(const std::vector<float>& x, const std::vector<float>& y,
                                        const std::vector<float>& z,
                                        const Eigen::Vector2d& robot_xy, double time_s) {
  if (x.empty()) return;
  const std::vector<core::Label> labels(x.size(), core::Label::NonTraversable);
  maps::PointsWorld pts;
  pts.x = x.data();
  pts.y = y.data();
  pts.z = z.data();
  pts.label = labels.data();
  pts.size = x.size();
  maps::integrateScan(grid_, pts, robot_xy, time_s, config_.fusion);
}

void NavigationLoop::labelFrame(const core::PointCloud& cloud_world) {
  FrameEvidence& f = last_frame_;
  f.cloud_world = cloud_world;
  f.normals_world = {};
  f.upd = {};
  f.classes = {};
  f.obstacles_world.clear();
  f.timings = {};
  f.classes.label.resize(cloud_world.size());
  for (std::size_t i = 0; i < cloud_world.size(); ++i) {
    const double x = cloud_world.x[i], y = cloud_world.y[i];
    const core::Label l = std::isfinite(x) && std::isfinite(y) && std::isfinite(cloud_world.z[i])
                              ? labeller_(x, y)
                              : core::Label::Unknown;
    f.classes.label[i] = l;
    if (l == core::Label::NonTraversable) {
      ++f.classes.non_traversable;
      f.obstacles_world.emplace_back(x, y);
    } else if (l == core::Label::Traversable) {
      ++f.classes.traversable;
    } else {
      ++f.classes.unknown;
    }
  }
}

void NavigationLoop::setFixedObstacles(std::vector<Eigen::Vector2d> points_world) {
  fixed_world_ = points_world;
  obstacles_.setFixedObstacles(std::move(points_world));
}

void NavigationLoop::navigateTo(const Eigen::Vector2d& goal_world) {
  if (!navigator_) {
    NavigatorSetup setup;
    setup.ptg_ini_path = config_.ptg_ini;
    setup.ptg_cache_dir = cacheDirFor(config_.ptg_cache_dir, config_.ptg_ini);
    setup.navlog_path = navlog_path_;
    setup.params = config_.navigator;
    navigator_ = std::make_unique<Navigator>(base_, obstacles_, setup);
  }
  goal_world_ = goal_world;
  route_ = Route{};
  failed_plans_ = 0;
  replanning_stopped_ = false;
  best_route_m_ = std::numeric_limits<double>::infinity();
  last_progress_s_ = base_.timeS();
  recoveries_ = 0;
  recovering_ = false;
  restartStallWatch();
  replan();
  if (!route_.found) navigator_->navigateTo(goal_world);
}

void NavigationLoop::replan() {
  const Pose2D pose = robotPose();
  last_plan_s_ = base_.timeS();
  Route r = planRoute(grid_, fixed_world_, {pose.x_m, pose.y_m},
                      goal_world_, config_.route);
  if (r.found && r.length_m < best_route_m_ - kProgress_m) {
    best_route_m_ = r.length_m;
    last_progress_s_ = last_plan_s_;
  }
  if (r.found && route_.found && routeBlocked(grid_, route_) &&
      routeDiffers(r, route_, kRouteLookahead_m, kRouteTolerance_m)) {
    // The map closed the route being driven and another way is open: what the robot has seen
    // is progress even when the new way is longer (the way round a wall leads away from the
    // goal first), so the best length starts again from it.
    best_route_m_ = r.length_m;
    last_progress_s_ = last_plan_s_;
  }
  if (last_plan_s_ - last_progress_s_ > config_.navigator.no_progress_timeout_s) {
    // The way to the goal has not got shorter for a while (circling a walled-in goal, each
    // route through a stretch of wall not seen yet): stop replanning and leave the navigator on
    // its last route, so it ends with its own error if it cannot get on.
    replanning_stopped_ = true;
  }
  if (!r.found) {
    // Keep driving the last route: the navigator reports its own error when it cannot get on.
    ++failed_plans_;
    return;
  }
  if (replanning_stopped_) return;
  // The route is kept while the new one follows it. One that became blocked within the
  // lookahead is replaced: the new route cannot pass there, so it leaves the old one.
  if (!routeDiffers(r, route_, kRouteLookahead_m, kRouteTolerance_m) &&
      navigator_->state() == NavState::Navigating) {
    return;
  }
  route_ = std::move(r);
  navigator_->followWaypoints(route_.waypoints);
}

bool NavigationLoop::navigating() const {
  return navigator_ && navigator_->state() == NavState::Navigating;
}

double NavigationLoop::routeHeadingError(const Pose2D& pose) const {
  constexpr double kAhead_m = 1.0;
  const Eigen::Vector2d xy(pose.x_m, pose.y_m);
  Eigen::Vector2d aim = goal_world_;
  if (route_.found && !route_.path_world.empty()) {
    const auto& path = route_.path_world;
    std::size_t nearest = 0;
    for (std::size_t i = 1; i < path.size(); ++i) {
      if ((path[i] - xy).squaredNorm() < (path[nearest] - xy).squaredNorm()) nearest = i;
    }
    aim = path.back();
    for (std::size_t i = nearest; i < path.size(); ++i) {
      if ((path[i] - xy).norm() >= kAhead_m) {
        aim = path[i];
        break;
      }
    }
  }
  const Eigen::Vector2d d = worldToRobot(pose, aim);
  return std::atan2(d.y(), d.x());
}

void NavigationLoop::restartStallWatch() {
  const Pose2D pose = robotPose();
  stall_anchor_xy_ = {pose.x_m, pose.y_m};
  stall_anchor_s_ = base_.timeS();
}

namespace {

std::uint64_t cellKey(std::int64_t i, std::int64_t j) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(i)) << 32) |
         static_cast<std::uint32_t>(j);
}

// Calls f(i, j, centre) for every grid cell (world indices: the centre of cell (i, j) is
// ((i + 0.5) cs, (j + 0.5) cs)) in the square of half side r_m around xy.
template <class F>
void forEachCellAround(const Eigen::Vector2d& xy, double r_m, double cs, F&& f) {
  const auto index = [&](double v_m) { return static_cast<std::int64_t>(std::floor(v_m / cs)); };
  for (std::int64_t j = index(xy.y() - r_m); j <= index(xy.y() + r_m); ++j) {
    for (std::int64_t i = index(xy.x() - r_m); i <= index(xy.x() + r_m); ++i) {
      f(i, j, Eigen::Vector2d((static_cast<double>(i) + 0.5) * cs,
                              (static_cast<double>(j) + 0.5) * cs));
    }
  }
}

// Centres of the cells within reach_m of the robot that the map has not observed and the robot
// has not driven on (cells outside the grid's window included), in the robot frame.
std::vector<Eigen::Vector2d> unknownCellsInRobot(const maps::TraversabilityGrid& grid,
                                                 const std::unordered_set<std::uint64_t>& driven,
                                                 const Pose2D& pose_world_robot, double reach_m) {
  const Eigen::Vector2d centre(pose_world_robot.x_m, pose_world_robot.y_m);
  std::vector<Eigen::Vector2d> out;
  forEachCellAround(centre, reach_m, grid.cellSize(),
                    [&](std::int64_t i, std::int64_t j, const Eigen::Vector2d& c) {
    if ((c - centre).norm() > reach_m || driven.count(cellKey(i, j)) > 0) return;
    const maps::GridCell* cell = grid.cellAt(c.x(), c.y());
    if (cell != nullptr && maps::isKnown(*cell, grid.params())) return;
    out.push_back(worldToRobot(pose_world_robot, c));
  });
  return out;
}

}  // namespace

void NavigationLoop::markDrivenCells(const Pose2D& pose, double half_length_m,
                                     double half_width_m) {
  forEachCellAround({pose.x_m, pose.y_m}, std::hypot(half_length_m, half_width_m), grid_.cellSize(),
                    [&](std::int64_t i, std::int64_t j, const Eigen::Vector2d& c) {
    if (rectangleSignedDistance(worldToRobot(pose, c), half_length_m, half_width_m) <= 0.0) {
      driven_cells_.insert(cellKey(i, j));
    }
  });
}

Pose2D NavigationLoop::robotPose() {
  BaseState s;
  if (!base_.readState(s)) throw std::runtime_error("the robot base does not report its pose");
  return s.pose_world_robot;
}

Eigen::Vector2d NavigationLoop::polygonHalfSizes() const {
  Eigen::Vector2d half = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& v : navigator_->robotShape()) half = half.cwiseMax(v.cwiseAbs());
  return half;
}

void NavigationLoop::updateDrivenAndUnobserved() {
  const double behind_m = config_.obstacles.unobserved_behind_m;
  if (behind_m <= 0.0 && (!config_.recovery.enabled || config_.recovery.into_unobserved)) return;
  const Pose2D pose = robotPose();
  const Eigen::Vector2d half = polygonHalfSizes();
  markDrivenCells(pose, half.x(), half.y());
  if (behind_m <= 0.0) return;
  std::vector<Eigen::Vector2d> behind_world;
  for (const Eigen::Vector2d& p : unknownCellsInRobot(grid_, driven_cells_, pose,
                                                      half.x() + behind_m)) {
    if (p.x() < -half.x() - grid_.cellSize()) behind_world.push_back(robotToWorld(pose, p));
  }
  obstacles_.setUnobservedBehind(std::move(behind_world));
}

bool NavigationLoop::startRecoveryIfStalled() {
  const RecoveryParams& rp = config_.recovery;
  if (!rp.enabled) return false;
  const Pose2D pose = robotPose();
  // The navigator's own shape and obstacle points: the manoeuvre keeps the clearance it keeps.
  const Eigen::Vector2d half = polygonHalfSizes();
  const double half_length_m = half.x(), half_width_m = half.y();
  const double now = base_.timeS();
  const Eigen::Vector2d xy(pose.x_m, pose.y_m);
  if ((xy - stall_anchor_xy_).norm() > rp.stall_radius_m) {
    stall_anchor_xy_ = xy;
    stall_anchor_s_ = now;
    return false;
  }
  if (now - stall_anchor_s_ < rp.stall_time_s || recoveries_ >= rp.max_recoveries) return false;
  std::vector<Eigen::Vector2d> unobserved_robot;
  if (!rp.into_unobserved) {
    unobserved_robot = unknownCellsInRobot(
        grid_, driven_cells_, pose,
        recoveryReach(half_length_m, half_width_m, rp, grid_.cellSize()));
  }
  const RecoveryMotion m =
      planRecovery(obstacles_.pointsInRobot(pose), unobserved_robot, half_length_m,
                   half_width_m, routeHeadingError(pose), rp);
  // Watch the next stretch of time whether or not a manoeuvre was found.
  stall_anchor_s_ = now;
  if (!m.feasible()) return false;
  ++recoveries_;
  recovering_ = true;
  recovery_ = m;
  recovery_end_s_ = now + m.duration_s;
  return true;
}

NavState NavigationLoop::step() {
  if (!navigator_) throw std::logic_error("NavigationLoop::step before navigateTo");
  if (recovering_) {
    // Each command holds for a control period: stop before the feasible duration runs out.
    if (base_.timeS() + config_.loop.control_period_s <= recovery_end_s_ + 1e-6) {
      base_.sendVelocity(recovery_.command);
      return navigator_->state();
    }
    recovering_ = false;
    restartStallWatch();
    // Start the navigator again (its motion state and no-progress clock start anew).
    replan();
    if (route_.found) {
      navigator_->followWaypoints(route_.waypoints);
    } else {
      navigator_->navigateTo(goal_world_);
    }
  } else if (navigator_->state() == NavState::Navigating && startRecoveryIfStalled()) {
    base_.sendVelocity(recovery_.command);
    return navigator_->state();
  }
  if (navigator_->state() == NavState::Navigating && !replanning_stopped_ &&
      base_.timeS() - last_plan_s_ >= config_.route.replan_period_s) {
    replan();
  }
  updateDrivenAndUnobserved();
  return navigator_->step();
}

NavOutcome NavigationLoop::outcome() const {
  return navigator_ ? navigator_->outcome() : NavOutcome{};
}

void NavigationLoop::finish() {
  if (!navigator_) return;
  if (navigator_->state() == NavState::Navigating) navigator_->cancel();
  base_.stop(false);
  navigator_->closeLog();
}

}  // namespace upd::nav
