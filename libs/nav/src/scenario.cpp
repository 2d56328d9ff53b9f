#include "upd/nav/scenario.h"

#include "upd/core/stopwatch.h"
#include "upd/core/version.h"
#include "upd/io/atomic_file.h"
#include "upd/io/json_io.h"
#include "upd/maps/grid_export.h"
#include "upd/nav/navigation_loop.h"
#include "upd/sim/robot.h"
#include "upd/sim/truth_raster.h"

#include <mrpt/core/Clock.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace upd::nav {

const char* toString(RunEnd e) {
  switch (e) {
    case RunEnd::GoalReached: return "goal reached";
    case RunEnd::NavigatorError: return "navigator error";
    case RunEnd::NavigatorStopped: return "navigator stopped";
    case RunEnd::TimeLimit: return "time limit";
  }
  return "?";
}

namespace {

// The simulated clock of MRPT (the navigator timestamps with mrpt::Clock::now()) for the
// duration of a run; the previous clock comes back on every exit path.
class SimulatedClock {
 public:
  SimulatedClock() : previous_(mrpt::Clock::getActiveClock()) {
    mrpt::Clock::setActiveClock(mrpt::Clock::Simulated);
    set(0.0);
  }
  ~SimulatedClock() { mrpt::Clock::setActiveClock(previous_); }
  SimulatedClock(const SimulatedClock&) = delete;
  SimulatedClock& operator=(const SimulatedClock&) = delete;
  // An epoch offset keeps timestamps away from MRPT's INVALID_TIMESTAMP (0).
  void set(double sim_time_s) {
    mrpt::Clock::setSimulatedTime(mrpt::Clock::fromDouble(1.0e9 + sim_time_s));
  }

 private:
  mrpt::Clock::Source previous_;
};

}  // namespace

namespace {

Eigen::Vector3d xyYaw(const Pose2D& p) { return {p.x_m, p.y_m, p.yaw_rad}; }

// One run in progress: the simulated base, the loop and the ground truth it is checked against.
class ScenarioRun {
 public:
  ScenarioRun(const sim::WorldSpec& world, const NavConfig& config, core::ObstacleDetector detector,
              const std::string& navlog_path, const NavigationLoop::PointLabeller& labeller)
      : world_(world),
        config_(config),
        base_(Pose2D{world.start_xy_yaw.x(), world.start_xy_yaw.y(), world.start_xy_yaw.z()},
              config.base),
        loop_(base_, config, detector, navlog_path),
        truth_(world.terrain, config.loop.truth_cell_m) {
    if (labeller) loop_.setLabeller(labeller);
    if (config.loop.fence_world) {
      loop_.setFixedObstacles(rectangleFence(world.terrain.minXY(), world.terrain.maxXY(),
                                             config.obstacles.decimation_m));
    }
  }

  // The state after a step, checked against the truth.
  TrajectorySample sample(NavState state) const {
    TrajectorySample s;
    s.t_s = base_.timeS();
    s.pose_world_robot = base_.pose();
    const Eigen::Vector3d pose = xyYaw(s.pose_world_robot);
    s.z_m = sim::bodyPoseOnTerrain(world_.terrain, pose, config_.body).translation().z();
    s.command = base_.lastCommand();
    s.clearance_m = truth_.clearance(pose, config_.body, config_.loop.clearance_search_m);
    s.collision = s.clearance_m <= 0.0;
    s.state = state;
    return s;
  }

  // One control step: render the camera from the body pose on the terrain, add the frame,
  // step the navigator and move the base. frame_ms: the frame's scoring time.
  TrajectorySample step(int k, SimulatedClock& clock, double& frame_ms) {
    clock.set(base_.timeS());
    const Eigen::Isometry3d body =
        sim::bodyPoseOnTerrain(world_.terrain, xyYaw(base_.pose()), config_.body);
    const core::PointCloud cloud =
        sim::renderCameraWorld(world_.terrain, body, config_.camera, config_.depth_noise,
                               static_cast<std::uint32_t>(config_.loop.seed + k));
    const FrameEvidence& ev = loop_.addFrame(cloud, base_.timeS(), body.translation().z());
    frame_ms = ev.timings.total_ms;
    const NavState state = loop_.step();
    base_.advance(config_.loop.control_period_s);
    TrajectorySample s = sample(state);
    s.obstacle_points = loop_.navigator()->lastObstacleCount();
    s.frame_nontraversable = ev.obstacles_world.size();
    return s;
  }

  SimulatedDiffDrive& base() { return base_; }
  NavigationLoop& loop() { return loop_; }

