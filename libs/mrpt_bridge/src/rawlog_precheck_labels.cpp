// A CObservation3DRangeScan's pixel labels, walked as MRPT 2.5.8's
// TPixelLabelInfoBase::readAndBuildFromStream() reads them: its version (1), the bytes of a label
// bit field (1-8: labels of 1, 2, 4 or 8 bytes), the rows and columns of the label matrix, which
// MRPT resizes to them, the labels; then the label names, a map written with its container, key and
// value type names and a count of index and name pairs.
#include "rawlog_precheck_cursor.h"

namespace upd::mrpt_bridge::detail {

Parse checkPixelLabels(Cursor& c, std::string& why) {
  std::uint8_t version = 0, field_bytes = 0;
  if (!c.value(version) || version != 1 || !c.value(field_bytes)) return Parse::OtherLayout;
  if (field_bytes < 1 || field_bytes > 8) return Parse::OtherLayout;  // MRPT refuses it
  static constexpr std::uint8_t kLabelBytes[9] = {0, 1, 2, 4, 4, 8, 8, 8, 8};
  std::uint64_t rows = 0, cols = 0;
  Parse p = checkSides(c, "pixel label", rows, cols, why);
  if (p != Parse::Read) return p;
  c.skip(rows * cols * kLabelBytes[field_bytes]);
  for (const char* field : {"label map container name length", "label map key type name length",
                            "label map value type name length"}) {
    if ((p = checkString(c, field, why)) != Parse::Read) return p;
  }
  const std::uint64_t names_at = c.position();
  std::uint32_t names = 0;
  if (!c.value(names)) return Parse::OtherLayout;
  if (!withinBound("label name count", names, names_at, kMaxLabelNames, "names", why)) {
    return Parse::Impossible;
  }
  for (std::uint32_t i = 0; i < names && p == Parse::Read; ++i) {
    c.skip(sizeof(std::uint32_t));  // the label's index
    p = checkString(c, "label name length", why);
  }
  return p;
}

}  // namespace upd::mrpt_bridge::detail
