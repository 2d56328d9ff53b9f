// A CObservationRGBD360, walked as MRPT 2.5.8's serializeFrom() reads version 1: the maximum
// range, the sensor pose, then for each of its NUM_SENSORS cameras a range image (rows and
// columns, then the 16-bit pixels: MRPT sizes its aligned matrix to them first) and an intensity
// image (each set behind a flag), the cameras' timestamps, the standard error, the timestamp,
// the label and the external-storage flags and file names. And those flags and names, which a
// CObservation3DRangeScan ends with too.
#include "rawlog_precheck_cursor.h"

#include <mrpt/obs/CObservationRGBD360.h>

#include <utility>

namespace upd::mrpt_bridge::detail {

Parse checkExternalFiles(Cursor& c, std::string& why) {
  for (const auto& [flag, field] :
       {std::pair{"points stored externally", "external points file name length"},
        std::pair{"range stored externally", "external range file name length"}}) {
    std::uint8_t external = 0;
    Parse p = checkFlag(c, flag, external, why);
    if (p == Parse::Read) p = checkString(c, field, why);
    if (p != Parse::Read) return p;
  }
  return Parse::Read;
}

Parse checkRgbd360(Cursor& c, int version, std::string& why) {
  constexpr unsigned kSensors = mrpt::obs::CObservationRGBD360::NUM_SENSORS;
  if (version != 1) return Parse::OtherLayout;
  c.skip(sizeof(float));  // maxRange
  Parse p = checkPose(c, why);
  std::uint8_t has_range = 0, has_intensity = 0;
  if (p == Parse::Read) p = checkFlag(c, "range images", has_range, why);
  for (unsigned s = 0; has_range && s < kSensors && p == Parse::Read; ++s) {
    std::uint64_t rows = 0, cols = 0;
    p = checkSides(c, "range image", rows, cols, why);
    c.skip(rows * cols * sizeof(std::uint16_t));
  }
  if (p == Parse::Read) p = checkFlag(c, "intensity images", has_intensity, why);
  for (unsigned s = 0; has_intensity && s < kSensors && p == Parse::Read; ++s) {
    p = checkPart(c, "CImage", why);
  }
  if (p != Parse::Read) return p;
  // The cameras' timestamps, the standard error, the timestamp.
  c.skip(kSensors * sizeof(std::uint64_t) + sizeof(float) + sizeof(std::uint64_t));
  p = checkString(c, "sensor label length", why);
  return p == Parse::Read ? checkExternalFiles(c, why) : p;
}

}  // namespace upd::mrpt_bridge::detail
