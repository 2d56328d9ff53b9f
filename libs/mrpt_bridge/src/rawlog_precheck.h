// Checks of the serialized fields that MRPT 2.5 acts on while it deserializes an object, made on
// the bytes ahead in the stream before MRPT reads them (private to the bridge).
//
// MRPT trusts the sizes it reads. CActionRobotMovement2D rebuilds its pose distribution inside
// its deserialization: with any motion model but the Gaussian one it draws as many particles as
// the stream says, so a corrupt count of 10^9 keeps a playback busy for minutes and gigabytes
// before the object ends. CActionCollection resizes its list of actions to the count it reads.
// The observations resize their buffers to the sizes they read: a CObservation2DRangeScan's
// corrupt scan size makes MRPT allocate 4.3 GB per vector (its aligned allocator returns null
// when that fails, and MRPT then writes through it), a CImage's JPEG size of 2^32 - 1 makes it
// allocate and zero 4 GiB.
// precheckNextObject() reads those fields of the next top-level object (a CActionCollection and
// the CActionRobotMovement2D actions in it, or a bare CActionRobotMovement2D; a CSensoryFrame
// and the observations in it, or a bare observation: 2D and 3D range scans, images, stereo
// images, with the poses, cameras, images and matrices inside them) as MRPT 2.5.8 lays them
// out (CArchive's object header: a length byte with its high bit set, the class name, a version
// byte; the body; the end flag 0x88), and names what is impossible. Bytes that follow another
// layout are left to MRPT, which reports what it finds.
#pragma once

#include <mrpt/io/CStream.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace upd::mrpt_bridge::detail {

/// Most particles a CActionRobotMovement2D may ask MRPT to draw (MRPT's default is 300; a
/// particle costs ~40 bytes and a few Gaussian draws: 10^5 take milliseconds).
constexpr std::uint32_t kMaxOdometryParticles = 100000;
/// Most particles or Gaussian modes of a scan-matching action's pose distribution
/// (CPosePDFParticles, CPosePDFSOG): MRPT allocates them all before reading the first.
constexpr std::uint32_t kMaxPosePdfElements = 100000;
/// Most cells of a CPosePDFGrid (2^24 doubles, 128 MiB).
constexpr std::uint64_t kMaxPoseGridCells = std::uint64_t{1} << 24;
/// Most velocity components of a CActionRobotMovement3D (MRPT writes 6: x y z yaw pitch roll, and
/// a flag for each).
constexpr std::uint32_t kMaxVelocityComponents = 6;
/// Most actions in one CActionCollection (a robot writes one or two per step).
constexpr std::uint32_t kMaxActionsPerCollection = 4096;
/// Most observations in one CSensoryFrame (a robot writes one per sensor and step).
constexpr std::uint32_t kMaxObservationsPerFrame = 4096;
/// Most rays in a CObservation2DRangeScan (a laser scanner gives a few thousand; MRPT allocates
/// 9 bytes a ray).
constexpr std::uint32_t kMaxScanRays = 1000000;
/// Most pixels of an image, range image, matrix or 3D point list (2^24: 4096 x 4096; a depth
/// camera gives 1-2 M), and most pixels along one side.
constexpr std::uint64_t kMaxImagePixels = std::uint64_t{1} << 24;
constexpr std::uint32_t kMaxImageSide = 65535;
/// Most bytes of a compressed (JPEG) image in a CImage.
constexpr std::uint32_t kMaxEncodedImageBytes = 1u << 28;
/// Most bytes of a string (a sensor label, a camera name, an external file name).
constexpr std::uint32_t kMaxStringBytes = 1u << 16;
/// Most measurements of a CObservationRange (a ring of sonars or infrared rangers gives tens).
constexpr std::uint32_t kMaxRangeMeasurements = 65536;
/// Most messages of a CObservationGPS (MRPT keeps one of each message type).
constexpr std::uint32_t kMaxGnssMessages = 1024;
/// Most bytes of a Novatel frame a CObservationGPS keeps whole (the receiver's own length field
/// has 16 bits).
constexpr std::uint32_t kMaxGnssFrameBytes = 1u << 16;
/// Most satellites in one of a Topcon SATS message's lists (a receiver tracks tens).
constexpr std::uint32_t kMaxGnssSatellites = 4096;
/// Most raw packets in one Velodyne scan (a turn of a 64-laser sensor at 5 Hz takes ~700).
constexpr std::uint32_t kMaxLidarPackets = 65536;
/// Most lasers in a Velodyne calibration or point cloud (sensors have 16 to 128).
constexpr std::uint32_t kMaxLidarLasers = 4096;
/// Most label names of a 3D scan's pixel labels (a bit field of 8 bytes names at most 64).
constexpr std::uint32_t kMaxLabelNames = 65536;
/// Most range layers of a rotating LiDAR's scan besides its range image (a sensor gives one or two,
/// each of the range image's size).
constexpr std::uint32_t kMaxRangeLayers = 256;
/// Most batteries of a CObservationBatteryState besides the main one and the computer's.
constexpr std::uint32_t kMaxBatteries = 4096;
/// Most bytes of a CObservationComment's text (a note, a configuration block).
constexpr std::uint32_t kMaxCommentBytes = 1u << 24;

