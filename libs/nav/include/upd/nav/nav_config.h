// Every parameter of the navigation loop (`upd navigate`, `upd live`), from two ini files:
//  1. the robot config (`--config`, default config/dune-kinect.ini), shared by every `upd`
//     command: the loop reads its UPD pipeline, [BaselineParams], [GridParams] and
//     [FusionParams] and leaves its other sections to the commands that own them (the `upd`
//     commands check the whole file strictly);
//  2. the navigation config (`--nav-config`, default config/dune-nav.ini), read strictly (an
//     unknown section or key is an error naming the file): robot body, camera mount, depth
//     noise, simulated base, obstacles, missing ground, route planner, navigator and loop.
// [NavigatorParams] also holds two paths, read as strings: ptg_ini (the MRPT navigator's own ini
// file, relative to the file that names it) and ptg_cache_dir (where the PTG collision grids
// are cached; empty = the user's cache directory, never the working directory).
#pragma once

#include "upd/core/baselines.h"
#include "upd/core/pipeline.h"
#include "upd/maps/fusion.h"
#include "upd/maps/step_edges.h"
#include "upd/maps/traversability_grid.h"
#include "upd/nav/navigator.h"
#include "upd/nav/negative_obstacles.h"
#include "upd/nav/obstacles.h"
#include "upd/nav/recovery.h"
#include "upd/nav/robot_base.h"
#include "upd/nav/route_planner.h"
#include "upd/sim/render.h"
#include "upd/sim/robot.h"

#include <string>
#include <vector>

namespace upd::nav {

/// The closed loop in simulation. Loaded from [LoopParams].
struct LoopParams {
  double control_period_s = 0.2;    ///< one frame, one navigator step, one motion step [s]
  double max_time_s = 300.0;        ///< simulated time limit; the run ends as "time limit" [s]
  int seed = 1;                     ///< depth-noise seed (frame k uses seed + k)
  bool fence_world = true;          ///< the world's border is an obstacle (the mission area)
  double truth_cell_m = 0.025;      ///< raster of the ground-truth checks [m]
  double clearance_search_m = 2.0;  ///< clearance is reported up to this distance [m]

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("control_period_s", control_period_s, "frame + navigator step + motion per period [s]");
    v("max_time_s", max_time_s, "simulated time limit of a run [s]");
    v("seed", seed, "depth-noise seed (frame k uses seed + k)");
    v("fence_world", fence_world, "treat the border of the world as an obstacle");
    v("truth_cell_m", truth_cell_m, "cell of the ground-truth raster for collisions [m]");
    v("clearance_search_m", clearance_search_m, "clearance is measured up to this distance [m]");
  }
};

/// What the loop changes in the robot config's pipeline. Loaded from [PerceptionParams].
struct PerceptionParams {
  /// d_m of the UPD that labels the navigator's obstacles [m], and of the roughness baseline
  /// when it does instead (compared at the same neighbourhood); 0: the robot config's
  /// [UpdParams] and [BaselineParams] radius_m. The UPD marks a band of about 0.7 d_m round every obstacle, and the
  /// route keeps RoutePlannerParams::inflation_m from it: at the paper's 0.5 m a gap narrower
  /// than about 1.55 m closes for the Dune, at 0.3 m one of 0.95 m (the robot's width plus
  /// 0.5 m) still does, at 0.2 m it stays open. Low edges the smaller d_m no longer smooths
  /// away are the step-edge check's (upd/maps/step_edges.h).
  double upd_radius_m = 0.2;

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("upd_radius_m", upd_radius_m,
      "d_m of the UPD (or the roughness baseline) for the navigator's obstacles [m]; 0: the "
      "robot config's [UpdParams] and [BaselineParams] radius_m");
  }
};

struct NavConfig {
  core::PipelineParams pipeline;
  core::BaselineParams baseline;
  maps::GridParams grid;
  maps::FusionParams fusion;
  sim::DepthNoise depth_noise;
  sim::RobotBodyParams body;
  sim::CameraMountParams camera;
  SimulatedBaseParams base;
  ObstacleParams obstacles;
  NegativeObstacleParams negative;
  maps::StepEdgeParams step_edges;
  RoutePlannerParams route;
  NavigatorParams navigator;
  RecoveryParams recovery;
  LoopParams loop;
  PerceptionParams perception;
  std::string ptg_ini;        ///< absolute path of the MRPT navigator ini
  std::string ptg_cache_dir;  ///< absolute path; defaultPtgCacheDir() when not configured

  /// Validates every part (std::invalid_argument naming the field).
  void validate() const;
};

/// Calls f(section, description, params) for every section of the navigation config
/// ([NavigatorParams]'s two path keys aside), in documentation order.
template <class F>
void forEachNavSection(NavConfig& c, F&& f) {
  f("RobotBodyParams", "The robot's footprint, for the navigator's collision checks.", c.body);
  f("CameraMountParams", "Where the depth camera sits on the robot.", c.camera);
  f("DepthNoise", "Noise of the simulated depth camera.", c.depth_noise);
  f("SimulatedBaseParams", "The simulated base that executes the velocity commands.", c.base);
  f("PerceptionParams", "What the loop changes in the robot config's UPD pipeline.",
    c.perception);
  f("ObstacleParams", "Which labelled points become obstacles for the reactive navigator.",
    c.obstacles);
  f("NegativeObstacleParams", "Drops and holes seen as missing ground.", c.negative);
  f("StepEdgeParams",
    "Step edges and bumps found on the grid's elevations (upd/maps/step_edges.h).", c.step_edges);
  f("RoutePlannerParams", "The global route over the traversability grid.", c.route);
  f("NavigatorParams",
    "MRPT's reactive navigator (its PTGs come from the file that `ptg_ini` names; "
    "`ptg_cache_dir` holds their tables).",
    c.navigator);
  f("RecoveryParams", "What the loop does when the robot stalls (upd/nav/recovery.h).",
    c.recovery);
  f("LoopParams", "The closed loop of `upd navigate`.", c.loop);
}

/// Reads the robot config's sections (absent ones keep their defaults), then the navigation
/// config strictly, and validates (see the header comment). Throws std::runtime_error /
/// std::invalid_argument naming the file, section, key and value.
NavConfig loadNavConfig(const std::string& robot_ini, const std::string& nav_ini);

/// UPD-Nav's data directory (config/, samples/; share/README.md): $UPD_NAV_DATA_DIR when set,
/// else found from the running executable: <prefix>/bin/upd -> <prefix>/share/upd-nav once
/// installed, build/apps/upd/upd -> build/share/upd-nav in the build tree (the first of the two
/// that holds a config/ directory). Throws std::runtime_error naming the places searched.
std::string defaultDataDir();
/// The shipped configs: $UPD_CONFIG_DIR when set, else defaultDataDir()/config.
std::string defaultConfigDir();
/// $XDG_CACHE_HOME/upd-nav/ptg, else $HOME/.cache/upd-nav/ptg, else <temp>/upd-nav-ptg.
std::string defaultPtgCacheDir();

}  // namespace upd::nav
