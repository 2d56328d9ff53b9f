// The OpenNI2 route of `upd live`: a PrimeSense PS1080 device (Xtion, Carmine) or an .oni
// recording, read through libs/openni2.
#ifdef UPD_HAVE_OPENNI2

#include "live_source.h"

#include "upd/openni2/depth_camera.h"

namespace upd::app {

namespace {

class OpenNI2Source : public LiveSource {
 public:
  OpenNI2Source(const std::string& oni, const Eigen::Isometry3d& mount, int downscale)
      : camera_(oni), mount_(mount), downscale_(downscale) {}

  Poll poll(LiveFrame& frame) override {
    switch (camera_.tryRead(raw_, kWaitMs)) {
      case openni2::ReadStatus::End:
        return Poll::End;
      case openni2::ReadStatus::Timeout:
        return Poll::Nothing;
      case openni2::ReadStatus::Frame:
        break;
    }
    frame.observation = depthObservation(raw_.depth, raw_.K, mount_, downscale_, "OPENNI2");
    frame.stamp_s = raw_.device_time_s;
    return Poll::Frame;
  }
  std::string description() const override { return camera_.description(); }

 private:
  static constexpr int kWaitMs = 100;
  openni2::OpenNI2Camera camera_;
  Eigen::Isometry3d mount_;
  int downscale_;
  openni2::DepthFrame raw_;
};

}  // namespace

std::unique_ptr<LiveSource> openOpenNI2Source(const std::string& oni,
                                              const Eigen::Isometry3d& mount_on_robot,
                                              int image_downscale) {
  return std::make_unique<OpenNI2Source>(oni, mount_on_robot, image_downscale);
}

}  // namespace upd::app

#endif