 private:
  const sim::WorldSpec& world_;
  const NavConfig& config_;
  SimulatedDiffDrive base_;
  NavigationLoop loop_;
  const sim::TruthRaster truth_;
};

// The run's totals from its trajectory and the loop's end state.
void summarize(ScenarioRun& run, const sim::WorldSpec& world, const NavConfig& config,
               NavState state, double frame_ms_sum, ScenarioResult& r) {
  r.navigator = run.loop().outcome();
  run.loop().finish();
  const Pose2D end = run.base().pose();
  r.final_distance_to_goal_m = std::hypot(end.x_m - world.goal_xy.x(), end.y_m - world.goal_xy.y());
  r.reached = r.navigator.target_reached && state == NavState::Idle;
  if (r.reached) r.end = RunEnd::GoalReached;
  r.sim_time_s = run.base().timeS();
  r.min_clearance_m = config.loop.clearance_search_m;
  for (std::size_t i = 1; i < r.trajectory.size(); ++i) {
    r.min_clearance_m = std::min(r.min_clearance_m, r.trajectory[i].clearance_m);
    r.collision_steps += r.trajectory[i].collision ? 1 : 0;
  }
  r.mean_frame_ms = r.steps > 0 ? frame_ms_sum / r.steps : 0.0;
  r.grid = run.loop().grid();
  r.route = run.loop().route();
  r.failed_plans = run.loop().failedPlans();
  r.replanning_stopped = run.loop().replanningStopped();
  r.recoveries = run.loop().recoveries();
}

}  // namespace

ScenarioResult runScenario(const sim::WorldSpec& world, const std::string& name,
                           const NavConfig& config, core::ObstacleDetector detector,
                           const std::string& navlog_path, const StepCallback& on_step,
                           const NavigationLoop::PointLabeller& labeller) {
  config.validate();
  const core::Stopwatch wall;
  SimulatedClock clock;
  ScenarioRun run(world, config, detector, navlog_path, labeller);

  ScenarioResult r;
  r.scenario = name;
  r.detector = detector;
  r.goal_xy = world.goal_xy;
  r.trajectory.push_back(run.sample(NavState::Navigating));

  run.loop().navigateTo(world.goal_xy);
  double frame_ms_sum = 0.0;
  NavState state = NavState::Navigating;
  r.end = RunEnd::TimeLimit;
  for (int k = 0;; ++k) {
    double frame_ms = 0.0;
    const TrajectorySample s = run.step(k, clock, frame_ms);
    frame_ms_sum += frame_ms;
    state = s.state;
    const auto& prev = r.trajectory.back().pose_world_robot;
    r.path_length_m +=
        std::hypot(s.pose_world_robot.x_m - prev.x_m, s.pose_world_robot.y_m - prev.y_m);
    r.trajectory.push_back(s);
    ++r.steps;
    if (on_step) on_step(s);

    if (state == NavState::Error) {
      r.end = RunEnd::NavigatorError;
      break;
    }
    if (state != NavState::Navigating) {
      r.end = RunEnd::NavigatorStopped;
      break;
    }
    if (run.base().timeS() >= config.loop.max_time_s) break;
  }
  summarize(run, world, config, state, frame_ms_sum, r);
  r.navlog_path = navlog_path;
  r.wall_time_s = wall.elapsedMs() / 1000.0;
  return r;
}

nlohmann::json summaryJson(const ScenarioResult& r) {
  nlohmann::json j;
  j["upd_nav_version"] = core::version();
  j["scenario"] = r.scenario;
  j["obstacles"] = r.perception.empty() ? std::string(toString(r.detector)) : r.perception;
  j["reached"] = r.reached;
  j["end"] = toString(r.end);
  j["navigator"] = {{"state", toString(r.navigator.state)},
                    {"target_reached_event", r.navigator.target_reached},
                    {"error_code", r.navigator.error_code},
                    {"error_message", r.navigator.error_message}};
  j["goal_xy_m"] = {r.goal_xy.x(), r.goal_xy.y()};
  const auto& last = r.trajectory.back().pose_world_robot;
  j["final_pose"] = {{"x_m", last.x_m}, {"y_m", last.y_m}, {"yaw_rad", last.yaw_rad}};
  j["final_distance_to_goal_m"] = r.final_distance_to_goal_m;
  j["sim_time_s"] = r.sim_time_s;
  j["steps"] = r.steps;
  j["path_length_m"] = r.path_length_m;
  j["min_clearance_m"] = r.min_clearance_m;
  j["collisions"] = r.collision_steps;
  j["route_plans_failed"] = r.failed_plans;
  j["route_replanning_stopped"] = r.replanning_stopped;
  j["recoveries"] = r.recoveries;
  j["mean_frame_scoring_ms"] = r.mean_frame_ms;
  j["wall_time_s"] = r.wall_time_s;
  j["navlog"] = r.navlog_path.empty() ? "" : fs::path(r.navlog_path).filename().string();
  return j;
}

