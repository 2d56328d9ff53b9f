// Writes a run's observations as an MRPT rawlog while the run goes on (the observation-only
// layout: one serialized CObservation per object, gzip-compressed), which rawlog-edit,
// RawLogViewer and `upd playback` read.
//
// write() serializes the observation and hands it to a writer thread of its own, which
// compresses it (~5 ms for a 640 x 480 depth frame) while the caller goes on: the loop of
// `upd live` does not wait for zlib. Up to 128 MB of observations wait for the writer; beyond
// that write() waits (none is dropped). The file is byte for byte what writing each object to
// CFileGZOutputStream in the caller's thread gives (zlib's gz calls as it makes them), but a
// member whose close fails (its last data not written: a full disk) is an error, where MRPT's
// stream says nothing.
//
// Crash safety: the objects go to `<path>.part`; every flush_every observations the gzip member
// is closed and a new one appended (a gzip file may hold several members, read as one stream),
// so the .part file on disk is a complete, replayable rawlog up to the writer's last flush (what
// was still queued at a crash is lost: at sensor rate the writer keeps up, so that is the frame
// being compressed or none). finish() closes it and renames it to path: a file at path is
// always whole. After a crash the .part file stays; `upd playback RUN.rawlog.part` replays it up to the last flush (what follows,
// if cut, is reported as damage and the frames before it are kept).
#pragma once

#include <cstddef>
#include <memory>
#include <string>

namespace mrpt::obs {
class CObservation;
}

namespace upd::mrpt_bridge {

class RawlogWriter {
 public:
  /// Opens `<path>.part` (truncated). Throws std::runtime_error naming it when it cannot be
  /// written, std::invalid_argument for flush_every < 1.
  explicit RawlogWriter(const std::string& path, int flush_every = 10);
  /// Without finish() (an error unwinding), what is queued is written, the .part file closed
  /// and left in place.
  ~RawlogWriter();
  RawlogWriter(const RawlogWriter&) = delete;
  RawlogWriter& operator=(const RawlogWriter&) = delete;

  /// Queues obs (serialized now: the caller may change it after). Throws std::runtime_error
  /// naming the .part file when the writer thread failed to write an earlier one.
  void write(const mrpt::obs::CObservation& obs);
  /// A CObservationOdometry: the robot's planar odometry pose at time_s [s since the UNIX
  /// epoch] (what `upd playback` takes as the robot pose of the observations after it).
  void writeOdometry(double x_m, double y_m, double yaw_rad, double time_s);
  /// Waits until the writer thread has written every observation queued (the file on disk
  /// then holds all of them up to the last flush). Throws as write() does.
  void drain();
  /// Writes what is queued, closes the file and renames `<path>.part` to path. Throws
  /// std::runtime_error naming the .part file (left in place) when it could not be written.
  void finish();

  /// The observations handed to write().
  std::size_t written() const { return written_; }
  /// The observations in the file's complete members: those a reader of the .part file gets
  /// (after a failure too); after finish(), all.
  std::size_t saved() const;
  const std::string& path() const { return path_; }
  std::string partPath() const { return path_ + ".part"; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string path_;
  int flush_every_;
  std::size_t written_ = 0;
};

}  // namespace upd::mrpt_bridge
