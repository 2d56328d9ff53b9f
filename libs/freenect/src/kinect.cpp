#include "upd/freenect/kinect.h"

#include <libfreenect.h>
#include <libfreenect_registration.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <sys/time.h>

namespace upd::freenect {

namespace {

constexpr int kWidth = 640, kHeight = 480;
constexpr std::uint16_t kRawNoValue = 2047;  // FREENECT_DEPTH_RAW_NO_VALUE
constexpr double kMaxMm = 10000;             // FREENECT_DEPTH_MM_MAX_VALUE
constexpr double kParamCoeff = 4, kShiftScale = 10, kConstOffset = 0.375;

ZeroPlane zeroPlaneOf(freenect_device* dev) {
  freenect_registration reg = freenect_copy_registration(dev);
  ZeroPlane zp;
  zp.dcmos_emitter_dist_cm = reg.zero_plane_info.dcmos_emitter_dist;
  zp.reference_distance_mm = reg.zero_plane_info.reference_distance;
  zp.reference_pixel_size_mm = reg.zero_plane_info.reference_pixel_size;
  zp.const_shift = reg.const_shift;
  freenect_destroy_registration(&reg);
  return zp;
}

}  // namespace

double rawToMm(std::uint16_t raw, const ZeroPlane& zp) {
  if (raw >= kRawNoValue) return 0;
  // libfreenect's freenect_raw_to_mm (registration.c), in floating point.
  const double fixed_ref_x = (raw - kParamCoeff * zp.const_shift) / kParamCoeff - kConstOffset;
  const double metric = fixed_ref_x * zp.reference_pixel_size_mm;
  const double mm = kShiftScale * (metric * zp.reference_distance_mm /
                                       (zp.dcmos_emitter_dist_cm - metric) +
                                   zp.reference_distance_mm);
  return mm > 0 && mm <= kMaxMm ? mm : 0;
}

std::uint16_t mmToRaw(double depth_mm, const ZeroPlane& zp) {
  if (!(depth_mm > 0) || depth_mm > kMaxMm) return kRawNoValue;
  const double q = depth_mm / kShiftScale - zp.reference_distance_mm;
  const double metric = zp.dcmos_emitter_dist_cm * q / (zp.reference_distance_mm + q);
  const double raw =
      kParamCoeff * (metric / zp.reference_pixel_size_mm + kConstOffset) + kParamCoeff * zp.const_shift;
  if (!(raw >= 0) || raw >= kRawNoValue) return kRawNoValue;
  return static_cast<std::uint16_t>(std::lround(raw));
}

core::CameraIntrinsics intrinsicsOf(const ZeroPlane& zp) {
  core::CameraIntrinsics K;
  K.width = kWidth;
  K.height = kHeight;
  // freenect_camera_to_world: x = (u - 320) * 2 * pixel_size * z / reference_distance.
  K.fx = K.fy = zp.reference_distance_mm / (2.0 * zp.reference_pixel_size_mm);
  K.cx = kWidth / 2.0;
  K.cy = kHeight / 2.0;
  return K;
}

struct KinectCamera::Impl {
  freenect_context* ctx = nullptr;
  freenect_device* dev = nullptr;
  int index = 0;
  std::string replay_dir;  ///< FAKENECT_PATH, empty for a device
  ZeroPlane zero_plane;
  std::vector<std::uint16_t> latest;
  std::uint32_t latest_ts = 0;
  bool fresh = false;
  std::uint64_t frames = 0;

