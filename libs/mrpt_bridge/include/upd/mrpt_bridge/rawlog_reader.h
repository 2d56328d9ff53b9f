// Streaming reader of MRPT rawlogs in both layouts, one observation at a time.
//
// A rawlog is a (usually gzip-compressed) MRPT archive of serialized objects. Two layouts exist:
// "actions + sensory frames" (CActionCollection, CSensoryFrame, CActionCollection, ...) and
// "observations only" (one CObservation per object). CRawlog::getActionObservationPairOrObservation
// silently drops a sensory frame that has no action before it, so this reader deserializes the
// objects one by one and dispatches on their type until the clean end of the file. Odometry
// actions read before an observation are composed into one increment and attached to the next
// observation (nothing is lost when a sensory frame is empty). Objects that carry nothing to
// yield are counted by reason in RawlogStats::skipped.
//
// Errors: a missing file throws one line naming it; a corrupt or truncated file throws
// RawlogError naming the file, the object index, its byte offset and what was read up to there
// (the observations yielded before it are intact). An odometry action whose motion model would
// make MRPT draw an impossible number of particles while reading it, or an action collection of
// an impossible count, is such damage too, found before MRPT reads the object. Externally
// stored images are found through CImage::setImagesPathBase(detectImagesDirectory(file)), which
// the constructor sets (MRPT keeps that path base process-wide: read one rawlog at a time).
#pragma once

#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

namespace mrpt::obs {
class CObservation;
}

namespace upd::mrpt_bridge {

/// Which layout the objects read so far follow.
enum class RawlogLayout {
  Empty,             ///< nothing read (yet)
  ActionsAndFrames,  ///< CActionCollection / CSensoryFrame objects only
  ObservationsOnly,  ///< top-level CObservation objects only
  Mixed,             ///< both kinds
};
const char* toString(RawlogLayout layout);

/// One observation of the file, in file order.
struct RawlogEntry {
  std::size_t index = 0;         ///< 0-based count of the observations yielded before this one
  std::size_t object_index = 0;  ///< 0-based index of the top-level object that held it
  /// Observation time [s since the UNIX epoch]; NaN when the observation is not stamped.
  double timestamp_s = std::numeric_limits<double>::quiet_NaN();
  std::shared_ptr<mrpt::obs::CObservation> observation;
  /// Robot motion since the previous entry (pose of the robot now, in the robot frame of the
  /// previous entry), composed from every odometry action read in between; empty when none.
  std::optional<Eigen::Isometry3d> odometry_increment;

  /// Short MRPT class name of the observation ("CObservation3DRangeScan"), "" when none.
  std::string className() const;
};

struct RawlogStats {
  std::size_t objects = 0;             ///< top-level objects deserialized
  std::size_t action_collections = 0;  ///< CActionCollection objects
  std::size_t sensory_frames = 0;      ///< CSensoryFrame objects
  std::size_t odometry_actions = 0;    ///< CActionRobotMovement2D/3D used for the increments
  std::size_t entries = 0;             ///< observations yielded
  std::map<std::string, std::size_t> entries_by_class;  ///< short class name -> observations
  std::map<std::string, std::size_t> skipped;           ///< reason -> objects not yielded

  std::size_t skippedTotal() const;
  /// One line: "450 objects (224 action collections, 225 sensory frames): 225 observations
  /// (225 CObservation2DRangeScan), 224 odometry actions; skipped: ..."
  std::string summary() const;
};

/// A rawlog that cannot be read to its end (corrupt, truncated, unknown class, ...). Every
/// object before objectIndex() was read intact: a caller may keep what it got from them.
class RawlogError : public std::runtime_error {
 public:
  RawlogError(const std::string& what, std::string path, std::size_t object_index,
              std::uint64_t byte_offset = 0, std::string reason = {})
      : std::runtime_error(what),
        path_(std::move(path)),
        object_index_(object_index),
        byte_offset_(byte_offset),
        reason_(std::move(reason)) {}
  const std::string& path() const { return path_; }
  /// 0-based index of the top-level object that could not be read.
  std::size_t objectIndex() const { return object_index_; }
  /// Where that object starts [bytes from the start of the decompressed stream; for a plain,
  /// uncompressed rawlog this is the file offset].
  std::uint64_t byteOffset() const { return byte_offset_; }
  /// Why it could not be read ("truncated, the file ends inside it (...)"), without the file
  /// and the counts that what() adds.
  const std::string& reason() const { return reason_; }

 private:
  std::string path_;
  std::size_t object_index_;
  std::uint64_t byte_offset_;
  std::string reason_;
};

class RawlogReader {
 public:
  /// Opens path (gzip or plain). Throws std::runtime_error("rawlog <path>: not found") when
  /// the file is missing, and a similar one-line error when it cannot be opened.
  explicit RawlogReader(const std::string& path);
  ~RawlogReader();
  RawlogReader(const RawlogReader&) = delete;
  RawlogReader& operator=(const RawlogReader&) = delete;

  /// Reads up to the next observation. Returns false at the clean end of the file (entry is
  /// left unchanged); throws RawlogError when the file is corrupt or truncated.
  bool next(RawlogEntry& entry);

  const RawlogStats& stats() const;
  RawlogLayout layout() const;
  const std::string& path() const;
  /// Where externally stored images are looked for (detectImagesDirectory()).
  const std::string& imagesDirectory() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Where MRPT's externally stored images of a rawlog live: the first existing directory of
/// "<dir>/<name>_Images", "_images", "_IMAGES", else "<dir>/Images" (MRPT's convention; MRPT
/// 2.5.8's own CRawlog::detectImagesDirectory drops the path separator).
std::string detectImagesDirectory(const std::string& rawlog_path);

/// Reads the whole file without keeping the observations and returns the counts (a quick
/// integrity check: throws like RawlogReader::next).
RawlogStats scanRawlog(const std::string& path);

}  // namespace upd::mrpt_bridge
