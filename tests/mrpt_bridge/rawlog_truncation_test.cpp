// A rawlog cut at any byte: the objects before the cut are read, the cut one is damage naming the
// end of the file, and MRPT is never handed an object the file ends inside (CArchive takes a short
// read as data: a count cut by the end was read with bytes that were never there).
#include "rawlog_bytes.h"
#include "upd/mrpt_bridge/rawlog_reader.h"

#include <mrpt/img/CImage.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>

#include <gtest/gtest.h>

#include <cstddef>
#include <fstream>
#include <string>
#include <vector>

namespace {

using upd::mrpt_bridge::RawlogEntry;
using upd::mrpt_bridge::RawlogError;
using upd::mrpt_bridge::RawlogReader;
using upd::test::serialized;
using upd::test::TempDir;

struct Written {
  std::string bytes;
  std::vector<std::size_t> ends;     ///< where each object ends
  std::vector<std::size_t> entries;  ///< observations delivered by the objects up to each end
};

// An odometry step, a sensory frame of a laser scan and a camera image (a JPEG, as MRPT writes a
// colour image), and a bare comment: each of a layout the reader's check walks to its end.
Written smallRun() {
  using namespace mrpt::obs;
  CActionCollection actions;
  CActionRobotMovement2D move;
  CActionRobotMovement2D::TMotionModelOptions model;
  model.modelSelection = CActionRobotMovement2D::mmGaussian;
  move.computeFromOdometry(mrpt::poses::CPose2D(0.1, 0.0, 0.02), model);
  actions.insert(move);

  CSensoryFrame frame;
  auto scan = CObservation2DRangeScan::Create();
  scan->resizeScan(24);
  for (std::size_t i = 0; i < 24; ++i) scan->setScanRange(i, 1.0f + 0.1f * static_cast<float>(i));
  for (std::size_t i = 0; i < 24; ++i) scan->setScanRangeValidity(i, true);
  frame.insert(scan);
  auto camera = CObservationImage::Create();
  camera->image.resize(16, 12, mrpt::img::CH_RGB);
  camera->image.filledRectangle(0, 0, 15, 11, mrpt::img::TColor(40, 120, 200));
  camera->image.filledRectangle(4, 3, 9, 8, mrpt::img::TColor(220, 30, 10));
  frame.insert(camera);

  CObservationComment note;
  note.text = "end of the run";

  const bool jpeg_off = mrpt::img::CImage::DISABLE_JPEG_COMPRESSION();
  mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(false);
  Written w;
  std::size_t entries = 0;
  for (const auto& [bytes, delivered] :
       {std::pair{serialized(actions), 0}, {serialized(frame), 2}, {serialized(note), 1}}) {
    w.bytes += bytes;
    entries += delivered;
    w.ends.push_back(w.bytes.size());
    w.entries.push_back(entries);
  }
  mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(jpeg_off);
  return w;
}

}  // namespace

TEST(RawlogTruncation, EveryCutIsDamageAtTheCutObjectAfterEverythingBeforeIt) {
  const Written run = smallRun();
  ASSERT_NE(run.bytes.find("\xFF\xD8\xFF"), std::string::npos) << "the image is no JPEG";
  TempDir tmp;
  const auto file = tmp.path() / "cut.rawlog";
  int damaged = 0;
  for (std::size_t cut = 1; cut < run.bytes.size(); ++cut) {
    SCOPED_TRACE("cut at byte " + std::to_string(cut) + " of " + std::to_string(run.bytes.size()));
    std::ofstream(file, std::ios::binary).write(run.bytes.data(), static_cast<std::streamsize>(cut));
    std::size_t object = 0;  // the object the cut falls in, or after
    while (run.ends[object] < cut) ++object;
    const bool at_end = run.ends[object] == cut;
    const std::size_t whole = at_end ? object + 1 : object;  // objects entirely before the cut
    const std::size_t expected_entries = whole == 0 ? 0 : run.entries[whole - 1];

    RawlogReader reader(file.string());
    RawlogEntry e;
    std::size_t entries = 0;
    try {
      while (reader.next(e)) ++entries;
      EXPECT_TRUE(at_end) << "a file cut inside object #" << object << " read to its end";
    } catch (const RawlogError& err) {
      ++damaged;
      EXPECT_FALSE(at_end) << err.what();
      EXPECT_EQ(err.objectIndex(), object) << err.what();
      EXPECT_EQ(err.byteOffset(), object == 0 ? 0 : run.ends[object - 1]) << err.what();
      const std::string reason = err.reason();
      // The cut named as the end of the file: MRPT's own end-of-file error at a header, the check's
      // where a field runs past the end, or where a JPEG does.
      const bool names_the_end = reason.rfind("truncated, the file ends inside it", 0) == 0 ||
                                 reason.find("cut short by the end of the stream") != std::string::npos;
      EXPECT_TRUE(names_the_end) << reason;
    }
    EXPECT_EQ(entries, expected_entries);
  }
  EXPECT_EQ(damaged, static_cast<int>(run.bytes.size()) - static_cast<int>(run.ends.size()));
}
