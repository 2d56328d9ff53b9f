// upd_bench: the fast paths (fast_normals.h, fast_upd.h) timed against the exact path and the
// PCL pipeline of the paper, on real and generated data, with the performance targets of
// docs/PERFORMANCE.md.
//
// Usage: upd_bench [--data DIR] [--json OUT.json] [--quick] [--frames-only] [--only TABLE]
//                  [--repeats N] [--frame FILE]... [--intrinsics F.yaml] [--depth-scale M]
//                  [--up X,Y,Z]
//   --data DIR   the shared real data (default: the build's UPD_SHARED_DATA_DIR); a missing
//                file makes its case "skipped" in the report, never a failure
//   --json OUT   also write the report as JSON (the same numbers as the printed tables)
//   --quick      skip the PCL peer and use fewer exact samples (minutes instead of ~15)
//   --frames-only  only the frame pipeline timings (one core, two cores, memory): seconds
//   --repeats N  timed runs per case for the medians (default 15; big clouds use fewer)
//   --only paper | sensor-rate | octree   that table alone: the paper's whole pipeline against
//                PCL's, the sensor-rate path against PCL's integral-image normals, or the
//                OctoMap update against OctoMap's own insert
//   --frame FILE a frame of one's own, after the report's three in every frame table (the
//                frame pipeline, the paper's pipeline, the sensor-rate path, ...) with its
//                targets: an organized .pcd or .ply (a camera's image, NaN pixels kept) or a
//                16-bit depth .png (--intrinsics F.yaml, an OpenCV or ROS calibration, else
//                the Kinect's focal length of 525 px at the image's centre; --depth-scale M
//                metres a unit, default 0.001: 0.0002 for TUM RGB-D); --up X,Y,Z is gravity-up
//                in its camera frame (default: the calibration's local_transform where it has
//                one, else 0,-1,0, a level camera's optical frame)
//
// What is timed, per case (medians over the runs after one warm-up run):
//  - frame pipeline (organized 640 x 480): depth image (or organized cloud) -> normals -> UPD
//    -> labels -> map update, every pixel scored, on one core and on two (frame_cases.cpp);
//  - PCL settings: voxel 0.02 m, normals 0.05 m, d_m 0.5 m on both sides: our fast path, our
//    exact path and the PCL peer (run once: it takes seconds) (peer_cases.cpp);
//  - normals alone: computeNormalsOrganized against PCL's IntegralImageNormalEstimation;
//  - the OctoMap update of `upd playback` against OctoMap's own insert (octree_cases.cpp);
//  - the LiDAR scan, the corner, and generated clouds of growing size and growing d_m.
// Agreement with the exact path is measured on the same pre-processed cloud: exact normals for
// every point and the exact UPD for every point or, where that would take minutes, for an evenly
// spaced sample of points (the sample size is printed; agreement.cpp). The program exits 0
// whether or not the targets are met: the report says which are.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "cases.h"
#include "cli_args.h"
#include "frames.h"
#include "report.h"

namespace core = upd::core;

