#include "live_watchdog.h"

#include "upd/nav/robot_base.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace upd::app {

SourceWatchdog::SourceWatchdog(double timeout_s, double start_s)
    : timeout_s_(timeout_s), last_new_s_(start_s), last_stamp_s_(0) {
  if (!(timeout_s > 0)) {
    throw std::invalid_argument("stale timeout = " + std::to_string(timeout_s) + " s: must be > 0");
  }
}

bool SourceWatchdog::frame(double now_s, double stamp_s) {
  const bool stamped = std::isfinite(stamp_s);
  if (stamped && has_stamp_ && stamp_s == last_stamp_s_) {
    ++stale_frames_;
    return false;
  }
  if (stamped) {
    last_stamp_s_ = stamp_s;
    has_stamp_ = true;
  }
  last_new_s_ = now_s;
  ++new_frames_;
  return true;
}

std::string SourceStall::line() const {
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "the source stopped: no new frame for %.2f s (after %zu frames, %zu repeated); %s",
                silent_s, new_frames, stale_frames,
                robot_stopped ? "robot stopped" : "stopping the robot FAILED");
  return buf;
}

NextFrame nextFreshFrame(LiveSource& source, SourceWatchdog& watchdog, nav::RobotBase& base,
                         const std::function<double()>& now_s, const std::function<bool()>& stop,
                         LiveFrame& frame, SourceStall& stall) {
  while (!stop()) {
    const Poll p = source.poll(frame);
    if (p == Poll::End) return NextFrame::End;
    const double now = now_s();
    if (p == Poll::Frame && watchdog.frame(now, frame.stamp_s)) return NextFrame::Fresh;
    if (watchdog.expired(now)) {
      stall.at_s = now;
      stall.silent_s = now - watchdog.lastNewS();
      stall.new_frames = watchdog.newFrames();
      stall.stale_frames = watchdog.staleFrames();
      stall.robot_stopped = base.stop(true);
      return NextFrame::Stalled;
    }
  }
  return NextFrame::Interrupted;
}

std::string BaseFault::line() const {
  return "the robot base stopped answering after " + std::to_string(frames) + " frames: " +
         (reason.empty() ? std::string("it does not report its pose") : reason) + "; " +
         (robot_stopped ? "emergency stop sent" : "the emergency stop FAILED too");
}

std::optional<BaseFault> readBaseState(nav::RobotBase& base, std::size_t frames,
                                       nav::BaseState& state) {
  if (base.readState(state)) return std::nullopt;
  BaseFault fault;
  fault.reason = base.lastError();
  fault.frames = frames;
  fault.robot_stopped = base.stop(true);
  return fault;
}

}  // namespace upd::app