/// A read-only stream over another that can look at the bytes ahead of its position without
/// consuming them. Its position is the count of bytes consumed (the underlying stream's
/// position less the bytes looked at and not yet read).
class LookaheadStream : public mrpt::io::CStream {
 public:
  explicit LookaheadStream(mrpt::io::CStream& in) : in_(in) {}

  size_t Read(void* buffer, size_t count) override;
  /// Throws: the stream is read-only.
  size_t Write(const void* buffer, size_t count) override;
  /// Throws: the stream reads forward only.
  uint64_t Seek(int64_t offset, TSeekOrigin origin = sFromBeginning) override;
  uint64_t getTotalBytesCount() const override;
  uint64_t getPosition() const override;

  /// Copies count bytes, starting offset bytes after the position, into out; false when the
  /// stream ends before them.
  bool peek(std::size_t offset, void* out, std::size_t count);
  /// The stream's length once a peek has run past its end (in the position's bytes), else none.
  std::optional<std::uint64_t> knownEnd() const { return end_; }

 private:
  mrpt::io::CStream& in_;
  std::vector<std::uint8_t> ahead_;  ///< bytes read from in_, not consumed from head_ on
  std::size_t head_ = 0;
  std::optional<std::uint64_t> end_;
};

/// The reason for an object the file ends inside, at byte `end` (MRPT's CArchive takes a short read
/// as data: such an object is damage before MRPT reads it).
std::string truncatedAt(std::uint64_t end);

/// Why the next top-level object must not be handed to MRPT ("corrupt CObservation2DRangeScan
/// (observation 1 of 1 in a CSensoryFrame): scan size 4294967295 at byte 1234 (more than
/// 1000000 rays)"), or "" when nothing impossible was found. Consumes nothing. checked_bytes,
/// when given, is set to the object's length when every field of it was walked (its layout is
/// one the checks know, to its end flag), 0 when the checks stopped before its end.
std::string precheckNextObject(LookaheadStream& in, std::size_t* checked_bytes = nullptr);

/// The head of a container the reader hands to MRPT one element at a time, so that each element
/// is checked at its own start (the walk of the whole container stops at the first element of a
/// layout it does not know): a CSensoryFrame (versions 0-2) or a CActionCollection (version 0).
struct ContainerHead {
  bool frame = false;  ///< a CSensoryFrame; else a CActionCollection
  int version = 0;
  bool has_end_flag = true;
  std::uint32_t count = 0;     ///< elements (checked by precheckContainerHead)
  std::int64_t timestamp = 0;  ///< a version-0 frame's, which MRPT sets on every observation
  std::size_t bytes = 0;       ///< from the object's first byte to its first element
};

/// true, with its head, when the next object is such a container. Consumes nothing.
bool peekContainerHead(LookaheadStream& in, ContainerHead& head);

/// Why the head of the container at the stream's position is impossible (its element count past
/// its bound, as precheckNextObject names it), or "". Its elements are checked one at a time by
/// precheckNextElement.
std::string precheckContainerHead(LookaheadStream& in, const ContainerHead& head);

/// As precheckNextObject, for element `index` (0-based) of the container `head` at the stream's
/// position, with the container walk's reasons ("corrupt CObservationPointCloud (observation 4 of
/// 8 in a CSensoryFrame): point count ...", "corrupt CActionCollection: action 2 of 2 is a
/// null object").
std::string precheckNextElement(LookaheadStream& in, const ContainerHead& head,
                                std::uint32_t index);

}  // namespace upd::mrpt_bridge::detail
