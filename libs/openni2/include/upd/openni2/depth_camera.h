// A live depth camera through OpenNI2: an Xtion or Carmine (PrimeSense PS1080), or an .oni
// recording of one. Debian's OpenNI2 has no Kinect v1 driver: libs/freenect reads the Kinect v1.
//
// OpenNI2 is used directly (not through MRPT's COpenNI2Sensor, which aborts the process when no
// device is attached): the constructor enumerates the devices first and fails with one line when
// there is none. Frames come as z-depth images in metres with the intrinsics derived from the
// stream's fields of view (camera-optical frame, camera.h). This library is optional: it is
// built when OpenNI2 is found, and `upd live` reads a camera only then.
#pragma once

#include "upd/core/camera.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace upd::openni2 {

struct DepthFrame {
  core::DepthImage depth;          ///< z-depth [m]; 0 = invalid
  core::CameraIntrinsics K;        ///< of this image
  std::uint64_t index = 0;   ///< frame number from the device or recording
  double device_time_s = 0;  ///< the device's timestamp [s]
};

/// What tryRead() got.
enum class ReadStatus { Frame, Timeout, End };

class OpenNI2Camera {
 public:
  /// oni_path empty: the first connected device; otherwise an .oni recording, played frame by
  /// frame without repeating. Throws std::runtime_error with a one-line reason when no device is
  /// connected, the file cannot be opened or it has no depth stream.
  explicit OpenNI2Camera(const std::string& oni_path = "");
  ~OpenNI2Camera();
  OpenNI2Camera(const OpenNI2Camera&) = delete;
  OpenNI2Camera& operator=(const OpenNI2Camera&) = delete;

  /// The next frame. False at the end of a recording; throws std::runtime_error when a device
  /// sends nothing for timeout_ms.
  bool read(DepthFrame& frame, int timeout_ms = 2000);
  /// The next frame within timeout_ms: Frame, Timeout (a device sent nothing yet) or End (a
  /// recording has no more frames). Throws std::runtime_error when reading a frame fails.
  ReadStatus tryRead(DepthFrame& frame, int timeout_ms);
  bool isRecording() const;
  /// "PrimeSense Carmine 1.09 (1d27:0601)" or "recording FILE.oni (N frames)".
  std::string description() const;

  /// URIs of the connected OpenNI2 devices (initializes OpenNI2; safe without any device).
  static std::vector<std::string> connectedDevices();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace upd::openni2
