// Every parameter section the `upd` commands read from an ini file, in one place: loaded
// strictly (an unknown section or key is an error) and listed by `upd params`.
#pragma once

#include "upd/core/params.h"
#include "upd/mrpt_bridge/robot_config.h"
#include "upd/mrpt_bridge/upd_observer.h"

#include <string>

namespace upd::app {

/// How `upd playback` scores the fused map against a ground-truth grid.
struct EvaluationParams {
  /// A map cell and a truth cell this close count as the same obstacle [m]. The UPD of a point
  /// sums the normals within d_m (eq. 6), so it places an obstacle no more precisely than d_m:
  /// it flags a band about d_m wide around every obstacle, like a robot-sized inflation. Set
  /// this to d_m (0.5 m for the Dune); summary.json also reports strict cell-by-cell scores.
  double tolerance_m = 0.5;

  void validate() const {
    core::requireParam(tolerance_m >= 0, "EvaluationParams", "tolerance_m", tolerance_m, "must be >= 0");
  }
  template <class V>
  void visit(V& v) {
    v("tolerance_m", tolerance_m,
      "map and truth obstacles this close match when scoring precision and recall; d_m [m]");
  }
};

struct RunConfig {
  mrpt_bridge::ObserverParams observer;  ///< pipeline + how observations become clouds
  maps::GridParams grid;
  maps::FusionParams fusion;
  maps::OctreeParams octree;
  mrpt_bridge::GroundTruthParams ground_truth;
  mrpt_bridge::SimulationParams simulation;
  EvaluationParams evaluation;
  core::BaselineParams baseline;

  /// Every part of the robot config (mrpt_bridge::forEachRobotSection's list).
  mrpt_bridge::RobotConfigParts parts() {
    mrpt_bridge::RobotConfigParts p;
    p.pipeline = &observer.pipeline;
    p.baseline = &baseline;
    p.source = &observer.source;
    p.grid = &grid;
    p.fusion = &fusion;
    p.octree = &octree;
    p.ground_truth = &ground_truth;
    p.simulation = &simulation;
    return p;
  }
};

/// Calls f(section_name, description, params) for every section, in documentation order: the
/// robot config's list, then the app's own [EvaluationParams].
template <class F>
void forEachSection(RunConfig& c, F&& f) {
  mrpt_bridge::forEachRobotSection(c.parts(), f);
  f("EvaluationParams", "Scoring a map against a ground-truth grid.", c.evaluation);
}

/// Reads every section present in path (absent keys keep their defaults), validates, and
/// rejects unknown sections and keys, naming the file, section, key and value.
RunConfig loadRunConfig(const std::string& path);

}  // namespace upd::app
