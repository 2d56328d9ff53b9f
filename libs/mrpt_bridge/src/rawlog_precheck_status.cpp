// A rotating LiDAR's range images and a robot's battery state, walked as MRPT 2.5.8's
// serializeFrom() reads them. Both keep their sizes in MRPT's dynamic matrices and vectors, whose
// aligned allocator returns null on a size it cannot give (MRPT then writes through it): each size
// is bounded before MRPT reads the object.
#include "rawlog_precheck_cursor.h"

namespace upd::mrpt_bridge::detail {

namespace {

// A matrix's columns and rows (16 bits each), their product bounded as an image's pixels.
Parse sides16(Cursor& c, const char* field, std::uint64_t& rows, std::uint64_t& cols,
              std::string& why) {
  const std::uint64_t at = c.position();
  std::uint16_t k = 0, r = 0;
  if (!c.value(k) || !c.value(r)) return Parse::OtherLayout;
  rows = r;
  cols = k;
  return withinBound(field, rows * cols, at, kMaxImagePixels, "pixels", why) ? Parse::Read
                                                                            : Parse::Impossible;
}

}  // namespace

// CObservationRotatingScan, version 0: timestamp, label, row and column counts, four doubles
// (range resolution, start azimuth, azimuth span, sweep duration), the LiDAR model's name, the
// minimum and maximum range, the sensor pose, the original timestamp, the satellite timestamp
// flag; then the range image (16-bit ranges) and the intensity image (bytes), each after its
// columns and rows, and the count of other range layers, each a name and a matrix of the range
// image's size.
Parse checkRotatingScan(Cursor& c, int version, std::string& why) {
  if (version != 0) return Parse::OtherLayout;
  c.skip(sizeof(std::uint64_t));
  Parse p = checkString(c, "sensor label length", why);
  if (p != Parse::Read) return p;
  c.skip(2 * sizeof(std::uint16_t) + 4 * sizeof(double));
  if ((p = checkString(c, "LiDAR model name length", why)) != Parse::Read) return p;
  c.skip(2 * sizeof(double));
  if ((p = checkPose(c, why)) != Parse::Read) return p;
  c.skip(sizeof(std::uint64_t));
  std::uint8_t satellite = 0;
  if ((p = checkFlag(c, "satellite timestamp", satellite, why)) != Parse::Read) return p;
  std::uint64_t rows = 0, cols = 0, intensity_rows = 0, intensity_cols = 0;
  if ((p = sides16(c, "range image pixels", rows, cols, why)) != Parse::Read) return p;
  c.skip(rows * cols * sizeof(std::uint16_t));
  p = sides16(c, "intensity image pixels", intensity_rows, intensity_cols, why);
  if (p != Parse::Read) return p;
  c.skip(intensity_rows * intensity_cols);
  const std::uint64_t layers_at = c.position();
  std::uint16_t layers = 0;
  if (!c.value(layers)) return Parse::OtherLayout;
  if (!withinBound("range layer count", layers, layers_at, kMaxRangeLayers, "layers", why)) {
    return Parse::Impossible;
  }
  for (unsigned i = 0; i < layers; ++i) {
    if ((p = checkString(c, "range layer name length", why)) != Parse::Read) return p;
    c.skip(rows * cols * sizeof(std::uint16_t));
  }
  return Parse::Read;
}

// CObservationBatteryState, version 2: the main battery's and the computer's voltages, their two
// validity flags, the other batteries' voltages (a dynamic vector: its count, then doubles) and
// their validity (a count, then a byte each), the label, the timestamp.
Parse checkBatteryState(Cursor& c, int version, std::string& why) {
  if (version != 2) return Parse::OtherLayout;
  c.skip(2 * sizeof(double));
  std::uint8_t valid = 0;
  Parse p = checkFlag(c, "main battery valid", valid, why);
  if (p != Parse::Read || (p = checkFlag(c, "computer battery valid", valid, why)) != Parse::Read) {
    return p;
  }
  if ((p = checkList(c, "battery voltage count", sizeof(double), kMaxBatteries, "batteries",
                     why)) != Parse::Read ||
      (p = checkList(c, "battery validity count", 1, kMaxBatteries, "batteries", why)) !=
          Parse::Read ||
      (p = checkString(c, "sensor label length", why)) != Parse::Read) {
    return p;
  }
  c.skip(sizeof(std::uint64_t));
  return Parse::Read;
}

}  // namespace upd::mrpt_bridge::detail
