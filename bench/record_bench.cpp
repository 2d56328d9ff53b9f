// upd_record_bench: what the recording of `upd live --record` costs the loop thread, against the
// peer in the same run: each object serialized and compressed by MRPT's CFileGZOutputStream in
// the loop thread, a gzip member closed every 10 objects (the same file, byte for byte). The
// frames (generated 640 x 480 depth frames as CObservation3DRangeScan, each after its
// CObservationOdometry, as `upd live` records them) come at 30 Hz: the loop sleeps until the
// next frame is due, as it waits for the sensor. Timed: each frame's two writes on the loop
// thread; then the wait at the end for what is still queued (finish()).
// Printed, and written as JSON with --json.
//
// Usage: upd_record_bench [--frames N (100)] [--rounds N (3)] [--json OUT.json]
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/serialization/CArchive.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "cli_args.h"
#include "depth_frames.h"
#include "upd/io/json_io.h"
#include "upd/mrpt_bridge/rawlog_writer.h"
#include "upd/sim/robot.h"

namespace {

using namespace upd;
using Clock = std::chrono::steady_clock;
constexpr int kFlushEvery = 10;  // RawlogWriter's default

double ms(Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

mrpt::obs::CObservationOdometry odometry(int i, double t) {
  mrpt::obs::CObservationOdometry odo;
  odo.sensorLabel = "ODOMETRY";
  odo.odometry = mrpt::poses::CPose2D(0.05 * i, 0, 0);
  odo.timestamp = mrpt::Clock::fromDouble(t);
  return odo;
}

// The peer: the objects written in the caller's thread, a member closed every kFlushEvery.
class InlineWriter {
 public:
  explicit InlineWriter(const std::string& path) : path_(path), out_(path) {}
  void write(const mrpt::serialization::CSerializable& o) {
    mrpt::serialization::archiveFrom(out_) << o;
    if (++written_ % kFlushEvery == 0) {
      out_.close();
      std::string err;
      out_.open(path_, 1, err, mrpt::io::OpenMode::APPEND);
    }
  }
  void finish() { out_.close(); }

 private:
  std::string path_;
  mrpt::io::CFileGZOutputStream out_;
  int written_ = 0;
};

struct Timing {
  std::vector<double> frame_ms;  // the loop thread's time in the writes, every frame
  std::vector<double> finish_ms;
};

// One recording of the scans at 30 Hz by Writer into path.
template <class Writer>
void record(const std::vector<mrpt::obs::CObservation3DRangeScan>& scans, const std::string& path,
            Timing& t) {
  Writer w(path);
  const Clock::time_point start = Clock::now();
  for (std::size_t i = 0; i < scans.size(); ++i) {
    std::this_thread::sleep_until(start + std::chrono::microseconds(33333) * i);
    const double stamp = 1000.0 + static_cast<double>(i) / 30.0;
    const Clock::time_point t0 = Clock::now();
    if constexpr (std::is_same_v<Writer, mrpt_bridge::RawlogWriter>) {
      w.writeOdometry(0.05 * static_cast<double>(i), 0, 0, stamp);
    } else {
      w.write(odometry(static_cast<int>(i), stamp));
    }
    w.write(scans[i]);
    t.frame_ms.push_back(ms(Clock::now() - t0));
  }
  const Clock::time_point t0 = Clock::now();
  w.finish();
  t.finish_ms.push_back(ms(Clock::now() - t0));
}

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

std::string bytesOf(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

int run(int n_frames, int rounds, const std::string& json_path) {
  const core::CameraIntrinsics K = sim::simulatedIntrinsics(sim::CameraMountParams{});
  std::vector<mrpt::obs::CObservation3DRangeScan> scans;
  for (const core::DepthImage& d : bench::renderFrames(n_frames, K)) {
    scans.push_back(bench::scanOf(d));
  }
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("upd_record_bench-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string ours_path = (dir / "ours.rawlog").string();
  const std::string peer_path = (dir / "peer.rawlog").string();
  Timing ours, peer;
  for (int r = 0; r < rounds; ++r) {  // (in turn, the first one alternating)
    if (r % 2 == 0) {
      record<mrpt_bridge::RawlogWriter>(scans, ours_path, ours);
      record<InlineWriter>(scans, peer_path, peer);
    } else {
      record<InlineWriter>(scans, peer_path, peer);
      record<mrpt_bridge::RawlogWriter>(scans, ours_path, ours);
    }
  }
  const bool same = bytesOf(ours_path) == bytesOf(peer_path);
  const double mb = static_cast<double>(std::filesystem::file_size(ours_path)) / 1e6;
  std::filesystem::remove_all(dir);
  const double ours_median = quantile(ours.frame_ms, 0.5),
               peer_median = quantile(peer.frame_ms, 0.5);
  std::printf(
      "upd_record_bench: %d frames of 640 x 480 at 30 Hz, %d rounds; the rawlog %.1f MB, the same "
      "bytes: %s\nthe loop thread's time a frame (median / 95th percentile / most), ms:\n"
      "  RawlogWriter (writer thread)        %6.2f / %6.2f / %6.2f, finish %6.1f\n"
      "  CFileGZOutputStream in the loop     %6.2f / %6.2f / %6.2f, finish %6.1f\n"
      "  peer / ours (medians)               %6.1fx\n",
      n_frames, rounds, mb, same ? "yes" : "NO", ours_median, quantile(ours.frame_ms, 0.95),
      quantile(ours.frame_ms, 1.0), quantile(ours.finish_ms, 0.5), peer_median,
      quantile(peer.frame_ms, 0.95), quantile(peer.frame_ms, 1.0), quantile(peer.finish_ms, 0.5),
      peer_median / ours_median);
  const auto side = [](const Timing& t) {
    return nlohmann::json{{"median_ms_per_frame", quantile(t.frame_ms, 0.5)},
                          {"p95_ms_per_frame", quantile(t.frame_ms, 0.95)},
                          {"max_ms_per_frame", quantile(t.frame_ms, 1.0)},
                          {"finish_ms", quantile(t.finish_ms, 0.5)}};
  };
  const nlohmann::json report = {{"frames", n_frames},
                                 {"rounds", rounds},
                                 {"rate_hz", 30},
                                 {"rawlog_mb", mb},
                                 {"same_bytes", same},
                                 {"rawlog_writer", side(ours)},
                                 {"cfilegz_in_loop", side(peer)},
                                 {"peer_over_ours", peer_median / ours_median}};
  if (!json_path.empty()) upd::io::writeJsonAtomically(json_path, report);
  return same ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    int frames = 100, rounds = 3;
    std::string json_path;
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (i + 1 < argc && a == "--frames") {
        frames = upd::bench::positiveCount(a, argv[++i]);
      } else if (i + 1 < argc && a == "--rounds") {
        rounds = upd::bench::positiveCount(a, argv[++i]);
      } else if (i + 1 < argc && a == "--json") {
        json_path = argv[++i];
      } else {
        std::fprintf(stderr,
                     "usage: upd_record_bench [--frames N] [--rounds N] [--json OUT.json]\n");
        return a == "--help" ? 0 : 2;
      }
    }
    return run(frames, rounds, json_path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "upd_record_bench: %s\n", e.what());
    return 1;
  }
}
