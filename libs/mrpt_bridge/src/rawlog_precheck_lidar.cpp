// A CObservationVelodyneScan, walked as MRPT 2.5.8's serializeFrom() reads versions 0-2: the
// timestamp, the label, the range limits, the sensor pose; the raw packets and the calibration's
// per-laser corrections, each a count MRPT resizes to and then that many fixed records; the point
// cloud's x, y, z and intensity lists; from version 1 whether the timestamp is the satellites';
// from version 2 the points' timestamps (a list written with its container and element type
// names), azimuths and laser IDs, and the points of each laser (a list of lists, named the same
// way).
#include "rawlog_precheck_cursor.h"

#include <mrpt/obs/CObservationVelodyneScan.h>

namespace upd::mrpt_bridge::detail {
namespace {

constexpr Parse kRead = Parse::Read;
constexpr Parse kOther = Parse::OtherLayout;
constexpr Parse kImpossible = Parse::Impossible;

// The container and element type names MRPT writes before a list it serializes generically.
Parse typeNames(Cursor& c, std::string& why) {
  const Parse p = checkString(c, "container name length", why);
  return p == kRead ? checkString(c, "element type name length", why) : p;
}

}  // namespace

Parse checkVelodyneScan(Cursor& c, int version, std::string& why) {
  using Scan = mrpt::obs::CObservationVelodyneScan;
  if (version > 2) return kOther;
  c.skip(sizeof(std::uint64_t));
  Parse p = checkString(c, "sensor label length", why);
  if (p != kRead) return p;
  c.skip(2 * sizeof(double));
  if ((p = checkPose(c, why)) != kRead) return p;
  if ((p = checkList(c, "packet count", sizeof(Scan::TVelodyneRawPacket), kMaxLidarPackets,
                     "packets", why)) != kRead ||
      (p = checkList(c, "laser count", sizeof(mrpt::obs::VelodyneCalibration::PerLaserCalib),
                     kMaxLidarLasers, "lasers", why)) != kRead) {
    return p;
  }
  static const struct {
    const char* field;
    std::size_t bytes;
  } kPoints[] = {{"point x count", sizeof(float)},
                 {"point y count", sizeof(float)},
                 {"point z count", sizeof(float)},
                 {"point intensity count", sizeof(std::uint8_t)}};
  for (const auto& f : kPoints) {
    if ((p = checkList(c, f.field, f.bytes, kMaxImagePixels, "points", why)) != kRead) return p;
  }
  std::uint8_t satellite_time = 0;
  if (version >= 1 && (p = checkFlag(c, "satellite timestamp", satellite_time, why)) != kRead) {
    return p;
  }
  if (version < 2) return kRead;
  if ((p = typeNames(c, why)) != kRead ||
      (p = checkList(c, "point timestamp count", sizeof(std::uint64_t), kMaxImagePixels,
                     "points", why)) != kRead ||
      (p = checkList(c, "point azimuth count", sizeof(float), kMaxImagePixels, "points",
                     why)) != kRead ||
      (p = checkList(c, "point laser ID count", sizeof(std::int16_t), kMaxImagePixels, "points",
                     why)) != kRead ||
      (p = typeNames(c, why)) != kRead) {
    return p;
  }
  const std::uint64_t at = c.position();
  std::uint32_t lasers = 0;
  if (!c.value(lasers)) return kOther;
  if (!withinBound("points-per-laser list count", lasers, at, kMaxLidarLasers, "lasers", why)) {
    return kImpossible;
  }
  for (std::uint32_t i = 0; i < lasers && p == kRead; ++i) {
    p = checkList(c, "laser point count", sizeof(std::uint64_t), kMaxImagePixels, "points", why);
  }
  return p;
}

}  // namespace upd::mrpt_bridge::detail
