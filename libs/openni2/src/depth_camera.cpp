#include "upd/openni2/depth_camera.h"

#include <OpenNI.h>

#include <cmath>
#include <stdexcept>

namespace upd::openni2 {

namespace {

// OpenNI2 is initialized once per process and never shut down while a camera may use it.
void initializeOpenNI() {
  static const openni::Status status = openni::OpenNI::initialize();
  if (status != openni::STATUS_OK) {
    throw std::runtime_error(std::string("OpenNI2 failed to initialize: ") +
                             openni::OpenNI::getExtendedError());
  }
}

std::string oneLine(const char* text) {
  std::string s = text == nullptr ? "" : text;
  for (char& c : s) {
    if (c == '\n' || c == '\t') c = ' ';
  }
  const auto b = s.find_first_not_of(' ');
  const auto e = s.find_last_not_of(' ');
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

}  // namespace

std::vector<std::string> OpenNI2Camera::connectedDevices() {
  initializeOpenNI();
  openni::Array<openni::DeviceInfo> devices;
  openni::OpenNI::enumerateDevices(&devices);
  std::vector<std::string> uris;
  for (int i = 0; i < devices.getSize(); ++i) uris.emplace_back(devices[i].getUri());
  return uris;
}

struct OpenNI2Camera::Impl {
  openni::Device device;
  openni::VideoStream depth;
  bool recording = false;
  int recording_frames = 0;
  std::string description;
};

OpenNI2Camera::OpenNI2Camera(const std::string& oni_path) : impl_(std::make_unique<Impl>()) {
  initializeOpenNI();
  auto& d = *impl_;
  if (oni_path.empty()) {
    const auto uris = connectedDevices();
    if (uris.empty()) {
      throw std::runtime_error(
          "no OpenNI2 depth camera connected (Xtion, Carmine; a Kinect v1 is read with "
          "--kinect): plug one in or pass --oni FILE.oni");
    }
    if (d.device.open(uris.front().c_str()) != openni::STATUS_OK) {
      throw std::runtime_error("cannot open the OpenNI2 device " + uris.front() + ": " +
                               oneLine(openni::OpenNI::getExtendedError()));
    }
    const openni::DeviceInfo& info = d.device.getDeviceInfo();
    d.description =
        std::string(info.getVendor()) + " " + info.getName() + " (" + uris.front() + ")";
  } else {
    if (d.device.open(oni_path.c_str()) != openni::STATUS_OK) {
      throw std::runtime_error("cannot open the OpenNI2 recording " + oni_path + ": " +
                               oneLine(openni::OpenNI::getExtendedError()));
    }
    d.recording = true;
  }
  if (!d.device.hasSensor(openni::SENSOR_DEPTH) ||
      d.depth.create(d.device, openni::SENSOR_DEPTH) != openni::STATUS_OK) {
    throw std::runtime_error((d.recording ? "recording " + oni_path : "device " + d.description) +
                             " has no depth stream");
  }
  if (d.recording) {
    openni::PlaybackControl* playback = d.device.getPlaybackControl();
    if (playback != nullptr) {
      playback->setRepeatEnabled(false);
      playback->setSpeed(-1.0f);  // manual: one frame per read, as fast as we process
      d.recording_frames = playback->getNumberOfFrames(d.depth);
    }
    d.description =
        "recording " + oni_path + " (" + std::to_string(d.recording_frames) + " depth frames)";
  } else {
    // Prefer 640 x 480 in millimetres, the Kinect's native depth mode.
    const auto& modes = d.device.getSensorInfo(openni::SENSOR_DEPTH)->getSupportedVideoModes();
    for (int i = 0; i < modes.getSize(); ++i) {
      if (modes[i].getResolutionX() == 640 && modes[i].getResolutionY() == 480 &&
          modes[i].getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_1_MM) {
        d.depth.setVideoMode(modes[i]);
        break;
      }
    }
  }
  if (d.depth.start() != openni::STATUS_OK) {
    throw std::runtime_error("cannot start the depth stream of " + d.description + ": " +
                             oneLine(openni::OpenNI::getExtendedError()));
  }
}

OpenNI2Camera::~OpenNI2Camera() {
  impl_->depth.stop();
  impl_->depth.destroy();
  impl_->device.close();
}

bool OpenNI2Camera::isRecording() const { return impl_->recording; }
std::string OpenNI2Camera::description() const { return impl_->description; }

bool OpenNI2Camera::read(DepthFrame& frame, int timeout_ms) {
  switch (tryRead(frame, timeout_ms)) {
    case ReadStatus::Frame:
      return true;
    case ReadStatus::End:
      return false;
    case ReadStatus::Timeout:
      break;
  }
  throw std::runtime_error("the depth camera sent no frame for " + std::to_string(timeout_ms) +
                           " ms");
}

ReadStatus OpenNI2Camera::tryRead(DepthFrame& frame, int timeout_ms) {
  auto& d = *impl_;
  openni::VideoStream* streams[] = {&d.depth};
  int ready = -1;
  if (openni::OpenNI::waitForAnyStream(streams, 1, &ready, timeout_ms) != openni::STATUS_OK) {
    // A recording played without repeat: no frame comes after the last.
    return d.recording ? ReadStatus::End : ReadStatus::Timeout;
  }
  openni::VideoFrameRef ref;
  if (d.depth.readFrame(&ref) != openni::STATUS_OK || !ref.isValid()) {
    if (d.recording) return ReadStatus::End;
    throw std::runtime_error("reading a depth frame failed: " +
                             oneLine(openni::OpenNI::getExtendedError()));
  }
  const openni::VideoMode mode = ref.getVideoMode();
  const double unit_m = mode.getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_100_UM ? 1e-4 : 1e-3;
  frame.depth.width = ref.getWidth();
  frame.depth.height = ref.getHeight();
  frame.depth.depth_m.resize(static_cast<std::size_t>(frame.depth.width) * frame.depth.height);
  const auto* bytes = static_cast<const std::uint8_t*>(ref.getData());
  for (int v = 0; v < frame.depth.height; ++v) {
    const auto* row = reinterpret_cast<const std::uint16_t*>(bytes + static_cast<std::size_t>(v) *
                                                                         ref.getStrideInBytes());
    for (int u = 0; u < frame.depth.width; ++u) {
      frame.depth.depth_m[static_cast<std::size_t>(v) * frame.depth.width + u] =
          static_cast<float>(row[u] * unit_m);
    }
  }
  // Pinhole intrinsics from the fields of view (OpenNI reports no calibration).
  core::CameraIntrinsics K;
  K.width = frame.depth.width;
  K.height = frame.depth.height;
  K.fx = 0.5 * K.width / std::tan(0.5 * d.depth.getHorizontalFieldOfView());
  K.fy = 0.5 * K.height / std::tan(0.5 * d.depth.getVerticalFieldOfView());
  K.cx = 0.5 * (K.width - 1);
  K.cy = 0.5 * (K.height - 1);
  frame.K = K;
  frame.index = static_cast<std::uint64_t>(ref.getFrameIndex());
  frame.device_time_s = static_cast<double>(ref.getTimestamp()) * 1e-6;
  return ReadStatus::Frame;
}

}  // namespace upd::openni2
