// Writes the fuzzers' generated seed corpora: small valid files of every cloud format (the
// samples of the bad-input catalogue), for the pipeline the generated scenes at a coarse
// spacing as raw floats, and for the rawlog reader what the recorded rawlogs lack: a stream of
// actions (scan matching with each pose distribution, a 3D movement) and one of the other
// sensors a robot records beside its depth camera (IMU, odometry, GNSS, point clouds, range
// finders, JPEG camera images, a 360-degree RGB-D rig); with ROS 1, small bags (uncompressed,
// BZ2 and LZ4 chunks) of depth frames and point clouds with their transforms; for the depth
// files a small 16-bit depth PNG and calibrations as ROS and RTAB-Map write them; with the
// learned classifier, small models of each kind.
// scripts/fuzz.sh adds the seeds taken from ../shared/data.
//   fuzz_seeds OUTDIR   ->  OUTDIR/{pcd,ply,xyz,kitti_bin,pipeline,rawlog,bag,depth_png,
//                                   calibration,classifier}/...
#include "io/cloud_samples.h"

#include "upd/io/cloud_io.h"
#include "upd/mrpt_bridge/depth_files.h"
#include "upd/sim/scenes.h"

#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/img/CImage.h>
#include <mrpt/maps/CColouredPointsMap.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CActionRobotMovement3D.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationBatteryState.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRGBD360.h>
#include <mrpt/obs/CObservationRange.h>
#include <mrpt/obs/CObservationRotatingScan.h>
#include <mrpt/obs/CObservationVelodyneScan.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/poses/CPosePDFGaussianInf.h>
#include <mrpt/poses/CPosePDFGrid.h>
#include <mrpt/poses/CPosePDFParticles.h>
#include <mrpt/poses/CPosePDFSOG.h>
#include <mrpt/serialization/CArchive.h>

#ifdef UPD_FUZZ_HAVE_ROS1
#include "ros/small_bag.h"
#endif
#ifdef UPD_FUZZ_HAVE_LEARN
#include "upd/learn/classifier.h"
#endif

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

// A 16 x 12 depth PNG (a ramp with invalid pixels), and calibrations: a ROS camera_info YAML,
// and an OpenCV (RTAB-Map) one with distortion and a local_transform.
void putDepthFiles(const fs::path& dir, const fs::path& yaml_dir) {
  fs::create_directories(dir);
  upd::core::DepthImage d;
  d.width = 16, d.height = 12;
  d.depth_m.resize(16 * 12);
  for (std::size_t i = 0; i < d.depth_m.size(); ++i) {
    d.depth_m[i] = i % 7 == 0 ? 0.f : 0.5f + 0.01f * static_cast<float>(i);
  }
  upd::mrpt_bridge::writeDepthPng((dir / "ramp.png").string(), d);
  put(yaml_dir, "ros.yaml",
      "image_width: 16\nimage_height: 12\ncamera_name: depth\ncamera_matrix:\n  rows: 3\n"
      "  cols: 3\n  data: [13.1, 0, 7.5, 0, 13.1, 5.5, 0, 0, 1]\ndistortion_model: plumb_bob\n"
      "distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [0, 0, 0, 0, 0]\n");
  put(yaml_dir, "rtabmap.yaml",
      "%YAML:1.0\n---\ncamera_name: depth\nimage_width: 16\nimage_height: 12\n"
      "camera_matrix:\n   rows: 3\n   cols: 3\n"
      "   data: [ 13.1, 0., 7.5, 0., 13.1, 5.5, 0., 0., 1. ]\n"
      "distortion_coefficients:\n   rows: 1\n   cols: 5\n   data: [ 0.1, -0.2, 0., 0., 0. ]\n"
      "local_transform:\n   rows: 3\n   cols: 4\n"
      "   data: [ 0., 0., 1., 0.1, -1., 0., 0., 0., 0., -1., 0., 0.4 ]\n");
}

