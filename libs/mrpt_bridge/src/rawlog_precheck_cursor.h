// The reading side of the rawlog pre-check (private to the bridge): a cursor over the bytes ahead
// of a LookaheadStream that reads MRPT 2.5.8's serialized values without consuming them, and the
// checks of the objects a rawlog holds. Each check walks an object as MRPT's serializeFrom() reads
// it, stops with Parse::Impossible and a reason naming the field, its value and its byte where MRPT
// would allocate or read what no sensor produces, and with Parse::OtherLayout where the bytes
// follow a layout it does not know (MRPT then reports what it finds).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>

#include "rawlog_precheck.h"

namespace upd::mrpt_bridge::detail {

enum class Parse { Read, Impossible, OtherLayout };

/// Reads ahead of the stream's position: little-endian values (MRPT's byte
/// order on disk), as MRPT's CArchive would read them next, without consuming
/// them.
class Cursor {
 public:
  explicit Cursor(LookaheadStream& in) : in_(in), base_(in.getPosition()) {}

  bool bytes(void* out, std::size_t n) {
    if (!in_.peek(offset_, out, n)) {
      ran_out_ = true;
      return false;
    }
    offset_ += n;
    return true;
  }
  /// true when at least n bytes follow the position (reads no more than the stream holds: a
  /// corrupt size near the end of a file is not allocated ahead of its bytes).
  bool has(std::uint64_t n) {
    std::uint8_t last = 0;
    if (n == 0 || in_.peek(offset_ + static_cast<std::size_t>(n - 1), &last, 1)) return true;
    ran_out_ = true;
    return false;
  }
  template <typename T>
  bool value(T& v) {
    static_assert(std::is_integral_v<T> && sizeof(T) <= 8);
    std::uint8_t b[sizeof(T)];
    if (!bytes(b, sizeof b)) return false;
    std::uint64_t u = 0;
    for (std::size_t i = sizeof(T); i-- > 0;) u = (u << 8) | b[i];
    std::memcpy(&v, &u, sizeof v);  // little-endian host, as MRPT assumes
    return true;
  }
  /// Fields whose values are not checked: skipped (a read after them fails at
  /// the end).
  void skip(std::uint64_t n) { offset_ += static_cast<std::size_t>(n); }
  /// The byte of the decompressed stream the next value is at.
  std::uint64_t position() const { return base_ + offset_; }
  /// Bytes walked since the cursor was made.
  std::size_t walked() const { return offset_; }
  /// true once a read ran past the end of the stream.
  bool ranOut() const { return ran_out_; }
  /// The byte the cursor started at.
  std::uint64_t start() const { return base_; }
  /// Back to that byte, to walk the same bytes again another way.
  void restart() {
    offset_ = 0;
    ran_out_ = false;
  }
  bool endFlag() {
    std::uint8_t f = 0;
    return value(f) && f == 0x88;  // MRPT's SERIALIZATION_END_FLAG after each object
  }

 private:
  LookaheadStream& in_;
  std::uint64_t base_;
  std::size_t offset_ = 0;
  bool ran_out_ = false;
};

struct ObjectHeader {
  std::string class_name;  ///< without a namespace
  std::string full_name;   ///< as written (MRPT looks the class up by it)
  int version = -1;
  bool has_end_flag = true;  ///< false in the format before MRPT 0.5.5
};

/// CArchive::internal_ReadObjectHeader's layout; false where MRPT would refuse
/// it.
bool readHeader(Cursor& c, ObjectHeader& h);

/// A bool, which MRPT reads as a raw byte into the bool: a byte other than 0 or 1 (MRPT writes no
/// other) is an impossible bool to whatever reads it. Impossible, with `why` naming the field, its
/// value and its byte, for any other.
inline Parse checkFlag(Cursor& c, const char* field, std::uint8_t& v, std::string& why) {
  const std::uint64_t at = c.position();
  if (!c.value(v)) return Parse::OtherLayout;
  if (v <= 1) return Parse::Read;
  why = std::string(field) + " flag " + std::to_string(v) + " at byte " + std::to_string(at) +
        " (a flag is 0 or 1)";
  return Parse::Impossible;
}

/// A count or size read from the stream at byte `at`, checked against its
/// bound: false, with `why` naming the field ("scan size 4294967295 at byte
/// 1234 (more than 1000000 rays)"), when it exceeds it.
bool withinBound(const char* field, std::uint64_t value, std::uint64_t at, std::uint64_t max,
                 const char* unit, std::string& why);

/// An observation object whose header has been read (of a class in the walks' table of
/// rawlog_precheck_observations.cpp; any other is OtherLayout), up to and including its end flag.
Parse checkObservation(Cursor& c, const ObjectHeader& h, std::string& why);

/// A part of an observation stored as an object of its own (a CImage, TCamera, CMatrix, CMatrixF,
/// CMatrixD, CPose3D, CPose3DQuat, CPose2D or points map), header to end flag, as the
/// observations' walks read it; OtherLayout for any other class.
Parse checkPart(Cursor& c, const std::string& class_name, std::string& why);

/// A CPose3D (versions 0-3), CPose3DQuat or CPose2D object, header to end flag.
Parse checkPose(Cursor& c, std::string& why);

/// A std::string: its 32-bit length (bounded by max_bytes: false, with why, past it), then its
/// bytes.
Parse checkString(Cursor& c, const char* field, std::string& why,
                  std::uint32_t max_bytes = kMaxStringBytes);

/// Rows and columns of an image or matrix (32 bits each), each side and their product bounded as
/// an image's ("<field> rows 70000 at byte ... (more than 65535 rows)").
Parse checkSides(Cursor& c, const char* field, std::uint64_t& rows, std::uint64_t& cols,
                 std::string& why);

/// A list MRPT resizes to the 32-bit count before it, then reads: the count bounded by max (false,
/// with why naming field and unit, past it), the elements of element_bytes each skipped.
Parse checkList(Cursor& c, const char* field, std::size_t element_bytes, std::uint64_t max,
                const char* unit, std::string& why);

/// A CObservation3DRangeScan's pixel labels (TPixelLabelInfo), after their flag.
Parse checkPixelLabels(Cursor& c, std::string& why);

/// A CObservationVelodyneScan's body (versions 0-2; any other is OtherLayout), after its header.
Parse checkVelodyneScan(Cursor& c, int version, std::string& why);

/// A CObservationRotatingScan's body (version 0; any other is OtherLayout), after its header.
Parse checkRotatingScan(Cursor& c, int version, std::string& why);

/// A CObservationBatteryState's body (version 2; any other is OtherLayout), after its header.
Parse checkBatteryState(Cursor& c, int version, std::string& why);

/// A CObservationRGBD360's body (version 1; any other is OtherLayout), after its header.
Parse checkRgbd360(Cursor& c, int version, std::string& why);

/// The flags and file names of points and range images stored outside the rawlog, which a
/// CObservation3DRangeScan (from version 3) and a CObservationRGBD360 end with.
Parse checkExternalFiles(Cursor& c, std::string& why);

/// The `count` messages of a CObservationGPS (its messages follow its message count).
Parse checkGnssMessages(Cursor& c, std::uint32_t count, std::string& why);

}  // namespace upd::mrpt_bridge::detail
