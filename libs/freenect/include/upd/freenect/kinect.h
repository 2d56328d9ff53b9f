// The Kinect v1 (Xbox 360 Kinect, model 1414/1473) through libfreenect: z-depth images in
// metres with the depth camera's intrinsics.
//
// A device is read in FREENECT_DEPTH_MM: libfreenect's registration converts the raw disparity
// to millimetres with the device's own zero-plane calibration, and the intrinsics follow from it
// (fx = fy = reference_distance / (2 * reference_pixel_size), the principal point at the image
// centre: what freenect_camera_to_world uses). fakenect, libfreenect's replay library
// (libfreenect-bin; `FAKENECT_PATH=DIR` with its libfreenect.so preloaded, or `fakenect DIR
// upd ...`), plays recordings of the raw 11-bit disparity only and has no registration: when
// FAKENECT_PATH is set the camera reads FREENECT_DEPTH_11BIT and converts with libfreenect's
// own formula (freenect_raw_to_mm) over the nominal Kinect zero plane (kNominalZeroPlane).
// A fakenect recording (fakenect-record's layout) is a folder with INDEX.txt, one file name a
// line, and the files: `d-TIME-TIMESTAMP.pgm` a depth frame (a one-line PGM header "P5 640 480
// 65535", then 640 x 480 uint16 raw disparities in the machine's byte order; 2047 = no value),
// `r-...ppm` a colour frame, `a-...dump` the accelerometer; TIME is the recording time [s],
// TIMESTAMP the device's frame counter. writeFakenectDepth() writes such depth frames.
#pragma once

#include "upd/core/camera.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace upd::freenect {

/// libfreenect's zero-plane calibration: what converts disparity to depth.
struct ZeroPlane {
  double dcmos_emitter_dist_cm = 7.5;  ///< emitter to depth camera [cm]
  double reference_distance_mm = 120;  ///< [mm]
  double reference_pixel_size_mm = 0.1042;  ///< at full (1280-px) sensor resolution [mm]
  double const_shift = 200;
};
/// The values libfreenect uses when a device gives none (its registration.c).
constexpr ZeroPlane kNominalZeroPlane{};

/// Raw 11-bit disparity to depth [mm] as libfreenect computes it (0 for 2047, no value).
double rawToMm(std::uint16_t raw, const ZeroPlane& zp = kNominalZeroPlane);
/// The raw disparity whose depth is nearest to depth_mm (2047 for 0 or out of range): to
/// write recordings of known depth.
std::uint16_t mmToRaw(double depth_mm, const ZeroPlane& zp = kNominalZeroPlane);
/// The depth camera's intrinsics at 640 x 480 from the zero plane.
core::CameraIntrinsics intrinsicsOf(const ZeroPlane& zp = kNominalZeroPlane);

struct KinectFrame {
  core::DepthImage depth;    ///< z-depth [m]; 0 = invalid
  core::CameraIntrinsics K;  ///< of this image
  std::uint32_t timestamp = 0;  ///< the device's frame timestamp (a counter)
  std::uint64_t index = 0;      ///< frames read so far, this one included
};

enum class ReadStatus { Frame, Timeout, End };

class KinectCamera {
 public:
  /// Opens Kinect number index. Throws std::runtime_error with one line when libfreenect cannot
  /// start or no Kinect has that index.
  explicit KinectCamera(int index = 0);
  ~KinectCamera();
  KinectCamera(const KinectCamera&) = delete;
  KinectCamera& operator=(const KinectCamera&) = delete;

  /// The next depth frame within timeout_ms: Frame, Timeout, or End (fakenect without looping
  /// reached the end of its recording). Throws std::runtime_error when libfreenect fails.
  ReadStatus read(KinectFrame& frame, int timeout_ms);
  /// "Kinect v1 #0 (libfreenect)" or "fakenect recording DIR".
  std::string description() const;
  bool isReplay() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Writes one depth frame of a fakenect recording into dir and appends its line to
/// dir/INDEX.txt: `d-<time_s>-<timestamp>.pgm` holding depth (z [m], 0 = invalid, 640 x 480)
/// as raw disparity (mmToRaw). Throws std::runtime_error naming a file it cannot write, and
/// std::invalid_argument when the image is not 640 x 480.
void writeFakenectDepth(const std::string& dir, const core::DepthImage& depth, double time_s,
                        std::uint32_t timestamp);

}  // namespace upd::freenect
