// A source or a base that stops: `upd live` must notice a device that delivers no frame, or delivers the
// same frame again and again (the same device stamp), and stop the robot.
//
// SourceWatchdog measures the time since the last NEW frame (a stamp it has not seen; a frame
// without a stamp counts as new) on a clock the caller gives, and expires after timeout_s.
// nextFreshFrame() polls a LiveSource until a new frame comes, the recording ends or the
// watchdog expires; on expiry it tells the base to stop (RobotBase::stop, emergency) and
// returns Stalled with what happened, so that the caller logs one line and records it.
//
// readBaseState() reads the robot base once per frame; a base that stops answering (a call
// returns false: RosRobotBase's odometry older than odom_timeout_s, a driver that times out) is
// told to stop (emergency) and the run ends with BaseFault's line.
#pragma once

#include "live_source.h"

#include <atomic>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>

namespace upd::nav {
class RobotBase;
struct BaseState;
}

namespace upd::app {

class SourceWatchdog {
 public:
  /// Throws std::invalid_argument for timeout_s <= 0.
  SourceWatchdog(double timeout_s, double start_s);
  /// A frame with the device stamp stamp_s arrived at now_s; true when it is new.
  bool frame(double now_s, double stamp_s);
  bool expired(double now_s) const { return now_s - last_new_s_ > timeout_s_; }
  double timeoutS() const { return timeout_s_; }
  double lastNewS() const { return last_new_s_; }
  std::size_t newFrames() const { return new_frames_; }
  std::size_t staleFrames() const { return stale_frames_; }

 private:
  double timeout_s_;
  double last_new_s_;
  double last_stamp_s_;
  bool has_stamp_ = false;
  std::size_t new_frames_ = 0, stale_frames_ = 0;
};

/// What the watchdog saw when the source stopped.
struct SourceStall {
  double at_s = 0;            ///< when it was detected (the caller's clock) [s]
  double silent_s = 0;        ///< since the last new frame [s]
  std::size_t new_frames = 0;   ///< new frames before it
  std::size_t stale_frames = 0; ///< repeated frames (same stamp) in the whole run
  bool robot_stopped = false;   ///< RobotBase::stop succeeded
  /// "the source stopped: no new frame for 1.02 s (after 37 frames, 12 repeated); robot stopped"
  std::string line() const;
};

enum class NextFrame { Fresh, End, Stalled, Interrupted };

/// Polls source until a new frame (Fresh: frame holds it), the end of a recording (End), stop
/// becoming true (Interrupted), or the watchdog expiring (Stalled: base.stop(true) was called
/// and stall says what happened). now_s is the clock the watchdog runs on [s].
NextFrame nextFreshFrame(LiveSource& source, SourceWatchdog& watchdog, nav::RobotBase& base,
                         const std::function<double()>& now_s, const std::function<bool()>& stop,
                         LiveFrame& frame, SourceStall& stall);

/// A robot base that stopped answering.
struct BaseFault {
  std::string reason;        ///< RobotBase::lastError() ("" when the base gives none)
  std::size_t frames = 0;    ///< frames processed before it
  bool robot_stopped = false;  ///< the emergency stop sent after it was acknowledged
  /// "the robot base stopped answering after 37 frames: odometry on /odom is stale (...);
  /// emergency stop sent"
  std::string line() const;
};

/// base.readState(state); when it fails, base.stop(true) and the fault (frames: processed so far).
std::optional<BaseFault> readBaseState(nav::RobotBase& base, std::size_t frames,
                                       nav::BaseState& state);

}  // namespace upd::app
