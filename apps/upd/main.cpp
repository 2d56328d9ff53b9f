// upd: the UPD-Nav command-line tool. Subcommands are listed in kCommands; errors from any of
// them are caught here and printed as one line, with a non-zero exit code.
#include "cli.h"
#include "commands.h"
#include "upd/core/version.h"
#include "upd/nav/viewer.h"

#include <Eigen/Core>
#include <mrpt/system/os.h>

#include <malloc.h>

#include <cstring>
#include <iostream>

// The optional parts: defined as 1 by CMake where built (apps/upd/CMakeLists.txt), 0 here else.
#ifndef UPD_HAVE_OPENNI2
#define UPD_HAVE_OPENNI2 0
#endif
#ifndef UPD_HAVE_FREENECT
#define UPD_HAVE_FREENECT 0
#endif
#ifndef UPD_HAVE_ROS1
#define UPD_HAVE_ROS1 0
#endif
#ifndef UPD_HAVE_LEARN
#define UPD_HAVE_LEARN 0
#endif

namespace {

using upd::app::Command;

const char* const kBuilt[] = {"no", "yes"};  // by UPD_HAVE_*

const Command kCommands[] = {
    {"analyze", "score a point cloud (.pcd, .ply, .xyz, KITTI .bin) or a depth PNG with the UPD",
     upd::app::kAnalyzeUsage, upd::app::runAnalyze},
    {"scene", "write a generated test scene (the paper's experiments) as PLY",
     upd::app::kSceneUsage, upd::app::runScene},
    {"simulate", "record a simulated robot run through a generated world as a rawlog",
     upd::app::kSimulateUsage, upd::app::runSimulate},
    {"playback", "replay a rawlog: UPD per frame, fused traversability maps, exports",
     upd::app::kPlaybackUsage, upd::app::runPlayback},
    {"navigate", "drive a simulated robot to a goal on UPD traversability (closed loop)",
     upd::app::kNavigateUsage, upd::app::runNavigate},
    {"bench-nav", "navigation benchmark: the closed loop on generated worlds, against the optimum",
     upd::app::kBenchNavUsage, upd::app::runBenchNav},
    {"live", "UPD, map and navigation on a live OpenNI2 depth camera (or an .oni file)",
     upd::app::kLiveUsage, upd::app::runLive},
    {"map", "map folders: info, merge runs of one site, crop a region",
     upd::app::kMapUsage, upd::app::runMap},
    {"calibrate-mount", "measure the camera's height, pitch and roll from the floor it sees",
     upd::app::kCalibrateMountUsage, upd::app::runCalibrateMount},
    {"ros", "ROS 1 node: depth/cloud topics in, map, cloud and route out, goals driven",
     upd::app::kRosUsage, upd::app::runRos},
    {"render", "draw a scored cloud to a PNG, coloured by zeta (or label, cost, ...)",
     upd::app::kRenderUsage, upd::app::runRender},
    {"histogram", "plot the distribution of zeta at several d_m to a PNG",
     upd::app::kHistogramUsage, upd::app::runHistogram},
    {"baseline", "score a cloud with the paper's roughness index, beside the UPD (Fig. 5)",
     upd::app::kBaselineUsage, upd::app::runBaseline},
    {"view", "3D window on a scored cloud, an .ot tree or a playback folder (keys recolour)",
     upd::app::kViewUsage, upd::app::runView},
    {"evaluate", "score the UPD, its baselines and the classifier against labelled clouds",
     upd::app::kEvaluateUsage, upd::app::runEvaluate},
    {"train", "train the learned traversability classifier on labelled clouds",
     upd::app::kTrainUsage, upd::app::runTrain},
    {"params", "list every parameter with its ini section, default and unit",
     upd::app::kParamsUsage, upd::app::runParams},
};

// The release, the libraries it was built against and the optional parts built in: what a bug
// report needs.
void printVersion(std::ostream& os) {
  os << "upd (UPD-Nav) " << upd::core::version() << "\n"
     << "built with Eigen " << EIGEN_WORLD_VERSION << "." << EIGEN_MAJOR_VERSION << "."
     << EIGEN_MINOR_VERSION << ", " << mrpt::system::MRPT_getVersion() << "\n"
     << "optional parts: OpenNI2 " << kBuilt[UPD_HAVE_OPENNI2] << ", libfreenect "
     << kBuilt[UPD_HAVE_FREENECT] << ", ROS 1 " << kBuilt[UPD_HAVE_ROS1] << ", learned classifier "
     << kBuilt[UPD_HAVE_LEARN] << "\n";
}

void printHelp(std::ostream& os) {
  os << "upd: terrain traversability with the Unevenness Point Descriptor (UPD-Nav)\n\n"
        "usage: upd COMMAND [ARGS...]   (upd COMMAND --help for its options; upd --version)\n\n"
        "commands:\n";
  for (const auto& c : kCommands) os << "  " << c.name << std::string(17 - std::strlen(c.name), ' ') << c.summary << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  // A frame loop frees and allocates buffers of a few MB per frame. By default glibc serves
  // such blocks with fresh pages from the kernel every time (mmap, or a heap trimmed after
  // each free), and the page faults and zeroing cost more than the UPD itself (playback of
  // 640 x 480 frames: 18-30 ms per stage instead of 4-9). Keep them in the heap for reuse.
  mallopt(M_MMAP_THRESHOLD, 256 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") ||
      !std::strcmp(argv[1], "help")) {
    printHelp(std::cout);
    return argc < 2 ? 2 : 0;
  }
  if (!std::strcmp(argv[1], "--version") || !std::strcmp(argv[1], "version")) {
    printVersion(std::cout);
    return 0;
  }
  upd::app::registerClassifierLoader();
  const std::string name = argv[1];
  const std::vector<std::string> args(argv + 2, argv + argc);
  for (const auto& c : kCommands) {
    if (name != c.name) continue;
    for (const auto& a : args) {
      if (a == "--help" || a == "-h") {
        std::cout << c.usage;
        return 0;
      }
    }
    try {
      const int code = c.run(args);
      upd::nav::exitIfViewerShown(code);  // after a 3D window: no static destructors (viewer.h)
      return code;
    } catch (const upd::app::UsageError& e) {
      std::cerr << "upd " << name << ": " << e.what() << " (see 'upd " << name << " --help')\n";
      return 2;
    } catch (const std::exception& e) {
      std::cerr << "upd " << name << ": error: " << e.what() << "\n";
      upd::nav::exitIfViewerShown(1);
      return 1;
    }
  }
  std::cerr << "upd: unknown command '" << name << "' (see 'upd --help')\n";
  return 2;
}
