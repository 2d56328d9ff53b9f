// The stereo pair of a CObservationStereoImages to a cloud (observation_stereo.cpp), for
// toCloud, and the image check both use.
#pragma once

#include "upd/mrpt_bridge/observation_cloud.h"

#include <opencv2/core.hpp>

namespace mrpt::obs {
class CObservationStereoImages;
}

namespace upd::mrpt_bridge::detail {

/// An image the conversions read: 8-bit grey, BGR or BGRA, not empty.
inline bool usableImage(const cv::Mat& m) {
  return !m.empty() && m.depth() == CV_8U &&
         (m.channels() == 1 || m.channels() == 3 || m.channels() == 4);
}

/// out.cloud_in_robot from o's pair, or out.skipped_reason set (the pair missing or unusable,
/// no calibration). out.sensor_pose_on_robot is the left camera's pose on entry; on return it
/// includes the rectification's rotation of the left camera where toCloud rectified the pair.
void convertStereo(const mrpt::obs::CObservationStereoImages& o, const SourceParams& params,
                   ObservationCloud& out);

}  // namespace upd::mrpt_bridge::detail
