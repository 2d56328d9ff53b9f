// A calibration YAML opened by OpenCV's parser (cv::FileStorage), its text checked first against
// the subset calibrations are written in (yaml_text.cpp): OpenCV 4.6's parser loops forever on
// some malformed documents (tests/fuzz/regressions/calibration).
#pragma once

#include <opencv2/core/persistence.hpp>

#include <string>

namespace upd::mrpt_bridge {

// file opened for reading (OpenCV's "%YAML:1.0" directive added where it has none, as in ROS's
// camera_info files). Refused (std::runtime_error "<what> <file>: ...", naming the line where
// there is one) where it is missing or unreadable, where a byte is a control character or not
// ASCII (tabs and line ends are text), where a line is not of the subset that ROS's
// camera_info files, RTAB-Map's and OpenCV's calibrations are written in, or where OpenCV
// cannot parse it. The subset: a "%YAML" first line, "---" before the first key, "..." with
// nothing after it, comments, "key: value" (a plain or quoted scalar, a list of plain items in
// [ ] that may go on over the next lines, "!!opencv-matrix", or nothing) and such keys indented
// alike under a top-level key with no value or a tag.
cv::FileStorage openCheckedYaml(const std::string& file, const std::string& what);

}  // namespace upd::mrpt_bridge
