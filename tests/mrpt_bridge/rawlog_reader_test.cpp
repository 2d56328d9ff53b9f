// The streaming rawlog reader on every rawlog of the shared data, on truncated and corrupt
// copies, and on files written here in both layouts.
#include "upd/mrpt_bridge/rawlog_reader.h"
#include "rawlog_damage.h"
#include "temp_dir.h"
#include "test_data.h"

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CActionRobotMovement3D.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/poses/CPosePDFGrid.h>
#include <mrpt/poses/CPosePDFParticles.h>
#include <mrpt/poses/CPosePDFSOG.h>
#include <mrpt/serialization/CArchive.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>

namespace {

using upd::mrpt_bridge::RawlogEntry;
using upd::mrpt_bridge::RawlogError;
using upd::mrpt_bridge::RawlogLayout;
using upd::mrpt_bridge::RawlogReader;
namespace fs = std::filesystem;

using upd::test::damageAtSecondObject;
using upd::test::readFileBytes;
using upd::test::TempDir;

void writePrefix(const std::string& from, const fs::path& to, double fraction) {
  std::ifstream in(from, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream out(to, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size() * fraction));
}

TEST(RawlogReader, SenaActionsAndFramesAllEntriesWithOdometry) {
  UPD_REQUIRE_SHARED_FILE(path, "mrpt/2006-01ENE-21-SENA_Telecom_Faculty_one_loop_only.rawlog");
  RawlogReader reader(path);
  RawlogEntry e;
  std::size_t n = 0, with_odometry = 0;
  double travelled_m = 0, last_t = -1;
  while (reader.next(e)) {
    ASSERT_TRUE(e.observation);
    EXPECT_EQ(e.index, n);
    EXPECT_EQ(e.className(), "CObservation2DRangeScan");
    ASSERT_TRUE(std::isfinite(e.timestamp_s));
    EXPECT_GE(e.timestamp_s, last_t);  // file order is time order here
    last_t = e.timestamp_s;
    if (e.odometry_increment) {
      ++with_odometry;
      travelled_m += e.odometry_increment->translation().norm();
      // planar odometry: no z, rotation about z only
      EXPECT_NEAR(e.odometry_increment->translation().z(), 0.0, 1e-12);
      EXPECT_NEAR(e.odometry_increment->linear()(2, 2), 1.0, 1e-12);
    }
    ++n;
  }
  EXPECT_EQ(n, 225u);
  EXPECT_EQ(with_odometry, 224u);  // the first frame has no action before it
  EXPECT_GT(travelled_m, 10.0);    // one loop of a faculty corridor
  const auto& s = reader.stats();
  EXPECT_EQ(s.objects, 449u);
  EXPECT_EQ(s.action_collections, 224u);
  EXPECT_EQ(s.sensory_frames, 225u);
  EXPECT_EQ(s.odometry_actions, 224u);
  EXPECT_EQ(s.entries, 225u);
  EXPECT_EQ(s.entries_by_class.at("CObservation2DRangeScan"), 225u);
  EXPECT_EQ(s.skippedTotal(), 0u);
  EXPECT_EQ(reader.layout(), RawlogLayout::ActionsAndFrames);
  EXPECT_FALSE(reader.next(e));  // stays at the end
}

struct ExpectedFile {
  const char* rel;
  std::size_t objects, entries;
  const char* cls;
  RawlogLayout layout;
};

TEST(RawlogReader, EverySharedRawlogReadsToTheEnd) {
  const ExpectedFile files[] = {
      {"mrpt/2006-01ENE-21-SENA_Telecom_Faculty_one_loop_only.rawlog", 449, 225,
       "CObservation2DRangeScan", RawlogLayout::ActionsAndFrames},
      {"mrpt/test-3d-obs-ground.rawlog", 1, 1, "CObservation3DRangeScan",
       RawlogLayout::ActionsAndFrames},
      {"mrpt/tests_rgbd.rawlog", 1, 1, "CObservation3DRangeScan", RawlogLayout::ObservationsOnly},
      {"mrpt/test_velodyne_VLP16.rawlog", 1, 1, "CObservationVelodyneScan",
       RawlogLayout::ObservationsOnly},
  };
  std::size_t checked = 0;
  for (const auto& f : files) {
    const std::string path = upd::test::sharedFile(f.rel);
    if (path.empty()) continue;
    SCOPED_TRACE(f.rel);
    const auto stats = upd::mrpt_bridge::scanRawlog(path);
    EXPECT_EQ(stats.objects, f.objects);
    EXPECT_EQ(stats.entries, f.entries);
    EXPECT_EQ(stats.entries_by_class.at(f.cls), f.entries);
    RawlogReader reader(path);
    RawlogEntry e;
    while (reader.next(e)) {
    }
    EXPECT_EQ(reader.layout(), f.layout);
    ++checked;
  }
  // Any further rawlog in the directory must read without error too.
  const fs::path dir = upd::test::sharedDataDir() / "mrpt";
  if (fs::is_directory(dir)) {
    for (const auto& item : fs::directory_iterator(dir)) {
      if (item.path().extension() != ".rawlog") continue;
      SCOPED_TRACE(item.path().string());
      EXPECT_NO_THROW(upd::mrpt_bridge::scanRawlog(item.path().string()));
    }
  }
  if (checked == 0) GTEST_SKIP() << "no shared rawlog found under " << upd::test::sharedDataDir();
}

TEST(RawlogReader, TruncatedFileGivesCleanErrorNamingFileAndObject) {
  UPD_REQUIRE_SHARED_FILE(path, "mrpt/2006-01ENE-21-SENA_Telecom_Faculty_one_loop_only.rawlog");
  TempDir tmp;
  const fs::path cut = tmp.path() / "sena_half.rawlog";
  writePrefix(path, cut, 0.5);
  RawlogReader reader(cut.string());
  RawlogEntry e;
  std::size_t read = 0;
  try {
    while (reader.next(e)) ++read;
    FAIL() << "a truncated rawlog read to its end";
  } catch (const RawlogError& err) {
    const std::string what = err.what();
    EXPECT_NE(what.find(cut.string()), std::string::npos) << what;
    EXPECT_NE(what.find("object #" + std::to_string(err.objectIndex())), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
    EXPECT_EQ(err.path(), cut.string());
    EXPECT_GT(err.objectIndex(), 100u);  // about half of 449
    EXPECT_LT(err.objectIndex(), 449u);
    EXPECT_GT(read, 50u);  // what came before is still delivered
    // Where the unread object starts in the decompressed stream, and why, for a caller that
    // keeps what came before (upd playback's damage record).
    EXPECT_GT(err.byteOffset(), 0u);
    EXPECT_NE(what.find("byte " + std::to_string(err.byteOffset())), std::string::npos) << what;
    EXPECT_FALSE(err.reason().empty());
    EXPECT_NE(what.find(err.reason()), std::string::npos) << what;
  }
  // Asking again repeats the error instead of inventing an end.
  EXPECT_THROW(reader.next(e), RawlogError);
}

TEST(RawlogReader, TruncatedSingleObservationFiles) {
  for (const char* rel : {"mrpt/test-3d-obs-ground.rawlog", "mrpt/tests_rgbd.rawlog",
                          "mrpt/test_velodyne_VLP16.rawlog"}) {
    const std::string path = upd::test::sharedFile(rel);
    if (path.empty()) continue;
    SCOPED_TRACE(rel);
    TempDir tmp;
    for (double fraction : {0.1, 0.5, 0.9, 0.999}) {
      const fs::path cut =
          tmp.path() / ("cut_" + std::to_string(static_cast<int>(fraction * 1000)) + ".rawlog");
      writePrefix(path, cut, fraction);
      try {
        upd::mrpt_bridge::scanRawlog(cut.string());
        ADD_FAILURE() << "no error for " << fraction << " of " << rel;
      } catch (const RawlogError& err) {
        EXPECT_NE(std::string(err.what()).find(cut.string()), std::string::npos);
        EXPECT_EQ(err.objectIndex(), 0u);
      }
    }
  }
}

TEST(RawlogReader, GarbageAndMissingFiles) {
  TempDir tmp;
  const fs::path garbage = tmp.path() / "garbage.rawlog";
  {
    std::ofstream out(garbage, std::ios::binary);
    std::uint32_t x = 12345u;  // fixed-seed LCG bytes
    for (int i = 0; i < 4096; ++i) {
      x = x * 1664525u + 1013904223u;
      out.put(static_cast<char>(x >> 24));
    }
  }
  try {
    upd::mrpt_bridge::scanRawlog(garbage.string());
    FAIL() << "garbage was read as a rawlog";
  } catch (const RawlogError& err) {
    const std::string what = err.what();
    EXPECT_NE(what.find(garbage.string()), std::string::npos);
    EXPECT_EQ(what.find('\n'), std::string::npos);
    for (char c : what) EXPECT_TRUE(c >= 0x20 && c < 0x7f) << "non-printable in: " << what;
  }
  const fs::path text = tmp.path() / "text.rawlog";
  std::ofstream(text) << "this is not a rawlog\n";
  EXPECT_THROW(upd::mrpt_bridge::scanRawlog(text.string()), RawlogError);

  const std::string missing = (tmp.path() / "nope.rawlog").string();
  try {
    RawlogReader reader(missing);
    FAIL() << "a missing file opened";
  } catch (const std::runtime_error& err) {
    EXPECT_EQ(std::string(err.what()), "rawlog " + missing + ": not found");
  }

  const fs::path empty = tmp.path() / "empty.rawlog";
  std::ofstream(empty).close();
  const auto stats = upd::mrpt_bridge::scanRawlog(empty.string());
  EXPECT_EQ(stats.objects, 0u);
  EXPECT_EQ(stats.entries, 0u);
}

// Both layouts written here: an odometry increment reaches the next observation even across an
// empty sensory frame; a frame with no action before it is not lost; skips are counted.
TEST(RawlogReader, WrittenLayoutsAndSkipReasons) {
  using namespace mrpt::obs;
  TempDir tmp;
  const fs::path file = tmp.path() / "mixed.rawlog";
  const auto movement = [](double x, double y, double phi) {
    CActionRobotMovement2D act;
    CActionRobotMovement2D::TMotionModelOptions opts;
    act.computeFromOdometry(mrpt::poses::CPose2D(x, y, phi), opts);
    CActionCollection acts;
    acts.insert(act);
    return acts;
  };
  const auto odoObs = [](double x) {
    auto o = CObservationOdometry::Create();
    o->odometry = mrpt::poses::CPose2D(x, 0, 0);
    o->timestamp = mrpt::Clock::fromDouble(1000.0 + x);
    return o;
  };
  {
    mrpt::io::CFileGZOutputStream out(file.string());
    auto ar = mrpt::serialization::archiveFrom(out);
    CSensoryFrame sf0;  // no action before it
    sf0.insert(odoObs(0.0));
    ar << sf0;
    ar << movement(1.0, 0.0, 0.0);
    CSensoryFrame empty;
    ar << empty;  // the increment must survive this
    ar << movement(0.0, 2.0, 0.0);
    CSensoryFrame sf1;
    sf1.insert(odoObs(1.0));
    sf1.insert(odoObs(2.0));
    ar << sf1;
    ar << *odoObs(3.0);  // observation-only layout in the same file
    CObservationComment comment;
    comment.text = "hello";
    ar << comment;
    ar << movement(5.0, 0.0, 0.0);  // nothing after it
  }
  RawlogReader reader(file.string());
  RawlogEntry e;
  ASSERT_TRUE(reader.next(e));
  EXPECT_FALSE(e.odometry_increment);
  EXPECT_NEAR(e.timestamp_s, 1000.0, 1e-6);
  ASSERT_TRUE(reader.next(e));
  ASSERT_TRUE(e.odometry_increment);  // (1,0) then (0,2), composed
  EXPECT_NEAR(e.odometry_increment->translation().x(), 1.0, 1e-9);
  EXPECT_NEAR(e.odometry_increment->translation().y(), 2.0, 1e-9);
  EXPECT_EQ(e.object_index, 4u);
  ASSERT_TRUE(reader.next(e));
  EXPECT_FALSE(e.odometry_increment);  // same frame, the increment went to the first one
  EXPECT_EQ(e.object_index, 4u);
  ASSERT_TRUE(reader.next(e));
  EXPECT_EQ(e.className(), "CObservationOdometry");
  ASSERT_TRUE(reader.next(e));
  EXPECT_EQ(e.className(), "CObservationComment");
  EXPECT_FALSE(reader.next(e));
  const auto& s = reader.stats();
  EXPECT_EQ(s.entries, 5u);
  EXPECT_EQ(s.odometry_actions, 3u);
  EXPECT_EQ(s.skipped.at("empty CSensoryFrame"), 1u);
  EXPECT_EQ(s.skipped.at("odometry at the end of the file with no observation after it"), 1u);
  EXPECT_EQ(reader.layout(), RawlogLayout::Mixed);
  EXPECT_NE(s.summary().find("5 observations"), std::string::npos) << s.summary();
}

// An odometry action whose motion model MRPT rebuilds while reading it: the Thrun model draws
// nParticlesCount particles, any value but 0 (Gaussian) selects it. Nothing is drawn here: the
// fields are set and written as they are.
mrpt::obs::CActionCollection odometryWithModel(int model, std::uint32_t particles) {
  using mrpt::obs::CActionRobotMovement2D;
  CActionRobotMovement2D act;
  act.estimationMethod = CActionRobotMovement2D::emOdometry;
  act.rawOdometryIncrementReading = mrpt::poses::CPose2D(0.5, 0, 0);
  act.motionModelConfiguration.modelSelection =
      static_cast<CActionRobotMovement2D::TDrawSampleMotionModel>(model);
  act.motionModelConfiguration.thrunModel.nParticlesCount = particles;
  mrpt::obs::CActionCollection acts;
  acts.insert(act);
  return acts;
}

// A plain rawlog: an observation, the given actions (a collection or a bare action), an
// observation.
void writeAroundActions(const fs::path& file, const mrpt::serialization::CSerializable& acts) {
  mrpt::io::CFileOutputStream out(file.string());
  auto ar = mrpt::serialization::archiveFrom(out);
  mrpt::obs::CObservationComment first, last;
  first.text = "before";
  last.text = "after";
  ar << first << acts << last;
}

// A corrupt particle count would make MRPT draw 10^9 particles inside its deserialization
// (minutes, gigabytes): the reader reads the fields first and names the object as damage; the
// observation before it is delivered. A sane Thrun model is read as usual.
TEST(RawlogReader, ImpossibleOdometryMotionModelIsDamageBeforeMrptDrawsIt) {
  TempDir tmp;
  struct Case {
    int model;
    std::uint32_t particles;
    const char* reason;  ///< "" when the file reads to its end
  } cases[] = {
      {1, 2000000000u,
       "corrupt CActionRobotMovement2D (action 1 of 1 in a CActionCollection): a motion model of "
       "2000000000 particles (more than 100000; MRPT draws every one while reading the object)"},
      {-256, 1007614517u,
       "corrupt CActionRobotMovement2D (action 1 of 1 in a CActionCollection): unknown motion "
       "model -256 (0 Gaussian, 1 Thrun; MRPT would draw its 1007614517 particles)"},
      {7, 300u, "unknown motion model 7"},
      {1, 300u, ""},
      {0, 4000000000u, ""},  // the Gaussian model draws nothing: the count is not used
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::to_string(c.model) + " / " + std::to_string(c.particles));
    const fs::path file = tmp.path() / "odometry.rawlog";
    writeAroundActions(file, odometryWithModel(c.model, c.particles));
    RawlogReader reader(file.string());
    RawlogEntry e;
    ASSERT_TRUE(reader.next(e));
    EXPECT_EQ(e.className(), "CObservationComment");
    if (*c.reason == '\0') {
      ASSERT_TRUE(reader.next(e));
      EXPECT_TRUE(e.odometry_increment);
      EXPECT_FALSE(reader.next(e));
      continue;
    }
    try {
      reader.next(e);
      ADD_FAILURE() << "the action was read";
    } catch (const RawlogError& err) {
      EXPECT_EQ(err.objectIndex(), 1u);
      EXPECT_GT(err.byteOffset(), 0u);
      EXPECT_NE(err.reason().find(c.reason), std::string::npos) << err.reason();
      EXPECT_NE(std::string(err.what()).find("cannot read object #1 (at byte " +
                                             std::to_string(err.byteOffset())),
                std::string::npos)
          << err.what();
    }
  }
}

// CActionCollection resizes its list of actions to the count it reads: an impossible count is
// damage before MRPT allocates it.
TEST(RawlogReader, ImpossibleActionCountIsDamage) {
  TempDir tmp;
  const fs::path file = tmp.path() / "actions.rawlog";
  writeAroundActions(file, odometryWithModel(0, 300));
  std::string bytes = readFileBytes(file);
  // The object header: the name's length with the high bit set, the name, the version 0.
  const std::string name = "mrpt::obs::CActionCollection";
  const std::string header = std::string(1, static_cast<char>(0x80 | name.size())) + name + '\0';
  const auto at = bytes.find(header);
  ASSERT_NE(at, std::string::npos);
  const std::size_t count_at = at + header.size();
  ASSERT_EQ(bytes[count_at], 1);
  bytes.replace(count_at, 4, std::string("\xF0\xFF\xFF\xFF", 4));  // 4294967280 actions
  std::ofstream(file, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  RawlogReader reader(file.string());
  RawlogEntry e;
  ASSERT_TRUE(reader.next(e));
  try {
    reader.next(e);
    ADD_FAILURE() << "the collection was read";
  } catch (const RawlogError& err) {
    EXPECT_EQ(err.objectIndex(), 1u);
    EXPECT_EQ(err.byteOffset(), at);
    EXPECT_EQ(err.reason(), "corrupt CActionCollection: action count 4294967280 at byte " +
                                std::to_string(count_at) + " (more than 4096 actions)");
  }
}

// An action estimated by scan matching carries its pose distribution (a CPosePDF) where odometry
// carries its increment, and MRPT uses whatever object it reads there as one: an estimation
// method corrupted to anything but odometry (found by fuzz_rawlog: 256, with the odometry's
// CPose2D following) is damage before MRPT reads it, as is an unknown method. A real
// scan-matching action is read as usual.
TEST(RawlogReader, EstimationMethodWithoutItsPoseDistributionIsDamage) {
  TempDir tmp;
  const fs::path file = tmp.path() / "method.rawlog";
  writeAroundActions(file, odometryWithModel(0, 300));
  const std::string odometry = readFileBytes(file);
  // The action's header (the name's length with the high bit set, the name, its version byte),
  // then the method, an int32.
  const std::string name = "mrpt::obs::CActionRobotMovement2D";
  const auto at = odometry.find(std::string(1, static_cast<char>(0x80 | name.size())) + name);
  ASSERT_NE(at, std::string::npos);
  const std::size_t method_at = at + 1 + name.size() + 1;
  ASSERT_EQ(odometry.substr(method_at, 4), std::string(4, '\0'));
  const std::string prefix =
      "corrupt CActionRobotMovement2D (action 1 of 1 in a CActionCollection): ";
  std::string bytes = odometry;
  bytes.replace(method_at, 4, std::string("\x00\x01\x00\x00", 4));
  EXPECT_EQ(damageAtSecondObject(file, bytes),
            prefix + "unknown estimation method 256 (0 odometry, 1 scan matching)");
  bytes.replace(method_at, 4, std::string("\x01\x00\x00\x00", 4));
  EXPECT_EQ(damageAtSecondObject(file, bytes),
            prefix + "a CPose2D where scan matching's pose distribution (a CPosePDF) belongs");

  mrpt::obs::CActionRobotMovement2D matched;
  matched.estimationMethod = mrpt::obs::CActionRobotMovement2D::emScan2DMatching;
  auto pdf = mrpt::poses::CPosePDFGaussian::Create();
  pdf->mean = mrpt::poses::CPose2D(0.4, 0.1, 0.05);
  matched.poseChange = mrpt::containers::deepcopy_poly_ptr<mrpt::poses::CPosePDF::Ptr>(pdf);
  mrpt::obs::CActionCollection acts;
  acts.insert(matched);
  writeAroundActions(file, acts);
  EXPECT_EQ(damageAtSecondObject(file, readFileBytes(file)), "(read)");
}

// A scan-matching action carrying pose distribution pdf.
mrpt::obs::CActionCollection scanMatched(const mrpt::poses::CPosePDF::Ptr& pdf) {
  mrpt::obs::CActionRobotMovement2D matched;
  matched.estimationMethod = mrpt::obs::CActionRobotMovement2D::emScan2DMatching;
  matched.poseChange = mrpt::containers::deepcopy_poly_ptr<mrpt::poses::CPosePDF::Ptr>(pdf);
  mrpt::obs::CActionCollection acts;
  acts.insert(matched);
  return acts;
}

// bytes with the 4 bytes at `at` replaced by v (little-endian).
std::string withInt32(std::string bytes, std::size_t at, std::uint32_t v) {
  for (int b = 0; b < 4; ++b) bytes[at + b] = static_cast<char>((v >> (8 * b)) & 0xFF);
  return bytes;
}

// The sizes a scan-matching action's pose distribution makes MRPT allocate before it reads the
// elements (particles, Gaussian modes, grid cells) are bounded, and a grid's cells must match
// its sides (MRPT walks the sides when it takes the mean the reader asks for): each corrupt
// size is damage with a one-line reason naming the distribution, the field and its byte; the
// intact distributions read.
TEST(RawlogReader, ScanMatchingPoseDistributionSizesAreCheckedBeforeMrptAllocates) {
  TempDir tmp;
  const fs::path file = tmp.path() / "pdf.rawlog";
  const std::string prefix =
      "corrupt CActionRobotMovement2D (action 1 of 1 in a CActionCollection): ";
  // The byte after the class name and version byte of the distribution in bytes.
  const auto bodyOf = [](const std::string& bytes, const std::string& name) {
    const auto at = bytes.find("mrpt::poses::" + name);
    EXPECT_NE(at, std::string::npos) << name;
    return at + std::string("mrpt::poses::").size() + name.size() + 1;
  };

  // Every distribution is walked through: what follows it is checked as well (an odometry
  // action whose motion model would draw 2 * 10^9 particles, behind scan matching).
  mrpt::obs::CActionCollection behind =
      scanMatched(mrpt::poses::CPosePDFGaussian::Create(mrpt::poses::CPose2D(0.3, 0.1, 0.02)));
  behind.insert(*odometryWithModel(1, 2000000000u).get(0));
  writeAroundActions(file, behind);
  EXPECT_EQ(damageAtSecondObject(file, readFileBytes(file)),
            "corrupt CActionRobotMovement2D (action 2 of 2 in a CActionCollection): a motion "
            "model of 2000000000 particles (more than 100000; MRPT draws every one while "
            "reading the object)");

  auto particles = mrpt::poses::CPosePDFParticles::Create(5);
  particles->resetDeterministic(mrpt::math::TPose2D(0.3, 0.1, 0.02));
  writeAroundActions(file, scanMatched(particles));
  std::string bytes = readFileBytes(file);
  EXPECT_EQ(damageAtSecondObject(file, bytes), "(read)");
  std::size_t n_at = bodyOf(bytes, "CPosePDFParticles");
  EXPECT_EQ(damageAtSecondObject(file, withInt32(bytes, n_at, 200000000u)),
            prefix + "corrupt CPosePDFParticles: particle count 200000000 at byte " +
                std::to_string(n_at) + " (more than 100000 particles)");

  auto sog = mrpt::poses::CPosePDFSOG::Create(2);
  writeAroundActions(file, scanMatched(sog));
  bytes = readFileBytes(file);
  EXPECT_EQ(damageAtSecondObject(file, bytes), "(read)");
  n_at = bodyOf(bytes, "CPosePDFSOG");
  EXPECT_EQ(damageAtSecondObject(file, withInt32(bytes, n_at, 0xFFFFFFF0u)),
            prefix + "corrupt CPosePDFSOG: mode count 4294967280 at byte " +
                std::to_string(n_at) + " (more than 100000 modes)");

  // 5 x 5 x 5 cells.
  auto grid = mrpt::poses::CPosePDFGrid::Create(-1.0, 1.0, -1.0, 1.0, 0.5, M_PI / 2, -M_PI, M_PI);
  ASSERT_EQ(grid->getSizeX(), 5u);
  ASSERT_EQ(grid->getSizeY(), 5u);
  ASSERT_EQ(grid->getSizePhi(), 5u);
  writeAroundActions(file, scanMatched(grid));
  bytes = readFileBytes(file);
  EXPECT_EQ(damageAtSecondObject(file, bytes), "(read)");
  const std::size_t sides_at = bodyOf(bytes, "CPosePDFGrid") + 8 * sizeof(double);
  const std::size_t count_at = sides_at + 7 * sizeof(std::int32_t);
  EXPECT_EQ(damageAtSecondObject(file, withInt32(bytes, count_at, 124u)),
            prefix + "corrupt CPosePDFGrid: 124 cells at byte " + std::to_string(count_at) +
                " for sides 5 x 5 x 5");
  EXPECT_EQ(damageAtSecondObject(file, withInt32(bytes, count_at, 1u << 30)),
            prefix + "corrupt CPosePDFGrid: cell count 1073741824 at byte " +
                std::to_string(count_at) + " (more than 16777216 cells)");
  // A side grown to 40000: MRPT would walk 40000 x 5 x 5 cells of a 125-cell table.
  EXPECT_EQ(damageAtSecondObject(file, withInt32(bytes, sides_at, 40000u)),
            prefix + "corrupt CPosePDFGrid: sides 40000 x 5 x 5 with 25 cells a layer, at byte " +
                std::to_string(sides_at));
  // The same grid behind particles of version 0 (CPose2D objects), a layout the walk of the
  // collection leaves to MRPT (found by fuzz_rawlog behind actions the walk then stopped at):
  // the reader hands MRPT a collection one action at a time, each checked at its own start.
  mrpt::obs::CActionCollection two = scanMatched(mrpt::poses::CPosePDFParticles::Create(1));
  two.insert(*scanMatched(grid).get(0));
  writeAroundActions(file, two);
  bytes = readFileBytes(file);
  const std::string pose2d = std::string("\x94" "mrpt::poses::CPose2D\x01") + std::string(24, '\0');
  bytes.replace(bodyOf(bytes, "CPosePDFParticles") - 1, 1 + 4 + 4 * 8,  // version 1, 1 particle
                std::string(1, '\0') + withInt32(std::string(12, '\0'), 0, 1) + pose2d + "\x88");
  EXPECT_EQ(damageAtSecondObject(file, bytes), "(read)");
  const std::size_t second_sides_at = bodyOf(bytes, "CPosePDFGrid") + 8 * sizeof(double);
  EXPECT_EQ(damageAtSecondObject(file, withInt32(bytes, second_sides_at, 40000u)),
            "corrupt CActionRobotMovement2D (action 2 of 2 in a CActionCollection): corrupt "
            "CPosePDFGrid: sides 40000 x 5 x 5 with 25 cells a layer, at byte " +
                std::to_string(second_sides_at));
}

// A robot movement whose pose change is not finite, or moves the robot more than a kilometre
// between two observations, is damage at its object, naming the action and the values: the
// second action of a collection, a bare 3D movement; a move of 999 m reads.
TEST(RawlogReader, MovementNotFiniteOrBeyondAKilometreIsDamage) {
  TempDir tmp;
  const fs::path file = tmp.path() / "nan.rawlog";
  using mrpt::obs::CActionRobotMovement2D;
  mrpt::obs::CActionCollection acts = odometryWithModel(0, 300);
  CActionRobotMovement2D nan_odometry;
  nan_odometry.computeFromOdometry(mrpt::poses::CPose2D(0.1, std::nan(""), 0.2),
                                   CActionRobotMovement2D::TMotionModelOptions());
  acts.insert(nan_odometry);
  writeAroundActions(file, acts);
  EXPECT_EQ(damageAtSecondObject(file, readFileBytes(file)),
            "corrupt CActionRobotMovement2D (action 2 of 2 in a CActionCollection): its pose "
            "change (x, y, phi) = (0.1, nan, 0.2) is not finite");

  mrpt::obs::CActionRobotMovement3D moved;
  moved.poseChange.mean = mrpt::poses::CPose3D(0.5, 0, std::numeric_limits<double>::infinity(),
                                               0, 0, 0);
  writeAroundActions(file, moved);
  EXPECT_EQ(damageAtSecondObject(file, readFileBytes(file)),
            "corrupt CActionRobotMovement3D: its pose change (x, y, z, yaw, pitch, roll) = (0.5, "
            "0, inf, 0, 0, 0) is not finite");
  for (const double z : {1000.5, 999.0}) {
    moved.poseChange.mean = mrpt::poses::CPose3D(0, 0, z, 0, 0, 0);
    writeAroundActions(file, moved);
    EXPECT_EQ(damageAtSecondObject(file, readFileBytes(file)),
              z > 1000 ? "corrupt CActionRobotMovement3D: its pose change moves the robot 1000.5 m "
                         "(more than 1000 m between two observations)"
                       : "(read)");
  }
}

}  // namespace

namespace {

TEST(RawlogReader, ImagesDirectoryFollowsMrptConvention) {
  TempDir tmp;
  const fs::path rawlog = tmp.path() / "run.rawlog";
  EXPECT_EQ(fs::path(upd::mrpt_bridge::detectImagesDirectory(rawlog.string())),
            tmp.path() / "Images");
  fs::create_directories(tmp.path() / "run_Images");
  EXPECT_EQ(fs::path(upd::mrpt_bridge::detectImagesDirectory(rawlog.string())),
            tmp.path() / "run_Images");
}

}  // namespace
