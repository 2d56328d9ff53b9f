// The report's tables, one function per table, in the order upd_bench prints them. Each prints
// its rows as it measures them, adds its targets to the report and returns its JSON cases.
#pragma once

#include <vector>

#include "frames.h"
#include "pcl_peer.h"
#include "report.h"
#include "upd/core/pipeline.h"

namespace upd::bench {

// ---- The frame pipeline (frame_cases.cpp) ----

/// The pipeline of the frame tables: no pre-processing (every pixel is scored), normals of
/// 0.05 m, the UPD at d_m.
core::PipelineParams frameParams(const Frame& f, double d_m);

/// Each frame on one core and on two, then the peak memory; results gets each frame's last
/// result (one core) for the agreement table.
json frameTimingCases(const std::vector<Frame>& frames, const Options& o, Report& report,
                      std::vector<core::PipelineResult>& results);

/// The frame pipeline's agreement with the exact path at full resolution, and what the
/// accuracy settings cost; stored into frame_cases[f]["agreement"] and ["accuracy_settings"].
void frameAgreementCases(const std::vector<Frame>& frames,
                         const std::vector<core::PipelineResult>& results, const Options& o,
                         Report& report, json& frame_cases);

/// computeNormalsOrganized against PCL's IntegralImageNormalEstimation.
json normalsAloneCases(const std::vector<Frame>& frames, const Options& o);

/// The generated frame's pipeline at d_m = 0.25, 0.5, 1 and 2 m.
json growthWithRadiusCases(const Frame& generated, const Options& o, Report& report);

// ---- The PCL peer's settings (peer_cases.cpp) ----

/// UpdParams::fast_exact_band at the PCL peer's settings.
constexpr double kExactBand = 0.02;

/// Our pipeline at the PCL peer's settings (voxel_m 0: no voxel grid).
core::PipelineParams pclSettings(const Eigen::Vector3f& up, double voxel_m, double normal_radius_m,
                           double d_m);

/// The peer's settings equal to p.
PeerSettings peerOf(const core::PipelineParams& p);

/// Neighbour visits the peer's UPD search would make: its cost, to decide whether to run it.
double peerCostEstimate(const core::PointCloud& cloud, const core::PipelineParams& p);

/// The Kinect frames voxelized, the LiDAR scan and the corner: ours fast, ours exact, PCL.
json pclSettingsCases(const std::vector<Frame>& frames, const Options& o, Report& report);

/// 1 to 16 tiles of the rocks scene at the PCL peer's settings.
json growthWithSizeCases(const Options& o, Report& report);

// ---- The pipelines as `upd` runs them (paper_cases.cpp) ----

/// The paper's pipeline (config/dune-kinect.ini's steps, normals 0.05 m): cut-off 0.4-5 m,
/// voxel 0.02 m, outlier filter k 16 at 2 sigma, normals 0.05 m, UPD d_m 0.5 m.
core::PipelineParams paperParams(const Eigen::Vector3f& up);

/// config/dune-kinect-realtime.ini's pipeline: the cut-off alone, every pixel scored.
core::PipelineParams sensorRateParams(const Eigen::Vector3f& up);

/// The paper's pipeline on each frame, ours (one core, two) against PCL's, stage by stage.
json paperPipelineCases(const std::vector<Frame>& frames, const Options& o, Report& report);

/// The sensor-rate path on each frame against PCL's IntegralImageNormalEstimation alone.
json sensorRateCases(const std::vector<Frame>& frames, const Options& o, Report& report);

// ---- The OctoMap update (octree_cases.cpp) ----

/// upd::maps::insertScan against OctoMap's own insert on each frame scored by the sensor-rate
/// path, into a new tree and as the fifth insert of the frame.
json octreeCases(const std::vector<Frame>& frames, const Options& o);

}  // namespace upd::bench
