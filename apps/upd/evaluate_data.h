// The labelled clouds `upd evaluate` and `upd train` read, one at a time:
//  - generated: the paper's scenes (upd::sim, exact truth) without and with 5 mm Gaussian
//    noise, and views of the simulated Kinect over the generated worlds (Terrain::truthAt of
//    each pixel's hit) without and with the Kinect noise model;
//  - real frames of the shared data (office, lab and table RGB-D frames) with geometric
//    labels: the floor plane by RANSAC, the rule of upd/core/floor_labels.h;
//  - the semantic-LiDAR layout of SemanticKITTI and RELLIS-3D: `NNNNNN.bin` scans with
//    `NNNNNN.label` files, mapped to traversability by a class map.
// Each cloud has a scene: the split of `upd train` is by scene (kHeldOutScenes), so a model is
// never scored on a scene it was trained on.
#pragma once

#include "upd/core/floor_labels.h"
#include "upd/core/point_cloud.h"

#include <Eigen/Core>

#include <functional>
#include <string>
#include <vector>

namespace upd::app {

struct LabelledCloud {
  std::string name;   ///< e.g. "scene ramp", "world mixed view 2", "pcl/office1.pcd"
  std::string group;  ///< the table it is scored in
  std::string scene;  ///< the unit of the train / test split
  bool held_out = true;  ///< in the test split of `upd train`
  /// One of the scenes the shipped classifier was trained on: `upd evaluate` skips it unless
  /// --all-scenes.
  bool trains_shipped_model = false;
  std::string config;    ///< the shipped config it is scored with: "dune-kinect.ini", "lidar.ini"
  core::PointCloud cloud;
  std::vector<core::Label> truth;  ///< one per point
  Eigen::Vector3f up = Eigen::Vector3f::UnitZ();  ///< unit, in the cloud's frame
};

struct DataOptions {
  bool generated = true;
  std::string shared_dir;  ///< real frames from here; "" for none
  std::vector<std::string> semantic_inputs;  ///< folders or .bin files
  std::string class_map;                     ///< required with semantic_inputs
  int max_scans = 20;                        ///< per semantic folder (evenly spaced)
  core::GeometricLabelParams geometric;
};

/// Calls visit for each labelled cloud in a fixed order; appends a line to notes for data
/// skipped (a missing file, a frame without floor) and a summary per source.
void forEachLabelledCloud(const DataOptions& options,
                          const std::function<void(LabelledCloud&)>& visit,
                          std::vector<std::string>& notes);

/// The shared data folder: $UPD_SHARED_DATA_DIR, else /work/shared/data or ../shared/data
/// when present; "" when none is.
std::string findSharedDataDir();

}  // namespace upd::app
