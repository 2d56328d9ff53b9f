#include "upd/nav/navigator.h"

#include "upd/core/params.h"
#include "upd/nav/nav_interface.h"

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/nav/reactive/CReactiveNavigationSystem.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace fs = std::filesystem;

namespace upd::nav {

const char* toString(NavState s) {
  switch (s) {
    case NavState::Idle: return "IDLE";
    case NavState::Navigating: return "NAVIGATING";
    case NavState::Suspended: return "SUSPENDED";
    case NavState::Error: return "NAV_ERROR";
  }
  return "?";
}

void NavigatorParams::validate() const {
  core::requireParam(std::isfinite(target_allowed_distance_m) && target_allowed_distance_m > 0,
               "NavigatorParams", "target_allowed_distance_m", target_allowed_distance_m,
               "must be > 0");
  core::requireParam(std::isfinite(no_progress_timeout_s) && no_progress_timeout_s > 0, "NavigatorParams",
               "no_progress_timeout_s", no_progress_timeout_s, "must be > 0");
  core::requireParam(std::isfinite(waypoint_allowed_distance_m) && waypoint_allowed_distance_m > 0,
               "NavigatorParams", "waypoint_allowed_distance_m", waypoint_allowed_distance_m,
               "must be > 0");
}

namespace {

// MRPT's navigator with its always-on delay profiler silenced (it prints a table to stdout when
// destroyed) and its robot shape readable.
class ReactiveNavigator : public mrpt::nav::CReactiveNavigationSystem {
 public:
  explicit ReactiveNavigator(mrpt::nav::CRobot2NavInterface& robot)
      : mrpt::nav::CReactiveNavigationSystem(robot, /*enableConsoleOutput=*/false,
                                             /*enableLogFile=*/false) {
    m_timlog_delays.enable(false);
  }
  const mrpt::math::CPolygon& shape() const { return m_robotShape; }
};

NavState fromMrpt(mrpt::nav::CAbstractNavigator::TState s) {
  switch (s) {
    case mrpt::nav::CAbstractNavigator::IDLE: return NavState::Idle;
    case mrpt::nav::CAbstractNavigator::NAVIGATING: return NavState::Navigating;
    case mrpt::nav::CAbstractNavigator::SUSPENDED: return NavState::Suspended;
    case mrpt::nav::CAbstractNavigator::NAV_ERROR: return NavState::Error;
  }
  return NavState::Error;
}

const char* errorCodeName(mrpt::nav::CAbstractNavigator::TErrorCode c) {
  switch (c) {
    case mrpt::nav::CAbstractNavigator::ERR_NONE: return "";
    case mrpt::nav::CAbstractNavigator::ERR_EMERGENCY_STOP: return "ERR_EMERGENCY_STOP";
    case mrpt::nav::CAbstractNavigator::ERR_CANNOT_REACH_TARGET: return "ERR_CANNOT_REACH_TARGET";
    case mrpt::nav::CAbstractNavigator::ERR_OTHER: return "ERR_OTHER";
  }
  return "ERR_OTHER";
}

std::string readWholeFile(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw std::runtime_error("navigator config " + path + ": no such file");
  }
  std::ifstream in(path);
  std::ostringstream os;
  os << in.rdbuf();
  if (!in && !in.eof()) throw std::runtime_error("navigator config " + path + ": cannot read");
  return os.str();
}

// The collision grids are built once per PTG file and shared by every process through the
// cache directory. MRPT writes them while it initializes, so a process that finds no cache
// builds it in a private directory and renames that into place afterwards: another process
// never reads grids that are still being written.
std::string ptgBuildDir(const std::string& cache_dir) {
  if (fs::exists(cache_dir)) return cache_dir;
  std::random_device rd;
  return cache_dir + ".tmp." + std::to_string(rd()) + std::to_string(rd());
}

void publishPtgCache(const std::string& build_dir, const std::string& cache_dir) {
  if (build_dir == cache_dir) return;
  std::error_code ec;
  fs::rename(build_dir, cache_dir, ec);  // fails when another process published first
  if (ec) fs::remove_all(build_dir, ec);
}

}  // namespace

struct Navigator::Impl {
  Impl(RobotBase& base, const ObstacleSource& obstacles) : robot(base, obstacles), nav(robot) {}
  UpdNavInterface robot;
  ReactiveNavigator nav;
  NavigatorSetup setup;
  std::string log_tmp_dir;
  bool log_open = false;
};

