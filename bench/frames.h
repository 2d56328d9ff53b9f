// The benchmark's inputs and how a frame is timed: the Kinect frames (two real PCD files and a
// generated depth image), the frame loop (depth image -> cloud -> runPipeline -> map update,
// its buffers kept from frame to frame, as a sensor loop does) and the medians over its runs.
#pragma once

#include <Eigen/Geometry>
#include <functional>
#include <optional>
#include <string>
#include <utility>

#include "report.h"
#include "upd/core/camera.h"
#include "upd/core/pipeline.h"
#include "upd/core/point_cloud.h"

namespace upd::bench {

struct Frame {
  std::string name, source;
  bool available = false;
  std::string skip_reason;
  core::PointCloud cloud;                 // organized, camera frame
  std::optional<core::DepthImage> depth;  // the generated frame starts from its depth image
  core::CameraIntrinsics intrinsics;
  Eigen::Vector3f up = Eigen::Vector3f::UnitZ();
  Eigen::Isometry3f pose_world_cloud = Eigen::Isometry3f::Identity();
};

/// The path of rel under --data, when that file exists.
std::optional<std::string> dataFile(const Options& o, const std::string& rel);

/// An organized PCD frame; not available (with the reason) when the file is missing.
Frame pcdFrame(const Options& o, const std::string& name, const std::string& rel,
               const Eigen::Vector3f& up);

/// makeWorld("mixed") rendered by a simulated Kinect.
Frame generatedFrame();

/// The frame as the pipeline takes it: its depth image converted, or its organized cloud.
core::PointCloud inputCloud(const Frame& f);

/// The three Kinect frames of the report, in its order, then the user's (Options::frames).
std::vector<Frame> kinectFrames(const Options& o);

/// A frame of the user's: an organized cloud (.pcd, .ply) or a 16-bit depth PNG (with
/// o.intrinsics, else the Kinect's at the image's size, and o.depth_scale). Throws
/// std::runtime_error naming the file when it cannot be read or is not organized.
Frame userFrame(const Options& o, const std::string& path);

/// Whether a frame's file is read as a depth image (a .png, in any case).
bool isDepthPng(const std::string& path);

/// What the map-update stage of the frame loop does (it depends on whether libs/maps is built).
const char* mapStageKind();

struct FrameTiming {
  double total_ms = kNaN;
  json stages;
  std::size_t scored = 0, points = 0;
};

/// repeats frames after a warm-up frame, at the current thread count (pinned to one CPU when
/// that is 1); the last frame's result into *last when given.
FrameTiming timeFramePipeline(const Frame& f, const core::PipelineParams& params, int repeats,
                              core::PipelineResult* last = nullptr);

/// Frames on one core and on two in turn, a block of each at a time: a frame to warm up, then
/// kTimedInBlock timed ones (one(record) and two(record) run a frame and keep its time when
/// record), until repeats of each are timed. On a shared machine whose speed drifts both
/// medians then see the same conditions, and their ratio is the second core's gain. A block,
/// not a single frame: each thread keeps its share of the buffers in its own core's cache from
/// frame to frame, as a sensor loop at one team size does, and a two-core frame right after a
/// one-core one finds them in the other core's (office1's paper frame 0.3-0.5 ms longer). The
/// one-core frames are pinned to the CPU they start on (PinnedToThisCpu). With a probe, it is
/// sampled before each pair of blocks (the machine's own second core then).
constexpr int kTimedInBlock = 3;
void oneAndTwoCoresInBlocks(int repeats, CoreProbe* probe, const std::function<void(bool)>& one,
                            const std::function<void(bool)>& two);

/// The frame pipeline on one core and on two (oneAndTwoCoresInBlocks).
std::pair<FrameTiming, FrameTiming> timeOneAndTwoCores(const Frame& f, const core::PipelineParams& params,
                                                       int repeats,
                                                       core::PipelineResult* last = nullptr,
                                                       CoreProbe* probe = nullptr);

/// Median time of f over repeats runs after one warm-up run [ms].
double timeMedian(const std::function<void()>& f, int repeats);

}  // namespace upd::bench
