// The libfreenect route of `upd live --kinect`: a Kinect v1 (or a fakenect recording of one),
// read through libs/freenect.
#ifdef UPD_HAVE_FREENECT

#include "live_source.h"

#include "upd/freenect/kinect.h"

namespace upd::app {

namespace {

class FreenectSource : public LiveSource {
 public:
  FreenectSource(int index, const Eigen::Isometry3d& mount, int downscale)
      : camera_(index), mount_(mount), downscale_(downscale) {}

  Poll poll(LiveFrame& frame) override {
    switch (camera_.read(raw_, kWaitMs)) {
      case freenect::ReadStatus::End:
        return Poll::End;
      case freenect::ReadStatus::Timeout:
        return Poll::Nothing;
      case freenect::ReadStatus::Frame:
        break;
    }
    frame.observation = depthObservation(raw_.depth, raw_.K, mount_, downscale_, "KINECT");
    frame.stamp_s = raw_.timestamp;  // a counter: only equality matters
    return Poll::Frame;
  }
  std::string description() const override { return camera_.description(); }

 private:
  static constexpr int kWaitMs = 100;
  freenect::KinectCamera camera_;
  Eigen::Isometry3d mount_;
  int downscale_;
  freenect::KinectFrame raw_;
};

}  // namespace

std::unique_ptr<LiveSource> openFreenectSource(int index, const Eigen::Isometry3d& mount_on_robot,
                                               int image_downscale) {
  return std::make_unique<FreenectSource>(index, mount_on_robot, image_downscale);
}

}  // namespace upd::app

#endif
