// upd_bag_bench: what `upd playback RUN.bag` spends before its first frame is scored, against the
// peers, in the same run. On bags it writes (generated 640 x 480 depth frames of
// makeWorld("mixed"), a camera moving 5 cm a frame, each frame an Image, its CameraInfo and a
// transform; uncompressed, LZ4 and BZ2 chunks):
//  - the read: ros1::readBag (the walk that checks every length and offset, the transforms, the
//    frames converted to depth images with their poses), one core and two, against rosbag's own
//    reader doing the same reads (a view of /tf and /tf_static, then a view of the images and
//    their info, each message instantiated, each image converted and its poses looked up; it
//    checks nothing, and a damaged bag can end the process: docs/ROS.md);
//  - the converted frames' rawlog: the same serialized bytes gzip-compressed by
//    mrpt_bridge::GzOutputStream, one core and two, against MRPT's CFileGZOutputStream.
// Medians over the runs, ours and the peer in turn. Printed, and written as JSON with --json.
//
// Usage: upd_bag_bench [--frames N (100)] [--repeats N (7)] [--json OUT.json]
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/serialization/CArchive.h>
#include <omp.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tf2/buffer_core.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_args.h"
#include "depth_frames.h"
#include "upd/io/json_io.h"
#include "upd/mrpt_bridge/gz_output_stream.h"
#include "upd/ros1/bag_reader.h"
#include "upd/ros1/conversions.h"
#include "upd/sim/robot.h"

namespace {

using namespace upd;
using json = nlohmann::json;

const char* kDepth = "/camera/depth/image_raw";
const char* kInfo = "/camera/depth/camera_info";

void writeBag(const std::string& path, rosbag::compression::CompressionType compression,
              const std::vector<core::DepthImage>& frames, const core::CameraIntrinsics& K) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.setCompression(compression);
  tf2_msgs::TFMessage statics;
  statics.transforms.push_back(
      ros1::stampedTransform(Eigen::Isometry3d::Identity(), "base_link", "camera", ros::Time(1.0)));
  bag.write("/tf_static", ros::Time(1.0), statics);
  sensor_msgs::CameraInfo info = ros1::cameraInfoFromIntrinsics(K);
  info.header.frame_id = "camera";
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const double t = 1.0 + i / 30.0;
    Eigen::Isometry3d robot = Eigen::Isometry3d::Identity();
    robot.translation().x() = 0.05 * static_cast<double>(i);
    tf2_msgs::TFMessage tf;
    tf.transforms.push_back(ros1::stampedTransform(robot, "map", "base_link", ros::Time(t)));
    bag.write("/tf", ros::Time(t), tf);
    sensor_msgs::Image image = ros1::imageFromDepth(frames[i], "16UC1");
    image.header.frame_id = "camera";
    info.header.stamp = image.header.stamp = ros::Time(t);
    bag.write(kInfo, ros::Time(t), info);
    bag.write(kDepth, ros::Time(t), image);
  }
}

// rosbag's reader doing readBag's reads: the frames it places.
std::size_t readByRosbag(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  tf2::BufferCore tf(ros::Duration(3600.0));
  for (const rosbag::MessageInstance& m :
       rosbag::View(bag, rosbag::TopicQuery(std::vector<std::string>{"/tf", "/tf_static"}))) {
    const auto msg = m.instantiate<tf2_msgs::TFMessage>();
    for (const auto& t : msg->transforms) tf.setTransform(t, "bag", m.getTopic() == "/tf_static");
  }
  sensor_msgs::CameraInfo::ConstPtr info;
  std::size_t frames = 0;
  for (const rosbag::MessageInstance& m :
       rosbag::View(bag, rosbag::TopicQuery(std::vector<std::string>{kDepth, kInfo}))) {
    if (auto i = m.instantiate<sensor_msgs::CameraInfo>()) {
      info = i;
      continue;
    }
    const auto image = m.instantiate<sensor_msgs::Image>();
    if (!image || !info) continue;
    const core::DepthImage depth = ros1::depthFromImage(*image);
    const core::CameraIntrinsics k = ros1::intrinsicsForDepth(depth, *info);
    tf.lookupTransform("base_link", image->header.frame_id, image->header.stamp);
    tf.lookupTransform("map", "base_link", image->header.stamp);
    frames += k.width > 0 ? 1 : 0;
  }
  return frames;
}

double msOf(const std::function<void()>& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[v.size() / 2];
}

// The medians of each candidate over `repeats` runs, the candidates run in turn.
std::vector<double> medians(const std::vector<std::function<void()>>& candidates, int repeats) {
  std::vector<std::vector<double>> times(candidates.size());
  for (int r = 0; r < repeats; ++r) {
    for (std::size_t c = 0; c < candidates.size(); ++c) times[c].push_back(msOf(candidates[c]));
  }
  std::vector<double> out;
  for (auto& t : times) out.push_back(median(t));
  return out;
}

// The frames as `upd playback` converts them (scanOf), each serialized.
std::vector<std::vector<std::uint8_t>> serializedScans(
    const std::vector<core::DepthImage>& frames) {
  std::vector<std::vector<std::uint8_t>> all;
  for (const core::DepthImage& d : frames) {
    mrpt::io::CMemoryStream mem;
    mrpt::serialization::archiveFrom(mem) << bench::scanOf(d);
    const auto* p = static_cast<const std::uint8_t*>(mem.getRawBufferData());
    all.emplace_back(p, p + mem.getTotalBytesCount());
  }
  return all;
}

