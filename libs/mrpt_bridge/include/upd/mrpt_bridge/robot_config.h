// The sections of the robot config (`--config`, e.g. config/dune-kinect.ini), listed once.
//
// Every loader of the robot config walks this list: the UPD observer (pipeline and sources), the
// `upd` commands (every section, checked strictly), the navigation loop (the parts it uses) and
// `upd params` (the docs and the ini of defaults). A loader points the parts it holds at its own
// structs; the parts left null are not read by it (the `upd` commands check the whole file).
#pragma once

#include "upd/core/baselines.h"
#include "upd/core/pipeline.h"
#include "upd/maps/fusion.h"
#include "upd/maps/traversability_grid.h"
#include "upd/maps/traversability_octree.h"
#include "upd/mrpt_bridge/ini_params.h"
#include "upd/mrpt_bridge/observation_cloud.h"
#include "upd/mrpt_bridge/pose_source.h"
#include "upd/mrpt_bridge/simulated_run.h"

#include <Eigen/Core>

namespace upd::mrpt_bridge {

/// [PipelineParams] holds only `up`: the pipeline's parts have their own sections.
struct UpKey {
  Eigen::Vector3f& up;
  void validate() const {}
  template <class V>
  void visit(V& v) {
    v("up", up, "gravity-up direction x,y,z in the cloud frame (any length)");
  }
};

/// Where one loader keeps the parts of the robot config; a null part is not read by it.
struct RobotConfigParts {
  core::PipelineParams* pipeline = nullptr;  ///< [PipelineParams] `up` .. [ClassifyParams]
  core::BaselineParams* baseline = nullptr;
  SourceParams* source = nullptr;  ///< [SourceParams] and its [StereoMatchParams]
  maps::GridParams* grid = nullptr;
  maps::FusionParams* fusion = nullptr;
  maps::OctreeParams* octree = nullptr;
  GroundTruthParams* ground_truth = nullptr;
  SimulationParams* simulation = nullptr;
};

/// Calls f(section_name, description, params) for every non-null part's sections, in
/// documentation order.
template <class F>
void forEachRobotSection(const RobotConfigParts& c, F&& f) {
  if (c.pipeline != nullptr) {
    UpKey up{c.pipeline->up};
    f("PipelineParams", "Frames of the UPD pipeline.", up);
    f("PreprocessParams",
      "Pre-processing (paper section 3): range cut-off, voxel down-sampling, outlier removal.",
      c.pipeline->preprocess);
    f("NormalParams", "PCA normals (paper eqs. 4-5).", c.pipeline->normals);
    f("UpdParams", "The Unevenness Point Descriptor (paper eqs. 6-8).", c.pipeline->upd);
    f("ClassifyParams", "Traversability labels and cost from the UPD.", c.pipeline->classify);
  }
  if (c.baseline != nullptr) {
    f("BaselineParams", "The paper's baselines (roughness and inclination index).", *c.baseline);
  }
  if (c.source != nullptr) {
    f("SourceParams", "How MRPT observations become clouds (LiDAR ranges, stereo calibration).",
      *c.source);
    f("StereoMatchParams", "OpenCV StereoSGBM disparity for CObservationStereoImages.",
      c.source->stereo);
  }
  if (c.grid != nullptr) {
    f("GridParams", "The 2.5D traversability grid (a window that follows the robot).", *c.grid);
  }
  if (c.fusion != nullptr) {
    f("FusionParams", "Log-odds fusion of per-point evidence into cells and voxels.", *c.fusion);
  }
  if (c.octree != nullptr) f("OctreeParams", "The OctoMap traversability tree.", *c.octree);
  if (c.ground_truth != nullptr) {
    f("GroundTruthParams", "Ground-truth pose files (TUM) given to `upd playback --poses`.",
      *c.ground_truth);
  }
  if (c.simulation != nullptr) {
    f("SimulationParams", "The simulated Dune of `upd simulate`.", *c.simulation);
    f("RobotBodyParams", "The simulated robot's body (`upd simulate`; `upd navigate` reads it "
      "from the navigation config).", c.simulation->body);
    f("CameraMountParams", "The simulated robot's depth camera (`upd simulate`; `upd navigate` "
      "reads it from the navigation config).", c.simulation->camera);
  }
}

/// Reads the non-null parts from ini (absent sections and keys keep their defaults), validating
/// each section. Does not check for unknown sections or keys: the caller does, once everything
/// the file may hold is read.
inline void readRobotConfig(IniReader& ini, const RobotConfigParts& parts) {
  forEachRobotSection(parts,
                      [&](const char* name, const char*, auto& params) { ini.read(name, params); });
  if (parts.pipeline != nullptr) readClassifier(ini, *parts.pipeline);
}

}  // namespace upd::mrpt_bridge