namespace upd::bench {
namespace {

// The user's frames (--frame) as read: what each starts from, its size and its up, printed and
// as JSON (a wrong up or scale shows here before the tables).
json describeYourFrames(const std::vector<Frame>& frames, const Options& o) {
  json all = json::array();
  for (std::size_t i = frames.size() - o.frames.size(); i < frames.size(); ++i) {
    const Frame& f = frames[i];
    const char* kind = f.depth ? "depth image" : "organized cloud";
    std::printf("your frame %s: %s, %s of %zu x %zu, up %.3f,%.3f,%.3f\n", f.name.c_str(),
                f.source.c_str(), kind, f.cloud.width, f.cloud.height, f.up.x(), f.up.y(),
                f.up.z());
    all.push_back({{"name", f.name},
                   {"source", f.source},
                   {"starts_from", kind},
                   {"width", f.cloud.width},
                   {"height", f.cloud.height},
                   {"up", {f.up.x(), f.up.y(), f.up.z()}}});
  }
  return all;
}

int run(const Options& o) {
  Report report;
  json& root = report.root;
  std::printf("upd_bench: data from %s%s\n", o.data_dir.c_str(), o.quick ? " (--quick)" : "");
  const double bandwidth = copyBandwidthGBs();
  describeMachine(report, bandwidth);
  root["map_stage"] = mapStageKind();

  const std::vector<Frame> frames = kinectFrames(o);
  root["your_frames"] = describeYourFrames(frames, o);
  if (o.only == "paper") root["paper_pipeline"] = paperPipelineCases(frames, o, report);
  if (o.only == "sensor-rate") root["sensor_rate"] = sensorRateCases(frames, o, report);
  if (o.only == "octree") root["octree"] = octreeCases(frames, o);
  if (!o.only.empty()) return finish(report, o, bandwidth);
  std::vector<core::PipelineResult> frame_results;
  json frame_cases = frameTimingCases(frames, o, report, frame_results);
  if (o.frames_only) {
    root["frames"] = frame_cases;
    return finish(report, o, bandwidth);
  }
  frameAgreementCases(frames, frame_results, o, report, frame_cases);
  root["normals_alone"] = normalsAloneCases(frames, o);
  root["sensor_rate"] = sensorRateCases(frames, o, report);
  root["paper_pipeline"] = paperPipelineCases(frames, o, report);
  root["octree"] = octreeCases(frames, o);
  root["pcl_settings"] = pclSettingsCases(frames, o, report);
  root["growth_with_size"] = growthWithSizeCases(o, report);
  root["growth_with_radius"] = growthWithRadiusCases(frames[2], o, report);  // (the generated)
  root["frames"] = frame_cases;
  return finish(report, o, bandwidth);
}

// --up X,Y,Z into up: three numbers, not all 0.
void parseUp(const std::string& text, float up[3]) {
  std::size_t start = 0;
  for (int i = 0; i < 3; ++i) {
    const std::size_t comma = text.find(',', start);
    if ((i < 2) != (comma != std::string::npos)) {
      throw std::invalid_argument("--up " + text + ": three numbers X,Y,Z");
    }
    const std::string part = text.substr(start, comma - start);
    up[i] = static_cast<float>(number("--up " + text + " (" + part + ")", part));
    start = comma + 1;
  }
  if (up[0] == 0 && up[1] == 0 && up[2] == 0) {
    throw std::invalid_argument("--up " + text + ": the zero vector has no direction");
  }
}

// Fills o from the command line; false when --help was printed.
bool parseOptions(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--data") {
      o.data_dir = value();
    } else if (a == "--json") {
      o.json_path = value();
    } else if (a == "--quick") {
      o.quick = true;
    } else if (a == "--frames-only") {
      o.frames_only = true;
    } else if (a == "--only") {
      o.only = value();
      if (o.only != "paper" && o.only != "sensor-rate" && o.only != "octree") {
        throw std::invalid_argument("--only takes paper, sensor-rate or octree, not " + o.only);
      }
    } else if (a == "--repeats") {
      o.repeats = positiveCount(a, value());
    } else if (a == "--frame") {
      o.frames.push_back(value());
    } else if (a == "--intrinsics") {
      o.intrinsics = value();
    } else if (a == "--depth-scale") {
      const std::string v = value();
      o.depth_scale = number(a + " " + v, v);
      if (!(o.depth_scale > 0)) throw std::invalid_argument("--depth-scale must be > 0");
    } else if (a == "--up") {
      parseUp(value(), o.up);
      o.up_given = true;
    } else if (a == "--help" || a == "-h") {
      std::printf(
          "usage: upd_bench [--data DIR] [--json OUT.json] [--quick] [--frames-only] "
          "[--only paper|sensor-rate|octree] [--repeats N] [--frame FILE]... "
          "[--intrinsics F.yaml] [--depth-scale M] [--up X,Y,Z]\n");
      return false;
    } else {
      throw std::invalid_argument("unknown option " + a + " (see --help)");
    }
  }
  // (The calibration of a depth image: with none to apply it to, it would be left unread.)
  if (!o.intrinsics.empty() && std::none_of(o.frames.begin(), o.frames.end(), isDepthPng)) {
    throw std::invalid_argument("--intrinsics " + o.intrinsics +
                                ": a calibration for depth images, and no --frame is a .png");
  }
  return true;
}

}  // namespace
}  // namespace upd::bench

int main(int argc, char** argv) {
  try {
    upd::bench::Options o;
    if (!upd::bench::parseOptions(argc, argv, o)) return 0;
    return upd::bench::run(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "upd_bench: %s\n", e.what());
    return 1;
  }
}
