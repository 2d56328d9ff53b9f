// Every parameter section the `upd` commands read from an ini file, in one place: loaded
// strictly (an unknown section or key is an error) and listed by `upd params`.
#pragma once

#include "upd/core/baselines.h"
#include "upd/maps/fusion.h"
#include "upd/maps/traversability_grid.h"
#include "upd/maps/traversability_octree.h"
#include "upd/mrpt/pose_source.h"
#include "upd/mrpt/simulated_run.h"
#include "upd/mrpt/upd_observer.h"

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
    requireParam(tolerance_m >= 0, "EvaluationParams", "tolerance_m", tolerance_m, "must be >= 0");
  }
  template <class V>
  void visit(V& v) {
    v("tolerance_m", tolerance_m,
      "map and truth obstacles this close match when scoring precision and recall; d_m [m]");
  }
};

struct RunConfig {
  mrptbridge::ObserverParams observer;  ///< pipeline + how observations become clouds
  maps::GridParams grid;
  maps::FusionParams fusion;
  maps::OctreeParams octree;
  mrptbridge::GroundTruthParams ground_truth;
  mrptbridge::SimulationParams simulation;
  EvaluationParams evaluation;
  BaselineParams baseline;
};

/// The `up` key of [PipelineParams] as a visitable section.
struct UpSection {
  Eigen::Vector3f& up;
  void validate() const {}
  template <class V>
  void visit(V& v) {
    v("up", up, "gravity-up direction x,y,z in the cloud frame (any length)");
  }
};

/// Calls f(section_name, description, params) for every section, in documentation order.
template <class F>
void forEachSection(RunConfig& c, F&& f) {
  UpSection up{c.observer.pipeline.up};
  f("PipelineParams", "Frames of the UPD pipeline.", up);
  f("PreprocessParams",
    "Pre-processing (paper section 3): range cut-off, voxel down-sampling, outlier removal.",
    c.observer.pipeline.preprocess);
  f("NormalParams", "PCA normals (paper eqs. 4-5).", c.observer.pipeline.normals);
  f("UpdParams", "The Unevenness Point Descriptor (paper eqs. 6-8).", c.observer.pipeline.upd);
  f("ClassifyParams", "Traversability labels and cost from the UPD.",
    c.observer.pipeline.classify);
  f("BaselineParams", "The paper's baselines (roughness and inclination index).", c.baseline);
  f("SourceParams", "How MRPT observations become clouds (LiDAR ranges, stereo calibration).",
    c.observer.source);
  f("StereoMatchParams", "OpenCV StereoSGBM disparity for CObservationStereoImages.",
    c.observer.source.stereo);
  f("GridParams", "The 2.5D traversability grid (a window that follows the robot).", c.grid);
  f("FusionParams", "Log-odds fusion of per-point evidence into cells and voxels.", c.fusion);
  f("OctreeParams", "The OctoMap traversability tree.", c.octree);
  f("GroundTruthParams", "Ground-truth pose files (TUM) given to `upd playback --poses`.",
    c.ground_truth);
  f("SimulationParams", "The simulated Dune of `upd simulate`.", c.simulation);
  f("RobotBodyParams", "The simulated robot's body (`upd simulate`; `upd navigate` reads it "
    "from the navigation config).", c.simulation.body);
  f("CameraMountParams", "The simulated robot's depth camera (`upd simulate`; `upd navigate` "
    "reads it from the navigation config).", c.simulation.camera);
  f("EvaluationParams", "Scoring a map against a ground-truth grid.", c.evaluation);
}

/// Reads every section present in path (absent keys keep their defaults), validates, and
/// rejects unknown sections and keys, naming the file, section, key and value.
RunConfig loadRunConfig(const std::string& path);

}  // namespace upd::app
