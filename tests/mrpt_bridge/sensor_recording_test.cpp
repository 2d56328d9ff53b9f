// RawlogWriter: the recording of `upd live`. A finished recording is a whole rawlog at its
// path, and while it is written (or after a crash) the .part file holds a readable rawlog up to
// the last flush.
#include "upd/mrpt_bridge/rawlog_reader.h"
#include "upd/mrpt_bridge/rawlog_writer.h"

#include "temp_dir.h"

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/serialization/CArchive.h>

#include <gtest/gtest.h>

#include <sys/resource.h>

#include <csignal>
#include <filesystem>

namespace fs = std::filesystem;
using upd::mrpt_bridge::RawlogEntry;
using upd::mrpt_bridge::RawlogReader;

namespace {

mrpt::obs::CObservation3DRangeScan scan(int k, int w = 5, int h = 4) {
  mrpt::obs::CObservation3DRangeScan o;
  o.hasRangeImage = true;
  o.rangeImage.resize(h, w);
  o.cameraParams.ncols = static_cast<uint32_t>(w);
  o.cameraParams.nrows = static_cast<uint32_t>(h);
  o.cameraParamsIntensity = o.cameraParams;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) o.rangeImage(v, u) = static_cast<uint16_t>(1000 + k + (u ^ v) % 97);
  }
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
    w.drain();
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

// The writer thread writes what writing each object to CFileGZOutputStream in the caller's
// thread, a member closed every flush_every objects, writes: the same bytes.
TEST(SensorRecording, TheFileIsTheOneCFileGZOutputStreamWritesInTheCallersThread) {
  const upd::test::TempDir dir;
  const std::string path = dir.file("run.rawlog"), peer = dir.file("peer.rawlog");
  constexpr int kFlushEvery = 3;
  upd::mrpt_bridge::RawlogWriter w(path, kFlushEvery);
  auto out = std::make_unique<mrpt::io::CFileGZOutputStream>(peer);
  for (int k = 0; k < 8; ++k) {
    const mrpt::obs::CObservation3DRangeScan o = scan(k, 640, 480);
    w.write(o);
    mrpt::serialization::archiveFrom(*out) << o;
    if ((k + 1) % kFlushEvery == 0) {
      out->close();
      std::string err;
      ASSERT_TRUE(out->open(peer, 1, err, mrpt::io::OpenMode::APPEND)) << err;
    }
  }
  out.reset();
  w.finish();
  const std::string ours = upd::test::readFileBytes(path), theirs = upd::test::readFileBytes(peer);
  EXPECT_GT(ours.size(), 10000u);
  EXPECT_TRUE(ours == theirs) << ours.size() << " bytes against " << theirs.size();
  EXPECT_EQ(readable(path), 8u);
}

// An observation changed after write() is recorded as it was when written.
TEST(SensorRecording, WriteTakesTheObservationAsItIs) {
  const upd::test::TempDir dir;
  const std::string path = dir.file("run.rawlog");
  upd::mrpt_bridge::RawlogWriter w(path);
  mrpt::obs::CObservation3DRangeScan o = scan(1);
  for (int k = 0; k < 4; ++k) {
    o.timestamp = mrpt::Clock::fromDouble(2000.0 + k);
    w.write(o);
  }
  w.finish();
  RawlogReader reader(path);
  RawlogEntry e;
  for (int k = 0; k < 4; ++k) {
    ASSERT_TRUE(reader.next(e));
    ASSERT_TRUE(e.observation);
    EXPECT_NEAR(e.timestamp_s, 2000.0 + k, 1e-6);
  }
  EXPECT_FALSE(reader.next(e));
}

// A file that cannot take the data (/dev/full: no space left): write() or finish() says so,
// naming the .part file, which stays; no file at the path. Large frames fail in a write; small
// ones reach the file only when their member is closed (MRPT's stream ignores that failure).
TEST(SensorRecording, AFullDiskIsReportedNamingTheFile) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this system";
  for (const int width : {640, 5}) {
    const upd::test::TempDir dir;
    const std::string path = dir.file("run.rawlog");
    fs::create_symlink("/dev/full", path + ".part");
    std::string message;
    try {
      upd::mrpt_bridge::RawlogWriter w(path, 100);
      for (int k = 0; k < 20; ++k) w.write(scan(k, width, width * 3 / 4));
      w.finish();
    } catch (const std::runtime_error& e) {
      message = e.what();
    }
    EXPECT_EQ(message, "cannot write " + path + ".part: No space left on device") << width;
    EXPECT_FALSE(fs::exists(path)) << width;
  }
}

// A disk that fills part way (the process's file size limit): the writer reports it, and
// saved() counts the observations of the members closed before, which a reader of the .part
// file gets (the cut member after them may give up to its own).
TEST(SensorRecording, SavedCountsTheObservationsOfTheCompleteMembers) {
  const upd::test::TempDir dir;
  const std::string path = dir.file("run.rawlog");
  rlimit before{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &before), 0);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);  // (a write past it fails with EFBIG)
  rlimit limit = before;
  limit.rlim_cur = 48 << 10;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limit), 0);
  upd::mrpt_bridge::RawlogWriter w(path, 3);
  std::string message;
  try {
    for (int k = 0; k < 400; ++k) w.write(scan(k, 64, 48));
    w.finish();
  } catch (const std::runtime_error& e) {
    message = e.what();
  }
  setrlimit(RLIMIT_FSIZE, &before);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_EQ(message, "cannot write " + path + ".part: File too large");
  const std::size_t saved = w.saved(), read = readable(path + ".part");
  EXPECT_GT(saved, 0u);
  EXPECT_EQ(saved % 3, 0u);  // (whole members)
  EXPECT_GE(read, saved);
  EXPECT_LE(read, saved + 3);  // (at most the cut member's)
  EXPECT_LT(saved, w.written());
}