// A scored PLY of the points (writeScoredPly's file), for readScoredPly.
void putScoredPly(const fs::path& dir, const std::vector<samples::Xyz>& p) {
  fs::create_directories(dir);
  std::vector<float> x, y, z, n(p.size(), 0.5f);
  std::vector<upd::core::Label> label(p.size(), upd::core::Label::NonTraversable);
  for (const auto& q : p) {
    x.push_back(q.x);
    y.push_back(q.y);
    z.push_back(q.z);
  }
  upd::io::ScoredPoints s;
  s.x = x;
  s.y = y;
  s.z = z;
  s.nx = s.ny = s.nz = s.rx = s.ry = s.rz = s.zeta = s.cost = n;
  s.label = label;
  upd::io::writeScoredPly((dir / "scored.ply").string(), s);
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
  mrpt::obs::CActionRobotMovement3D moved;
  moved.poseChange.mean = mrpt::poses::CPose3D(0.3, 0.0, 0.01, 0.05, 0.0, 0.0);
  acts.insert(moved);
  mrpt::io::CFileOutputStream out((dir / "actions.rawlog").string());
  auto ar = mrpt::serialization::archiveFrom(out);
  mrpt::obs::CObservationComment first, last;
  first.text = "before";
  last.text = "after";
  ar << first << acts << last;
}

// A small JPEG image of w x h pixels with a gradient (MRPT compresses colour images as JPEG).
mrpt::img::CImage gradient(int w, int h) {
  mrpt::img::CImage im(w, h, mrpt::img::CH_RGB);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      im.setPixel(x, y, mrpt::img::TColor(static_cast<std::uint8_t>(8 * x),
                                          static_cast<std::uint8_t>(8 * y), 90));
    }
  }
  return im;
}

