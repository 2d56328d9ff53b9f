// A device that stops: a source that delivers nothing, or the same frame again and again, is
// detected within the stale timeout (on the clock the loop gives, here a simulated one) and the
// simulated base is stopped.
#include "live_watchdog.h"

#include "upd/nav/robot_base.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

using upd::app::LiveFrame;
using upd::app::NextFrame;
using upd::app::Poll;

// Delivers `fresh` frames with stamps 1, 2, ..., then `after` forever; every poll takes dt_s on
// the simulated clock.
class FakeSource : public upd::app::LiveSource {
 public:
  enum class After { Nothing, SameStamp, End };
  FakeSource(int fresh, After after, double& clock_s, double dt_s = 0.05)
      : fresh_(fresh), after_(after), clock_s_(clock_s), dt_s_(dt_s) {}
  Poll poll(LiveFrame& f) override {
    clock_s_ += dt_s_;
    ++polls;
    if (sent_ < fresh_) {
      f.stamp_s = ++sent_;
      return Poll::Frame;
    }
    switch (after_) {
      case After::Nothing:
        return Poll::Nothing;
      case After::SameStamp:
        f.stamp_s = sent_;
        return Poll::Frame;
      case After::End:
        return Poll::End;
    }
    return Poll::Nothing;
  }
  std::string description() const override { return "fake"; }
  int polls = 0;

 private:
  int fresh_, sent_ = 0;
  After after_;
  double& clock_s_;
  double dt_s_;
};

struct Pulled {
  NextFrame last = NextFrame::Fresh;
  int fresh = 0;
  upd::app::SourceStall stall;
};

// Pulls frames as the live loop does until something other than a fresh frame comes.
Pulled pull(upd::app::LiveSource& source, double& clock_s, upd::nav::RobotBase& base,
         double timeout_s) {
  upd::app::SourceWatchdog watchdog(timeout_s, clock_s);
  const std::function<bool()> stop = [] { return false; };
  Pulled r;
  LiveFrame f;
  for (int i = 0; i < 1000; ++i) {
    r.last = upd::app::nextFreshFrame(source, watchdog, base, [&] { return clock_s; }, stop, f,
                                      r.stall);
    if (r.last != NextFrame::Fresh) break;
    ++r.fresh;
  }
  return r;
}

}  // namespace

TEST(LiveWatchdog, RepeatedFramesStopTheRobotWithinTheTimeout) {
  double clock_s = 0;
  FakeSource source(5, FakeSource::After::SameStamp, clock_s, 0.125);  // exact in binary
  upd::nav::SimulatedDiffDrive base({});
  base.sendVelocity({0.3, 0.2});
  base.advance(0.5);
  const Pulled r = pull(source, clock_s, base, 1.0);
  EXPECT_EQ(r.last, NextFrame::Stalled);
  EXPECT_EQ(r.fresh, 5);
  // Detected at the first poll past the timeout (one poll = 0.125 s).
  EXPECT_EQ(r.stall.silent_s, 1.125);
  EXPECT_EQ(r.stall.new_frames, 5u);
  EXPECT_EQ(r.stall.stale_frames, 9u);  // the polls after the last new frame
  EXPECT_TRUE(r.stall.robot_stopped);
  EXPECT_EQ(base.lastCommand().v_mps, 0.0);
  EXPECT_EQ(base.lastCommand().w_radps, 0.0);
  EXPECT_NE(r.stall.line().find("(after 5 frames, 9 repeated); robot stopped"),
            std::string::npos)
      << r.stall.line();
}

TEST(LiveWatchdog, ASilentSourceStopsTheRobot) {
  double clock_s = 10;
  FakeSource source(0, FakeSource::After::Nothing, clock_s, 0.1);
  upd::nav::SimulatedDiffDrive base({});
  base.sendVelocity({0.3, 0});
  const Pulled r = pull(source, clock_s, base, 0.5);
  EXPECT_EQ(r.last, NextFrame::Stalled);
  EXPECT_NEAR(r.stall.silent_s, 0.6, 1e-9);
  EXPECT_EQ(base.lastCommand().v_mps, 0.0);
}

