// Writes the fuzzers' generated seed corpora: small valid files of every cloud format (the
// samples of the bad-input catalogue), for the pipeline the generated scenes at a coarse
// spacing as raw floats, and for the rawlog reader a stream of the actions the recorded
// rawlogs lack (scan matching with each pose distribution). scripts/fuzz.sh adds the seeds
// taken from ../shared/data.
//   fuzz_seeds OUTDIR   ->  OUTDIR/{pcd,ply,xyz,kitti_bin,pipeline,rawlog}/...
#include "io/cloud_samples.h"

#include "upd/sim/scenes.h"

#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/poses/CPosePDFGaussianInf.h>
#include <mrpt/poses/CPosePDFGrid.h>
#include <mrpt/poses/CPosePDFParticles.h>
#include <mrpt/poses/CPosePDFSOG.h>
#include <mrpt/serialization/CArchive.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

namespace fs = std::filesystem;
namespace samples = upd::test::samples;

namespace {

void put(const fs::path& dir, const std::string& name, const std::string& bytes) {
  fs::create_directories(dir);
  std::ofstream(dir / name, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// The pipeline fuzzer's input: a flags byte, then x, y, z floats.
std::string floats(const std::vector<samples::Xyz>& p, char flags) {
  std::string s(1, flags);
  for (const auto& q : p) {
    samples::putLe(s, q.x);
    samples::putLe(s, q.y);
    samples::putLe(s, q.z);
  }
  return s;
}

// A plain rawlog object stream: an observation, then a collection of an odometry action and a
// scan-matching action with each CPosePDF class, then an observation.
void putActionsRawlog(const fs::path& dir) {
  using mrpt::obs::CActionRobotMovement2D;
  fs::create_directories(dir);
  mrpt::obs::CActionCollection acts;
  CActionRobotMovement2D odometry;
  odometry.computeFromOdometry(mrpt::poses::CPose2D(0.3, 0.0, 0.05),
                               CActionRobotMovement2D::TMotionModelOptions());
  acts.insert(odometry);
  const mrpt::poses::CPosePDF::Ptr pdfs[] = {
      mrpt::poses::CPosePDFGaussian::Create(mrpt::poses::CPose2D(0.3, 0.1, 0.02)),
      mrpt::poses::CPosePDFGaussianInf::Create(mrpt::poses::CPose2D(0.3, 0.1, 0.02)),
      mrpt::poses::CPosePDFParticles::Create(4),
      mrpt::poses::CPosePDFSOG::Create(2),
      mrpt::poses::CPosePDFGrid::Create(-0.5, 0.5, -0.5, 0.5, 0.5, M_PI / 2, -M_PI, M_PI),
  };
  for (const auto& pdf : pdfs) {
    CActionRobotMovement2D matched;
    matched.estimationMethod = CActionRobotMovement2D::emScan2DMatching;
    matched.poseChange = mrpt::containers::deepcopy_poly_ptr<mrpt::poses::CPosePDF::Ptr>(pdf);
    acts.insert(matched);
  }
  mrpt::io::CFileOutputStream out((dir / "actions.rawlog").string());
  auto ar = mrpt::serialization::archiveFrom(out);
  mrpt::obs::CObservationComment first, last;
  first.text = "before";
  last.text = "after";
  ar << first << acts << last;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_seeds OUTDIR\n");
    return 2;
  }
  const fs::path out = argv[1];
  const auto small = samples::grid(4);
  const auto big = samples::grid(12);
  put(out / "pcd", "ascii.pcd", samples::pcdAscii(small));
  put(out / "pcd", "binary.pcd", samples::pcdBinary(small));
  put(out / "pcd", "binary_compressed.pcd", samples::pcdBinaryCompressed(big));
  put(out / "ply", "ascii.ply", samples::plyAscii(small));
  put(out / "ply", "le.ply", samples::plyBinary(small, false));
  put(out / "ply", "be.ply", samples::plyBinary(small, true));
  put(out / "xyz", "grid.xyz", samples::xyzText(small));
  put(out / "xyz", "colour.xyz", "x,y,z,r,g,b\n0 0 0 255 0 0\n1,0,0,0,255,0\n0 1 0 0 0 255 # c\n");
  put(out / "kitti_bin", "grid.bin", samples::kittiBin(small));

  auto nan_grid = big;
  for (std::size_t i = 0; i < nan_grid.size(); i += 3) nan_grid[i].z = std::numeric_limits<float>::quiet_NaN();
  for (char flags : {0, 1, 2, 3}) {
    put(out / "pipeline", "grid_" + std::to_string(int(flags)), floats(big, flags));
  }
  put(out / "pipeline", "grid_nan", floats(nan_grid, 0));
  upd::sim::SceneParams coarse;
  coarse.spacing_m = 0.05;
  for (const std::string& name : upd::sim::sceneNames()) {
    const upd::sim::Scene scene = upd::sim::makeScene(name, coarse);
    std::vector<samples::Xyz> p;
    for (std::size_t i = 0; i < scene.cloud.size() && p.size() < 4096; ++i) {
      p.push_back({scene.cloud.x[i], scene.cloud.y[i], scene.cloud.z[i]});
    }
    put(out / "pipeline", "scene_" + name, floats(p, 0));
  }
  putActionsRawlog(out / "rawlog");
  return 0;
}