// A plain rawlog object stream of the other sensors a robot records: a frame of an IMU, wheel
// odometry, a GNSS reading (GGA and RMC fixes, a Novatel frame kept whole, Topcon satellites,
// empty Novatel ranges), two point clouds (plain and coloured), a range finder, a JPEG camera
// image, a small 3D scan with a JPEG intensity image and pixel labels, a Velodyne scan, a rotating
// LiDAR's range images and a battery state; then the same bare.
void putSensorsRawlog(const fs::path& dir) {
  mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(false);
  auto imu = mrpt::obs::CObservationIMU::Create();
  imu->set(mrpt::obs::IMU_X_ACC, 0.1);
  imu->set(mrpt::obs::IMU_Z_ACC, 9.8);
  imu->set(mrpt::obs::IMU_WZ, 0.02);
  auto odometry = mrpt::obs::CObservationOdometry::Create();
  odometry->odometry = mrpt::poses::CPose2D(1.0, 0.2, 0.1);
  odometry->hasEncodersInfo = true;
  odometry->encoderLeftTicks = 120;
  odometry->encoderRightTicks = 118;
  auto gps = mrpt::obs::CObservationGPS::Create();
  mrpt::obs::gnss::Message_NMEA_GGA gga;
  gga.fields.latitude_degrees = 36.7;
  gga.fields.longitude_degrees = -4.4;
  gga.fields.fix_quality = 1;
  gga.fields.satellitesUsed = 8;
  gps->setMsg(gga);
  mrpt::obs::gnss::Message_NMEA_RMC rmc;
  rmc.fields.latitude_degrees = 36.7;
  rmc.fields.longitude_degrees = -4.4;
  gps->setMsg(rmc);
  {
    namespace gnss = mrpt::obs::gnss;
    auto* frame_msg = new gnss::Message_NV_OEM6_GENERIC_FRAME();
    frame_msg->msg_body = {0x11, 0x22, 0x33, 0x44};
    gps->messages[gnss::NV_OEM6_GENERIC_FRAME] = gnss::gnss_message_ptr(frame_msg);
    auto* sats = new gnss::Message_TOPCON_SATS();
    sats->USIs = {3, 7, 9};
    sats->ELs = {40, 50, 60};
    sats->AZs = {20, 120, 300};
    gps->messages[gnss::TOPCON_SATS] = gnss::gnss_message_ptr(sats);
    // (RANGECMP is left empty: MRPT packs it to 1-byte alignment, its list included, and UBSan
    // reports any call on that list from an instrumented build.)
    gps->messages[gnss::NV_OEM6_RANGECMP] =
        gnss::gnss_message_ptr(new gnss::Message_NV_OEM6_RANGECMP());
  }
  auto plain = mrpt::obs::CObservationPointCloud::Create();
  auto points = mrpt::maps::CSimplePointsMap::Create();
  auto coloured = mrpt::maps::CColouredPointsMap::Create();
  for (int i = 0; i < 40; ++i) {
    points->insertPoint(0.1f * i, 0.05f * i, 0.0f);
    coloured->insertPointRGB(0.1f * i, 0.0f, 0.02f * i, 0.5f, 0.4f, 0.3f);
  }
  plain->pointcloud = points;
  auto colour = mrpt::obs::CObservationPointCloud::Create();
  colour->pointcloud = coloured;
  auto range = mrpt::obs::CObservationRange::Create();
  for (int i = 0; i < 3; ++i) {
    mrpt::obs::CObservationRange::TMeasurement m;
    m.sensorID = static_cast<uint16_t>(i);
    m.sensedDistance = 0.5f + 0.25f * i;
    range->sensedData.push_back(m);
  }
  auto camera = mrpt::obs::CObservationImage::Create();
  camera->image = gradient(32, 24);
  auto depth = mrpt::obs::CObservation3DRangeScan::Create();
  depth->hasRangeImage = true;
  depth->rangeImage_setSize(24, 32);
  depth->rangeImage.fill(1000);
  depth->hasIntensityImage = true;
  depth->intensityImage = gradient(32, 24);
  auto* labels = new mrpt::obs::TPixelLabelInfo<1>();
  labels->setSize(24, 32);
  labels->setLabelName(0, "ground");
  labels->setLabelName(3, "rock");
  depth->pixelLabels = mrpt::obs::TPixelLabelInfoBase::Ptr(labels);
  depth->cameraParams.ncols = depth->cameraParamsIntensity.ncols = 32;
  depth->cameraParams.nrows = depth->cameraParamsIntensity.nrows = 24;
  auto lidar = mrpt::obs::CObservationVelodyneScan::Create();
  lidar->scan_packets.resize(1);
  lidar->calibration.laser_corrections.resize(16);
  for (int i = 0; i < 4; ++i) {
    lidar->point_cloud.x.push_back(2.0f + i);
    lidar->point_cloud.y.push_back(0.5f);
    lidar->point_cloud.z.push_back(-0.4f);
    lidar->point_cloud.intensity.push_back(90);
    lidar->point_cloud.timestamp.push_back(mrpt::Clock::fromDouble(10.0 + 0.01 * i));
    lidar->point_cloud.azimuth.push_back(0.2f * i);
    lidar->point_cloud.laser_id.push_back(static_cast<int16_t>(i));
  }
  lidar->point_cloud.pointsForLaserID = {{0, 1}, {2, 3}};
  auto rotating = mrpt::obs::CObservationRotatingScan::Create();
  rotating->rowCount = 4;
  rotating->columnCount = 6;
  rotating->rangeImage.setConstant(4, 6, 1500);
  rotating->intensityImage.setConstant(4, 6, 80);
  rotating->rangeOtherLayers["STRONGEST"].setConstant(4, 6, 1400);
  auto battery = mrpt::obs::CObservationBatteryState::Create();
  battery->voltageMainRobotBattery = 24.1;
  battery->voltageOtherBatteries.resize(2);
  battery->voltageOtherBatteries[0] = 12.0;
  battery->voltageOtherBatteries[1] = 12.1;
  battery->voltageOtherBatteriesValid.assign(2, true);
  auto rig = mrpt::obs::CObservationRGBD360::Create();
  rig->hasRangeImage = rig->hasIntensityImage = true;
  for (auto& r : rig->rangeImages) r.setConstant(6, 8, 1200);
  for (auto& image : rig->intensityImages) image = gradient(8, 6);
  const mrpt::obs::CObservation::Ptr all[] = {imu,    odometry, gps,   plain,    colour,  range,
                                              camera, depth,    lidar, rotating, battery, rig};
  mrpt::obs::CSensoryFrame frame;
  for (const auto& o : all) frame.insert(o);
  mrpt::io::CFileOutputStream out((dir / "sensors.rawlog").string());
  auto ar = mrpt::serialization::archiveFrom(out);
  ar << frame;
  for (const auto& o : all) ar << *o;
}