Navigator::Navigator(RobotBase& base, const ObstacleSource& obstacles, const NavigatorSetup& setup)
    : impl_(std::make_unique<Impl>(base, obstacles)) {
  setup.params.validate();
  if (setup.ptg_cache_dir.empty()) {
    throw std::invalid_argument(
        "Navigator: ptg_cache_dir is empty (the PTG cache must not go "
        "to the working directory)");
  }
  impl_->setup = setup;
  auto& nav = impl_->nav;
  nav.logging_enable_console_output = false;
  nav.setMinLoggingLevel(mrpt::system::LVL_WARN);

  const mrpt::config::CConfigFileMemory cfg(readWholeFile(setup.ptg_ini_path));
  try {
    nav.loadConfigFile(cfg);
  } catch (const std::exception& e) {
    // MRPT's message spans several lines (with a call stack): keep its first "Message:" line.
    std::string msg = e.what();
    const auto at = msg.find("Message:");
    if (at != std::string::npos) msg = msg.substr(at + 8);
    const auto eol = msg.find('\n');
    if (eol != std::string::npos) msg = msg.substr(0, eol);
    throw std::runtime_error("navigator config " + setup.ptg_ini_path + ": " + msg);
  }
  if (nav.shape().size() < 3) {
    throw std::runtime_error("navigator config " + setup.ptg_ini_path +
                             ": [CReactiveNavigationSystem] needs the robot shape "
                             "RobotModel_shape2D_xs / RobotModel_shape2D_ys");
  }
  nav.params_abstract_navigator.alarm_seems_not_approaching_target_timeout =
      setup.params.no_progress_timeout_s;

  std::error_code ec;
  const std::string ptg_build_dir = ptgBuildDir(setup.ptg_cache_dir);
  fs::create_directories(ptg_build_dir, ec);
  if (ec) {
    throw std::runtime_error("PTG cache directory " + ptg_build_dir + ": " + ec.message());
  }
  nav.params_abstract_ptg_navigator.ptg_cache_files_directory = ptg_build_dir;

  if (!setup.navlog_path.empty()) {
    // MRPT names its log log_NNN.reactivenavlog inside a directory: write it in a private
    // directory beside the target and move it into place when it is closed.
    const fs::path target(setup.navlog_path);
    const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    fs::create_directories(dir, ec);
    impl_->log_tmp_dir = (dir / ("." + target.filename().string() + ".tmp.d")).string();
    fs::remove_all(impl_->log_tmp_dir, ec);
    fs::create_directories(impl_->log_tmp_dir, ec);
    if (ec) {
      throw std::runtime_error("navlog directory " + impl_->log_tmp_dir + ": " + ec.message());
    }
    nav.setLogFileDirectory(impl_->log_tmp_dir);
    nav.enableLogFile(true);
    impl_->log_open = true;
  }
  try {
    nav.initialize();
  } catch (...) {
    if (ptg_build_dir != setup.ptg_cache_dir) fs::remove_all(ptg_build_dir, ec);
    throw;
  }
  publishPtgCache(ptg_build_dir, setup.ptg_cache_dir);
}

Navigator::~Navigator() {
  try {
    closeLog();
  } catch (...) {
    // A destructor must not throw; closeLog() reports failures when called explicitly.
  }
}

void Navigator::navigateTo(const Eigen::Vector2d& goal_world) {
  if (!goal_world.allFinite())
    throw std::invalid_argument("Navigator::navigateTo: goal not finite");
  mrpt::nav::CAbstractNavigator::TNavigationParams np;
  np.target.target_coords = mrpt::math::TPose2D(goal_world.x(), goal_world.y(), 0.0);
  np.target.targetAllowedDistance =
      static_cast<float>(impl_->setup.params.target_allowed_distance_m);
  np.target.targetIsRelative = false;
  impl_->nav.navigate(&np);
}

void Navigator::followWaypoints(const std::vector<Eigen::Vector2d>& waypoints_world) {
  if (waypoints_world.empty())
    throw std::invalid_argument("Navigator::followWaypoints: no waypoint");
  mrpt::nav::TWaypointSequence seq;
  for (std::size_t i = 0; i < waypoints_world.size(); ++i) {
    const auto& w = waypoints_world[i];
    if (!w.allFinite())
      throw std::invalid_argument("Navigator::followWaypoints: waypoint not finite");
    const bool last = i + 1 == waypoints_world.size();
    seq.waypoints.emplace_back(w.x(), w.y(),
                               last ? impl_->setup.params.target_allowed_distance_m
                                    : impl_->setup.params.waypoint_allowed_distance_m,
                               /*allow_skip=*/impl_->setup.params.skip_waypoints);
  }
  impl_->nav.navigateWaypoints(seq);
}

NavState Navigator::step() {
  impl_->nav.navigationStep();
  return state();
}

NavState Navigator::state() const { return fromMrpt(impl_->nav.getCurrentState()); }

NavOutcome Navigator::outcome() const {
  NavOutcome o;
  o.state = state();
  o.target_reached = impl_->robot.events().ends > 0;
  if (o.state == NavState::Error) {
    const auto& r = impl_->nav.getErrorReason();
    o.error_code = errorCodeName(r.error_code);
    o.error_message = r.error_msg;
  }
  return o;
}

void Navigator::cancel() { impl_->nav.cancel(); }

std::vector<Eigen::Vector2d> Navigator::robotShape() const {
  std::vector<Eigen::Vector2d> out;
  for (const auto& v : impl_->nav.shape()) out.emplace_back(v.x, v.y);
  return out;
}

std::size_t Navigator::lastObstacleCount() const { return impl_->robot.lastObstacleCount(); }

void Navigator::closeLog() {
  if (!impl_->log_open) return;
  impl_->log_open = false;
  impl_->nav.enableLogFile(false);
  std::error_code ec;
  fs::path produced;
  for (const auto& e : fs::directory_iterator(impl_->log_tmp_dir, ec)) {
    if (e.path().extension() == ".reactivenavlog") produced = e.path();
  }
  if (produced.empty()) {
    fs::remove_all(impl_->log_tmp_dir, ec);
    throw std::runtime_error("navlog: MRPT wrote no log in " + impl_->log_tmp_dir);
  }
  fs::rename(produced, impl_->setup.navlog_path, ec);
  if (ec) {
    throw std::runtime_error("navlog " + impl_->setup.navlog_path + ": " + ec.message());
  }
  fs::remove_all(impl_->log_tmp_dir, ec);
}

}  // namespace upd::nav
