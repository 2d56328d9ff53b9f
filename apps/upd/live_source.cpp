// The live sources that need no optional driver (an MRPT sensor file), the depth-image
// conversion shared by the depth cameras, and the choice of the source from the options.
#include "live_source.h"

#include "live_options.h"

#include "upd/mrpt_bridge/pose_source.h"
#include "upd/mrpt_bridge/sensor_source.h"

#include <mrpt/obs/CObservation3DRangeScan.h>

#include <chrono>
#include <cmath>
#include <deque>
#include <stdexcept>
#include <thread>

namespace upd::app {

namespace {

double stampOf(const mrpt::obs::CObservation& obs) {
  if (obs.timestamp == INVALID_TIMESTAMP) return std::numeric_limits<double>::quiet_NaN();
  return mrpt::Clock::toDouble(obs.timestamp);
}

// An MRPT sensor file's section: doProcess() per poll, its observations one at a time.
class SensorFileSource : public LiveSource {
 public:
  SensorFileSource(const std::string& ini, const std::string& section) : sensor_(ini, section) {}

  Poll poll(LiveFrame& frame) override {
    if (pending_.empty()) {
      std::vector<std::shared_ptr<mrpt::obs::CObservation>> got;
      if (!sensor_.poll(got)) return Poll::End;
      pending_.insert(pending_.end(), got.begin(), got.end());
    }
    if (pending_.empty()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));  // the sensor had nothing new
      return Poll::Nothing;
    }
    frame.observation = pending_.front();
    frame.stamp_s = stampOf(*frame.observation);
    pending_.pop_front();
    return Poll::Frame;
  }
  std::string description() const override { return sensor_.description(); }

 private:
  mrpt_bridge::MrptSensorSource sensor_;
  std::deque<std::shared_ptr<mrpt::obs::CObservation>> pending_;
};

}  // namespace

std::shared_ptr<mrpt::obs::CObservation> depthObservation(const core::DepthImage& depth,
                                                          const core::CameraIntrinsics& K,
                                                          const Eigen::Isometry3d& mount_on_robot,
                                                          int downscale, const std::string& label) {
  if (downscale < 1) {
    throw std::invalid_argument("image_downscale = " + std::to_string(downscale) +
                                ": must be >= 1");
  }
  auto obs = mrpt::obs::CObservation3DRangeScan::Create();
  const int w = depth.width / downscale, h = depth.height / downscale;
  obs->hasRangeImage = true;
  obs->range_is_depth = true;
  obs->rangeUnits = 0.001f;
  obs->rangeImage.resize(h, w);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const float z = depth.at(u * downscale, v * downscale);
      const float mm = std::isfinite(z) && z > 0 ? std::round(z * 1000.f) : 0.f;
      obs->rangeImage(v, u) = static_cast<uint16_t>(std::min(mm, 65535.f));
    }
  }
  // Pixel u of the decimated image is pixel u * downscale of the full one.
  const double s = 1.0 / downscale;
  obs->cameraParams.ncols = static_cast<uint32_t>(w);
  obs->cameraParams.nrows = static_cast<uint32_t>(h);
  obs->cameraParams.setIntrinsicParamsFromValues(K.fx * s, K.fy * s, K.cx * s, K.cy * s);
  obs->cameraParamsIntensity = obs->cameraParams;
  obs->sensorPose = mrpt_bridge::toCPose3D(mount_on_robot);
  obs->sensorLabel = label;
  obs->timestamp = mrpt::Clock::now();
  return obs;
}

std::unique_ptr<LiveSource> openLiveSource(const LiveOptions& o,
                                           const Eigen::Isometry3d& mount_on_robot,
                                           int image_downscale) {
  if (!o.sensors.empty()) return std::make_unique<SensorFileSource>(o.sensors, o.sensor_section);
  if (o.kinect) {
#ifdef UPD_HAVE_FREENECT
    return openFreenectSource(*o.kinect, mount_on_robot, image_downscale);
#else
    throw std::runtime_error(
        "--kinect: upd was built without libfreenect (install libfreenect-dev and rebuild)");
#endif
  }
#ifdef UPD_HAVE_OPENNI2
  return openOpenNI2Source(o.oni, mount_on_robot, image_downscale);
#else
  (void)mount_on_robot;
  (void)image_downscale;
  const std::string why = "upd was built without OpenNI2 (install libopenni2-dev and rebuild)";
  throw std::runtime_error(o.oni.empty() ? "no OpenNI2 depth camera input: " + why
                                         : "cannot play " + o.oni + ": " + why);
#endif
}

}  // namespace upd::app