  static void onDepth(freenect_device* dev, void* data, std::uint32_t ts) {
    auto* self = static_cast<Impl*>(freenect_get_user(dev));
    const auto* px = static_cast<const std::uint16_t*>(data);
    self->latest.assign(px, px + kWidth * kHeight);
    self->latest_ts = ts;
    self->fresh = true;
  }
  ~Impl() {
    if (dev) {
      freenect_stop_depth(dev);
      freenect_close_device(dev);
    }
    if (ctx) freenect_shutdown(ctx);
  }
  void open();
  void toFrame(KinectFrame& frame);
};

void KinectCamera::Impl::open() {
  if (freenect_init(&ctx, nullptr) < 0) {
    ctx = nullptr;
    throw std::runtime_error("libfreenect cannot start (no USB access?)");
  }
  freenect_select_subdevices(ctx, FREENECT_DEVICE_CAMERA);
  const int n = freenect_num_devices(ctx);
  if (index < 0 || index >= n) {
    throw std::runtime_error("no Kinect v1 with index " + std::to_string(index) + " (" +
                             std::to_string(n) + " connected, libfreenect)");
  }
  if (freenect_open_device(ctx, &dev, index) < 0) {
    dev = nullptr;
    throw std::runtime_error("cannot open Kinect v1 #" + std::to_string(index) +
                             " (libfreenect; in use, or no permission on its USB device?)");
  }
  // fakenect replays raw disparity only (and asserts on any other mode).
  const freenect_depth_format fmt = replay_dir.empty() ? FREENECT_DEPTH_MM : FREENECT_DEPTH_11BIT;
  if (freenect_set_depth_mode(dev, freenect_find_depth_mode(FREENECT_RESOLUTION_MEDIUM, fmt)) < 0) {
    throw std::runtime_error("Kinect v1 #" + std::to_string(index) +
                             ": cannot set the 640x480 depth mode");
  }
  if (replay_dir.empty()) zero_plane = zeroPlaneOf(dev);
  freenect_set_user(dev, this);
  freenect_set_depth_callback(dev, &Impl::onDepth);
  if (freenect_start_depth(dev) < 0) {
    throw std::runtime_error("Kinect v1 #" + std::to_string(index) + ": cannot start the depth stream");
  }
}

void KinectCamera::Impl::toFrame(KinectFrame& frame) {
  frame.depth.width = kWidth;
  frame.depth.height = kHeight;
  frame.depth.depth_m.resize(latest.size());
  const bool raw = !replay_dir.empty();
  for (std::size_t i = 0; i < latest.size(); ++i) {
    const double mm = raw ? rawToMm(latest[i], zero_plane) : latest[i];
    frame.depth.depth_m[i] = static_cast<float>(mm * 1e-3);
  }
  frame.K = intrinsicsOf(zero_plane);
  frame.timestamp = latest_ts;
  frame.index = ++frames;
  fresh = false;
}

KinectCamera::KinectCamera(int index) : impl_(std::make_unique<Impl>()) {
  impl_->index = index;
  if (const char* p = std::getenv("FAKENECT_PATH")) impl_->replay_dir = p;
  impl_->open();
}

KinectCamera::~KinectCamera() = default;

ReadStatus KinectCamera::read(KinectFrame& frame, int timeout_ms) {
  Impl& m = *impl_;
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (!m.fresh) {
    timeval tv{0, 20000};
    const int rc = freenect_process_events_timeout(m.ctx, &tv);
    if (rc < 0) {
      if (!m.replay_dir.empty()) return ReadStatus::End;  // fakenect: no more lines
      throw std::runtime_error("Kinect v1 #" + std::to_string(m.index) +
                               ": libfreenect failed (error " + std::to_string(rc) + ")");
    }
    if (!m.fresh && std::chrono::steady_clock::now() >= until) return ReadStatus::Timeout;
  }
  m.toFrame(frame);
  return ReadStatus::Frame;
}

std::string KinectCamera::description() const {
  if (!impl_->replay_dir.empty()) return "fakenect recording " + impl_->replay_dir;
  return "Kinect v1 #" + std::to_string(impl_->index) + " (libfreenect)";
}

bool KinectCamera::isReplay() const { return !impl_->replay_dir.empty(); }

void writeFakenectDepth(const std::string& dir, const core::DepthImage& depth, double time_s,
                        std::uint32_t timestamp) {
  if (depth.width != kWidth || depth.height != kHeight) {
    throw std::invalid_argument("fakenect depth frame: " + std::to_string(depth.width) + "x" +
                                std::to_string(depth.height) + ", must be 640x480");
  }
  char name[96];
  std::snprintf(name, sizeof name, "d-%.6f-%u.pgm", time_s, timestamp);
  const std::string path = (std::filesystem::path(dir) / name).string();
  std::vector<std::uint16_t> raw(depth.depth_m.size());
  for (std::size_t i = 0; i < raw.size(); ++i) {
    const float z = depth.depth_m[i];
    raw[i] = std::isfinite(z) && z > 0 ? mmToRaw(z * 1000.0) : kRawNoValue;
  }
  std::ofstream out(path, std::ios::binary);
  out << "P5 640 480 65535\n";
  out.write(reinterpret_cast<const char*>(raw.data()),
            static_cast<std::streamsize>(raw.size() * sizeof(std::uint16_t)));
  std::ofstream index((std::filesystem::path(dir) / "INDEX.txt").string(), std::ios::app);
  index << name << "\n";
  if (!out || !index) throw std::runtime_error("cannot write the fakenect frame " + path);
}

}  // namespace upd::freenect