#ifdef UPD_FUZZ_HAVE_LEARN
// A small model of each kind as YAML (random trees of 2 trees of depth 3; boosting; SVM).
void putModels(const fs::path& dir) {
  const int n = 200, width = upd::core::kFeatureCount;
  std::vector<float> f(static_cast<std::size_t>(n * width));
  std::vector<upd::core::Label> t(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < width; ++j) {
      f[i * width + j] = static_cast<float>((i * 7 + j * 13) % 29) / 29.f;
    }
    t[i] = f[i * width] < 0.5f ? upd::core::Label::NonTraversable : upd::core::Label::Traversable;
  }
  fs::create_directories(dir);
  for (const auto kind : {upd::learn::ModelKind::RandomTrees, upd::learn::ModelKind::Boost,
                          upd::learn::ModelKind::Svm}) {
    upd::learn::TrainParams p;
    p.kind = kind;
    p.trees = 2;
    p.max_depth = 3;
    const fs::path file = dir / (std::string(upd::learn::toString(kind)) + ".yml");
    upd::learn::PointClassifier::train(f, t, upd::core::FeatureParams{}, p)->save(file.string());
  }
}
#endif

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
  putScoredPly(out / "ply", small);
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
  putDepthFiles(out / "depth_png", out / "calibration");
  putActionsRawlog(out / "rawlog");
  putSensorsRawlog(out / "rawlog");
#ifdef UPD_FUZZ_HAVE_ROS1
  // Two 16 x 12 depth frames and point clouds in chunks of about 1 kB, in each compression.
  fs::create_directories(out / "bag");
  upd::test::SmallBag bag;
  bag.width = 16;
  bag.height = 12;
  bag.frames = 2;
  bag.chunk_bytes = 1000;
  bag.with_points = true;
  for (const auto& [name, compression] :
       {std::pair{"none.bag", rosbag::compression::Uncompressed},
        std::pair{"bz2.bag", rosbag::compression::BZ2}, std::pair{"lz4.bag", rosbag::compression::LZ4}}) {
    bag.compression = compression;
    upd::test::writeSmallBag((out / "bag" / name).string(), bag);
  }
  // Compressed depth images alone (the format's index, then the data), and the same frames as
  // compressed depth images in bags (image_transport's compressedDepth), each codec.
  fs::create_directories(out / "compressed_depth");
  upd::core::DepthImage depth;
  depth.width = 16;
  depth.height = 12;
  for (int i = 0; i < 16 * 12; ++i) depth.depth_m.push_back(i % 11 == 0 ? 0.f : 0.5f + 0.01f * i);
  const char* const codecs[] = {"png", "rvl"};
  for (int f = 0; f < 4; ++f) {
    const auto m =
        upd::test::compressedDepthOf(depth, f < 2 ? "16UC1" : "32FC1", codecs[f % 2]);
    std::ofstream seed(out / "compressed_depth" / ("seed" + std::to_string(f)), std::ios::binary);
    seed.put(static_cast<char>(f));
    seed.write(reinterpret_cast<const char*>(m.data.data()),
               static_cast<std::streamsize>(m.data.size()));
  }
  bag.compression = rosbag::compression::Uncompressed;
  for (const char* codec : {"png", "rvl"}) {
    bag.depth_codec = codec;
    const std::string name = std::string("compressed-depth-") + codec + ".bag";
    upd::test::writeSmallBag((out / "bag" / name).string(), bag);
  }
#endif
#ifdef UPD_FUZZ_HAVE_LEARN
  putModels(out / "classifier");
#endif
  return 0;
}
