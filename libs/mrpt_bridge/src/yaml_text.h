// The text of a calibration YAML for OpenCV's parser (cv::FileStorage), checked first against
// the subset calibrations are written in (yaml_text.cpp): OpenCV 4.6's parser loops forever on
// some malformed documents (tests/fuzz/regressions/calibration).
#pragma once

#include <string>

namespace upd::mrpt_bridge {

// The bytes of file, refused (std::runtime_error "<what> <file>: line N: ...") where missing or
// unreadable, where a byte is a control character or not ASCII (tabs and line ends are text),
// or where a line is not of the subset that ROS's camera_info files, RTAB-Map's and OpenCV's
// calibrations are written in: a "%YAML" first line, "---" before the first key, "..." with
// nothing after it, comments, "key: value" (a plain or quoted scalar, a list of plain items in
// [ ] that may go on over the next lines, "!!opencv-matrix", or nothing) and such keys indented
// alike under a top-level key with no value or a tag.
std::string checkedYamlText(const std::string& file, const std::string& what);

}  // namespace upd::mrpt_bridge