namespace {

// A top view of the world: pixel (row, col) <-> world (x, y), north up.
struct TopView {
  Eigen::Vector2d min_xy, max_xy;
  double m_per_px;
  int width, height;

  TopView(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, double res)
      : min_xy(lo), max_xy(hi), m_per_px(res) {
    width = static_cast<int>(std::ceil((hi.x() - lo.x()) / res));
    height = static_cast<int>(std::ceil((hi.y() - lo.y()) / res));
  }
  Eigen::Vector2d world(int row, int col) const {
    return {min_xy.x() + (col + 0.5) * m_per_px, max_xy.y() - (row + 0.5) * m_per_px};
  }
  cv::Point pixel(double x, double y) const {
    return {static_cast<int>(std::lround((x - min_xy.x()) / m_per_px - 0.5)),
            static_cast<int>(std::lround((max_xy.y() - y) / m_per_px - 0.5))};
  }
};

cv::Vec3b bgr(const std::array<std::uint8_t, 3>& rgb) { return {rgb[2], rgb[1], rgb[0]}; }

void drawFootprint(cv::Mat& img, const TopView& v, const Pose2D& pose,
                   const sim::RobotBodyParams& body, const cv::Scalar& colour) {
  const double hl = 0.5 * body.length_m, hw = 0.5 * body.width_m;
  std::vector<cv::Point> poly;
  for (const auto& c : {Eigen::Vector2d(hl, hw), Eigen::Vector2d(hl, -hw),
                        Eigen::Vector2d(-hl, -hw), Eigen::Vector2d(-hl, hw)}) {
    const Eigen::Vector2d w = robotToWorld(pose, c);
    poly.push_back(v.pixel(w.x(), w.y()));
  }
  cv::polylines(img, poly, true, colour, 2, cv::LINE_AA);
  const Eigen::Vector2d nose = robotToWorld(pose, {hl + 0.15, 0.0});
  cv::line(img, v.pixel(pose.x_m, pose.y_m), v.pixel(nose.x(), nose.y()), colour, 2, cv::LINE_AA);
}

cv::Mat drawPathImage(const TopView& v, const std::function<cv::Vec3b(double, double)>& background,
                      const ScenarioResult& r, const sim::WorldSpec& world,
                      const sim::RobotBodyParams& body, const std::string& title,
                      const std::string& subtitle) {
  const int header = 44;
  cv::Mat img(v.height + header, v.width, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::Mat map = img(cv::Rect(0, header, v.width, v.height));
  for (int row = 0; row < v.height; ++row) {
    for (int col = 0; col < v.width; ++col) {
      const Eigen::Vector2d p = v.world(row, col);
      map.at<cv::Vec3b>(row, col) = background(p.x(), p.y());
    }
  }
  // The world's border, then the path (blue), collisions (magenta), start and end footprints,
  // and the goal with the tolerance circle.
  cv::rectangle(map, v.pixel(world.terrain.minXY().x(), world.terrain.maxXY().y()),
                v.pixel(world.terrain.maxXY().x(), world.terrain.minXY().y()),
                cv::Scalar(60, 60, 60), 1);
  if (r.route.found) {
    std::vector<cv::Point> route;
    for (const auto& p : r.route.path_world) route.push_back(v.pixel(p.x(), p.y()));
    cv::polylines(map, route, false, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    for (const auto& w : r.route.waypoints) {
      cv::circle(map, v.pixel(w.x(), w.y()), 3, cv::Scalar(0, 0, 0), cv::FILLED);
    }
  }
  std::vector<cv::Point> path;
  for (const auto& s : r.trajectory)
    path.push_back(v.pixel(s.pose_world_robot.x_m, s.pose_world_robot.y_m));
  cv::polylines(map, path, false, cv::Scalar(200, 60, 0), 2, cv::LINE_AA);
  for (const auto& s : r.trajectory) {
    if (s.collision) {
      cv::circle(map, v.pixel(s.pose_world_robot.x_m, s.pose_world_robot.y_m), 4,
                 cv::Scalar(255, 0, 255), cv::FILLED);
    }
  }
  drawFootprint(map, v, r.trajectory.front().pose_world_robot, body, cv::Scalar(90, 90, 90));
  drawFootprint(map, v, r.trajectory.back().pose_world_robot, body, cv::Scalar(200, 60, 0));
  const cv::Point goal = v.pixel(r.goal_xy.x(), r.goal_xy.y());
  cv::drawMarker(map, goal, cv::Scalar(0, 0, 0), cv::MARKER_CROSS, 16, 2);
  cv::circle(map, goal, std::max(2, static_cast<int>(std::lround(0.3 / v.m_per_px))),
             cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(img, title, cv::Point(6, 17), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  cv::putText(img, subtitle, cv::Point(6, 37), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0),
              1, cv::LINE_AA);
  return img;
}

void writePng(const std::string& path, const cv::Mat& img) {
  std::vector<unsigned char> buf;
  if (!cv::imencode(".png", img, buf)) throw std::runtime_error(path + ": PNG encoding failed");
  io::writeFileAtomically(path, [&](std::ostream& os) {
    os.write(reinterpret_cast<const char*>(buf.data()), static_cast<std::streamsize>(buf.size()));
  });
}

}  // namespace

void writeScenarioOutputs(const ScenarioResult& r, const sim::WorldSpec& world,
                          const sim::RobotBodyParams& body, const std::string& output_dir) {
  std::error_code ec;
  fs::create_directories(output_dir, ec);
  if (ec) throw std::runtime_error("output directory " + output_dir + ": " + ec.message());
  const fs::path dir(output_dir);

  io::writeFileAtomically((dir / "trajectory.csv").string(), [&](std::ostream& os) {
    os << "t_s,x_m,y_m,yaw_rad,z_m,v_cmd_mps,w_cmd_radps,clearance_m,collision,obstacle_points,"
          "frame_nontraversable,nav_state\n";
    os << std::setprecision(9);
    for (const auto& s : r.trajectory) {
      os << s.t_s << ',' << s.pose_world_robot.x_m << ',' << s.pose_world_robot.y_m << ','
         << s.pose_world_robot.yaw_rad << ',' << s.z_m << ',' << s.command.v_mps << ','
         << s.command.w_radps << ',' << s.clearance_m << ',' << (s.collision ? 1 : 0) << ','
         << s.obstacle_points << ',' << s.frame_nontraversable << ',' << toString(s.state) << '\n';
    }
  });

  const Eigen::Vector2d margin(0.5, 0.5);
  const TopView view(world.terrain.minXY() - margin, world.terrain.maxXY() + margin, 0.02);
  const std::string title = r.scenario + " / " +
                            (r.perception.empty() ? std::string(toString(r.detector)) : r.perception) +
                            ": " + toString(r.end);
  std::ostringstream stats;
  stats << std::fixed << std::setprecision(1) << r.sim_time_s << " s, " << r.path_length_m
        << " m driven, " << r.collision_steps << " collisions, min clearance "
        << std::setprecision(2) << r.min_clearance_m << " m";

  const auto map_bg = [&](double x, double y) {
    const maps::GridCell* c = r.grid.cellAt(x, y);
    const float p = c == nullptr ? std::numeric_limits<float>::quiet_NaN()
                                 : maps::probabilityOf(*c, r.grid.params());
    return bgr(maps::traversabilityColourRgb(p));
  };
  writePng((dir / "path_map.png").string(),
           drawPathImage(view, map_bg, r, world, body, title + " (path over the fused map)",
                         stats.str()));

  const auto truth_bg = [&](double x, double y) {
    switch (world.terrain.truthAt(x, y)) {
      case core::Label::Traversable: {
        // Shade by height so ramps and platforms read as relief.
        const double h = world.terrain.heightAt(x, y);
        const auto g = static_cast<std::uint8_t>(std::clamp(200.0 - 150.0 * h, 80.0, 230.0));
        return cv::Vec3b(static_cast<std::uint8_t>(g * 0.8), g, static_cast<std::uint8_t>(g * 0.8));
      }
      case core::Label::NonTraversable: return cv::Vec3b(40, 40, 180);
      case core::Label::Unknown: break;
    }
    return cv::Vec3b(128, 128, 128);
  };
  writePng((dir / "path_truth.png").string(),
           drawPathImage(view, truth_bg, r, world, body, title + " (path over the ground truth)",
                         stats.str()));

  io::writeJsonAtomically((dir / "summary.json").string(), summaryJson(r));
}

}  // namespace upd::nav