// Writes each frame's bytes to out, as the conversion does frame by frame.
void writeFrames(mrpt::io::CStream& out, const std::vector<std::vector<std::uint8_t>>& frames) {
  for (const auto& f : frames) out.Write(f.data(), f.size());
}

int run(int n_frames, int repeats, const std::string& json_path) {
  const int threads = omp_get_max_threads();
  const core::CameraIntrinsics K = sim::simulatedIntrinsics(sim::CameraMountParams{});  // Kinect
  const std::vector<core::DepthImage> frames = bench::renderFrames(n_frames, K);
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("upd_bag_bench-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  json report = {{"frames", n_frames}, {"repeats", repeats}, {"threads", threads}};
  std::printf("upd_bag_bench: %d frames of 640 x 480, medians of %d runs, ms a frame\n", n_frames,
              repeats);
  std::printf("%-6s %10s %12s %12s %14s %10s\n", "chunks", "bag MB", "ours, 1 core", "ours, 2",
              "rosbag's reader", "rosbag / ours (2)");
  for (const auto& [name, compression] :
       std::vector<std::pair<std::string, rosbag::compression::CompressionType>>{
           {"none", rosbag::compression::Uncompressed},
           {"lz4", rosbag::compression::LZ4},
           {"bz2", rosbag::compression::BZ2}}) {
    const std::string path = (dir / (name + ".bag")).string();
    writeBag(path, compression, frames, K);
    std::size_t ours_frames = 0, peer_frames = 0;
    const auto ours = [&](int t) {
      return [&, t] {
        omp_set_num_threads(t);
        ours_frames = ros1::readBag(path, {}, [](const ros1::BagFrame&) {}).frames;
        omp_set_num_threads(threads);
      };
    };
    const std::vector<double> m =
        medians({ours(1), ours(threads), [&] { peer_frames = readByRosbag(path); }}, repeats);
    const double mb = static_cast<double>(std::filesystem::file_size(path)) / 1e6;
    std::printf("%-6s %10.1f %12.2f %12.2f %14.2f %10.2f\n", name.c_str(), mb, m[0] / n_frames,
                m[1] / n_frames, m[2] / n_frames, m[2] / m[1]);
    report["read"][name] = {{"bag_mb", mb},
                            {"ours_one_core_ms_per_frame", m[0] / n_frames},
                            {"ours_all_cores_ms_per_frame", m[1] / n_frames},
                            {"rosbag_ms_per_frame", m[2] / n_frames},
                            {"rosbag_over_ours", m[2] / m[1]},
                            {"frames_read", {{"ours", ours_frames}, {"rosbag", peer_frames}}}};
  }
  const std::vector<std::vector<std::uint8_t>> scans = serializedScans(frames);
  double serialized_mb = 0;
  for (const auto& f : scans) serialized_mb += f.size() / 1e6;
  const std::string rawlog = (dir / "frames.rawlog").string();
  const auto gz = [&](int t) {
    return [&, t] {
      omp_set_num_threads(t);
      mrpt_bridge::GzOutputStream out(rawlog);
      writeFrames(out, scans);
      out.close();
      omp_set_num_threads(threads);
    };
  };
  const std::vector<double> w = medians({gz(1), gz(threads),
                                         [&] {
                                           mrpt::io::CFileGZOutputStream out(rawlog);
                                           writeFrames(out, scans);
                                         }},
                                        repeats);
  std::printf(
      "\nthe converted frames' rawlog (%.1f MB serialized), ms a frame: GzOutputStream %.2f "
      "(1 core) / %.2f (%d), CFileGZOutputStream %.2f: %.2fx\n",
      serialized_mb, w[0] / n_frames, w[1] / n_frames, threads, w[2] / n_frames, w[2] / w[1]);
  report["rawlog_write"] = {{"serialized_mb", serialized_mb},
                            {"ours_one_core_ms_per_frame", w[0] / n_frames},
                            {"ours_all_cores_ms_per_frame", w[1] / n_frames},
                            {"cfilegz_ms_per_frame", w[2] / n_frames},
                            {"cfilegz_over_ours", w[2] / w[1]}};
  std::filesystem::remove_all(dir);
  if (!json_path.empty()) upd::io::writeJsonAtomically(json_path, report);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    int frames = 100, repeats = 7;
    std::string json_path;
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (i + 1 < argc && a == "--frames") {
        frames = upd::bench::positiveCount(a, argv[++i]);
      } else if (i + 1 < argc && a == "--repeats") {
        repeats = upd::bench::positiveCount(a, argv[++i]);
      } else if (i + 1 < argc && a == "--json") {
        json_path = argv[++i];
      } else {
        std::fprintf(stderr,
                     "usage: upd_bag_bench [--frames N] [--repeats N] [--json OUT.json]\n");
        return a == "--help" ? 0 : 2;
      }
    }
    return run(frames, repeats, json_path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "upd_bag_bench: %s\n", e.what());
    return 1;
  }
}