TEST(LiveWatchdog, TheEndOfARecordingIsNotAStall) {
  double clock_s = 0;
  FakeSource source(3, FakeSource::After::End, clock_s);
  upd::nav::SimulatedDiffDrive base({});
  base.sendVelocity({0.3, 0});
  const Pulled r = pull(source, clock_s, base, 1.0);
  EXPECT_EQ(r.last, NextFrame::End);
  EXPECT_EQ(r.fresh, 3);
  EXPECT_EQ(base.lastCommand().v_mps, 0.3);  // the loop's own finish() stops it, not the watchdog
}

TEST(LiveWatchdog, FramesWithoutStampsAreAlwaysNew) {
  upd::app::SourceWatchdog w(1.0, 0.0);
  const double nan = std::nan("");
  EXPECT_TRUE(w.frame(0.1, nan));
  EXPECT_TRUE(w.frame(0.2, nan));
  EXPECT_TRUE(w.frame(0.3, 5.0));
  EXPECT_FALSE(w.frame(0.4, 5.0));
  EXPECT_TRUE(w.frame(0.5, 6.0));
  EXPECT_FALSE(w.expired(1.5));
  EXPECT_TRUE(w.expired(1.51));
  EXPECT_THROW(upd::app::SourceWatchdog(0.0, 0.0), std::invalid_argument);
}

namespace {

// A base that answers `answers` readState calls, then stops answering (as RosRobotBase does
// when its odometry is older than odom_timeout_s); its stop may fail too.
class FakeBase : public upd::nav::RobotBase {
 public:
  FakeBase(int answers, std::string error, bool stop_works = true)
      : answers_(answers), error_(std::move(error)), stop_works_(stop_works) {}
  bool readState(upd::nav::BaseState& s) override {
    if (reads_ >= answers_) return false;
    s.pose_world_robot.x_m = ++reads_;
    return true;
  }
  bool sendVelocity(const upd::nav::Twist2D&) override { return reads_ < answers_; }
  bool stop(bool emergency) override {
    ++stops;
    emergency_stop = emergency;
    return stop_works_;
  }
  double timeS() const override { return 0.0; }
  std::string lastError() const override { return reads_ < answers_ ? "" : error_; }
  int stops = 0;
  bool emergency_stop = false;

 private:
  int answers_, reads_ = 0;
  std::string error_;
  bool stop_works_;
};

}  // namespace

TEST(LiveBaseFault, ABaseThatStopsAnsweringIsToldToStopWithTheReasonInOneLine) {
  FakeBase base(3, "odometry on /odom is stale (0.8 s old, limit 0.5 s)");
  upd::nav::BaseState s;
  for (std::size_t frame = 0; frame < 3; ++frame) {
    EXPECT_FALSE(upd::app::readBaseState(base, frame, s).has_value());
    EXPECT_EQ(s.pose_world_robot.x_m, frame + 1.0);
  }
  EXPECT_EQ(base.stops, 0);
  const auto fault = upd::app::readBaseState(base, 3, s);
  ASSERT_TRUE(fault.has_value());
  EXPECT_EQ(base.stops, 1);
  EXPECT_TRUE(base.emergency_stop);
  EXPECT_TRUE(fault->robot_stopped);
  EXPECT_EQ(fault->frames, 3u);
  EXPECT_EQ(fault->line(),
            "the robot base stopped answering after 3 frames: odometry on /odom is stale "
            "(0.8 s old, limit 0.5 s); emergency stop sent");
  EXPECT_EQ(fault->line().find('\n'), std::string::npos);
}

TEST(LiveBaseFault, ABaseWithoutAReasonOrAWorkingStopIsStillNamed) {
  FakeBase base(0, "", /*stop_works=*/false);
  upd::nav::BaseState s;
  const auto fault = upd::app::readBaseState(base, 0, s);
  ASSERT_TRUE(fault.has_value());
  EXPECT_FALSE(fault->robot_stopped);
  EXPECT_EQ(fault->line(), "the robot base stopped answering after 0 frames: it does not report "
                           "its pose; the emergency stop FAILED too");
}

// The source watchdog stops the base the run drives, whichever it is.
TEST(LiveBaseFault, AStalledSourceStopsTheBaseGiven) {
  double clock_s = 0;
  FakeSource source(2, FakeSource::After::Nothing, clock_s, 0.25);
  FakeBase base(100, "");
  const Pulled r = pull(source, clock_s, base, 1.0);
  EXPECT_EQ(r.last, NextFrame::Stalled);
  EXPECT_EQ(base.stops, 1);
  EXPECT_TRUE(base.emergency_stop);
}
