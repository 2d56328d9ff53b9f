// Generated depth frames for the benchmarks of the MRPT side (upd_bag_bench,
// upd_record_bench): 640 x 480 frames of makeWorld("mixed") from a camera 0.6 m high moving
// 5 cm a frame along x, and each as the CObservation3DRangeScan `upd playback` converts it to.
#pragma once

#include <mrpt/obs/CObservation3DRangeScan.h>

#include <vector>

#include "upd/core/camera.h"

namespace upd::bench {

/// n frames seen with the intrinsics K.
std::vector<core::DepthImage> renderFrames(int n, const core::CameraIntrinsics& K);

/// The frame as a range image in millimetres (0 where it has no range).
mrpt::obs::CObservation3DRangeScan scanOf(const core::DepthImage& d);

}  // namespace upd::bench
