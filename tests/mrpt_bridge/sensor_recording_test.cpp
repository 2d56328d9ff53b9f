// RawlogWriter: the recording of `upd live`. A finished recording is a whole rawlog at its
// path, and while it is written (or after a crash) the .part file holds a readable rawlog up to
// the last flush.
#include "upd/mrpt_bridge/rawlog_reader.h"
#include "upd/mrpt_bridge/rawlog_writer.h"

#include "temp_dir.h"

#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>

#include <gtest/gtest.h>

#include <filesystem>

namespace fs = std::filesystem;
using upd::mrpt_bridge::RawlogEntry;
using upd::mrpt_bridge::RawlogReader;

namespace {

mrpt::obs::CObservation3DRangeScan scan(int k) {
  mrpt::obs::CObservation3DRangeScan o;
  o.hasRangeImage = true;
  o.rangeImage.resize(4, 5);
  o.rangeImage.fill(static_cast<uint16_t>(1000 + k));
  o.sensorLabel = "DEPTH";
  o.timestamp = mrpt::Clock::fromDouble(1000.0 + k);
  return o;
}

// Entries read before the end or the first damage.
std::size_t readable(const std::string& path, std::vector<std::string>* classes = nullptr) {
  RawlogReader reader(path);
  RawlogEntry e;
  try {
    while (reader.next(e)) {
      if (classes) classes->push_back(e.className());
    }
  } catch (const upd::mrpt_bridge::RawlogError&) {
  }
  return reader.stats().entries;
}

}  // namespace

TEST(SensorRecording, FinishRenamesAWholeRawlog) {
  const upd::test::TempDir dir;
  const std::string path = dir.file("run.rawlog");
  upd::mrpt_bridge::RawlogWriter w(path, 2);
  for (int k = 0; k < 3; ++k) {
    w.writeOdometry(0.1 * k, 0, 0, 1000.0 + k);
    w.write(scan(k));
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_TRUE(fs::exists(path + ".part"));
  w.finish();
  EXPECT_EQ(dir.listing(), std::vector<std::string>{"run.rawlog"});
  std::vector<std::string> classes;
  EXPECT_EQ(readable(path, &classes), 6u);
  EXPECT_EQ(classes[0], "CObservationOdometry");
  EXPECT_EQ(classes[1], "CObservation3DRangeScan");
  EXPECT_EQ(upd::mrpt_bridge::scanRawlog(path).entries, 6u);  // no damage
}

TEST(SensorRecording, ThePartFileIsReplayableUpToTheLastFlush) {
  const upd::test::TempDir dir;
  const std::string path = dir.file("run.rawlog");
  {
    upd::mrpt_bridge::RawlogWriter w(path, 4);
    for (int k = 0; k < 6; ++k) w.write(scan(k));
    // A crash now: what is on disk is what a copy of the file holds.
    fs::copy_file(path + ".part", dir.file("crash.rawlog"));
  }  // unwinding without finish() leaves the .part file
  EXPECT_FALSE(fs::exists(path));
  EXPECT_GE(readable(dir.file("crash.rawlog")), 4u);
  EXPECT_EQ(readable(path + ".part"), 6u);
}

TEST(SensorRecording, RejectsBadArguments) {
  const upd::test::TempDir dir;
  EXPECT_THROW(upd::mrpt_bridge::RawlogWriter(dir.file("a.rawlog"), 0), std::invalid_argument);
  EXPECT_THROW(upd::mrpt_bridge::RawlogWriter(dir.file("no/such/dir/a.rawlog")),
               std::runtime_error);
}
