// The rawlog pre-check against MRPT 2.5.8's own writer: every object MRPT writes is walked to its
// end (the check follows the layout byte for byte), and each size MRPT would allocate from,
// corrupted in a file written here, is damage naming the object, the field and its byte.
#include "../../libs/mrpt_bridge/src/rawlog_precheck.h"
#include "rawlog_bytes.h"
#include "rawlog_damage.h"
#include "temp_dir.h"
#include "upd/mrpt_bridge/rawlog_reader.h"

#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/math/CMatrixD.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CActionRobotMovement3D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationRange.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/poses/CPosePDFGaussianInf.h>
#include <mrpt/poses/CPosePDFGrid.h>
#include <mrpt/poses/CPosePDFParticles.h>
#include <mrpt/poses/CPosePDFSOG.h>
#include <mrpt/serialization/CArchive.h>

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

namespace {

namespace fs = std::filesystem;
using upd::mrpt_bridge::RawlogEntry;
using upd::mrpt_bridge::RawlogError;
using upd::mrpt_bridge::RawlogReader;
using upd::test::damageReason;
using upd::test::serialized;
using upd::test::TempDir;
using upd::test::u32;
using upd::test::walked;

mrpt::obs::CObservation2DRangeScan::Ptr scan2D() {
  auto s = mrpt::obs::CObservation2DRangeScan::Create();
  s->resizeScan(777);
  s->setScanHasIntensity(true);
  s->sensorLabel = "LASERLABEL";
  return s;
}

mrpt::obs::CObservation3DRangeScan::Ptr scan3D() {
  auto d = mrpt::obs::CObservation3DRangeScan::Create();
  d->hasPoints3D = true;
  d->resizePoints3DVectors(555);
  d->hasRangeImage = true;
  d->rangeImage_setSize(33, 44);
  d->hasIntensityImage = true;
  d->intensityImage.resize(44, 33, mrpt::img::CH_RGB);
  d->hasConfidenceImage = true;
  d->confidenceImage.resize(44, 33, mrpt::img::CH_GRAY);
  d->rangeImageOtherLayers["STRONGEST"].resize(33, 44);
  // (Resized matrices and images hold whatever the memory held: zeros, so that the sizes the
  // tests look for are found only where they are.)
  d->rangeImage.setZero();
  d->rangeImageOtherLayers["STRONGEST"].setZero();
  d->intensityImage.filledRectangle(0, 0, 43, 32, mrpt::img::TColor(0, 0, 0));
  d->confidenceImage.filledRectangle(0, 0, 43, 32, mrpt::img::TColor(0, 0, 0));
  d->sensorLabel = "DEPTH";
  return d;
}

mrpt::obs::CObservationImage::Ptr greyImage() {
  auto o = mrpt::obs::CObservationImage::Create();
  o->image.resize(37, 29, mrpt::img::CH_GRAY);
  o->image.filledRectangle(0, 0, 36, 28, mrpt::img::TColor(0, 0, 0));
  return o;
}

mrpt::obs::CObservationStereoImages::Ptr stereo() {
  auto o = mrpt::obs::CObservationStereoImages::Create();
  o->imageLeft.resize(48, 40, mrpt::img::CH_RGB);
  o->imageLeft.filledRectangle(0, 0, 47, 39, mrpt::img::TColor(10, 200, 30));
  o->imageRight.resize(50, 40, mrpt::img::CH_RGB);
  o->imageRight.filledRectangle(0, 0, 49, 39, mrpt::img::TColor(30, 20, 100));
  o->hasImageRight = true;
  o->sensorLabel = "STEREO";
  return o;
}

mrpt::obs::CObservationRange::Ptr sonars() {
  auto o = mrpt::obs::CObservationRange::Create();
  for (int i = 0; i < 3; ++i) {
    mrpt::obs::CObservationRange::TMeasurement m;
    m.sensorID = static_cast<std::uint16_t>(i);
    m.sensedDistance = 0.5f + i;
    o->sensedData.push_back(m);
  }
  o->sensorConeApperture = 0.3f;  // the bytes before the count: 9a 99 99 3e
  o->sensorLabel = "SONARS";
  return o;
}

mrpt::obs::CObservationIMU::Ptr inertial() {
  auto o = mrpt::obs::CObservationIMU::Create();
  o->set(mrpt::obs::IMU_Z_ACC, 9.8);
  o->sensorLabel = "IMULABEL";
  return o;
}

mrpt::obs::CObservationOdometry::Ptr wheels(bool encoders) {
  auto o = mrpt::obs::CObservationOdometry::Create();
  o->odometry = mrpt::poses::CPose2D(1.0, 0.5, 0.1);
  o->hasEncodersInfo = o->hasVelocities = encoders;
  o->sensorLabel = "WHEELS";
  return o;
}

mrpt::obs::CObservationComment::Ptr note() {
  auto o = mrpt::obs::CObservationComment::Create();
  o->text = "COMMENTTEXT";
  return o;
}

// Every field of every object MRPT writes is where the check expects it: the walk ends exactly at
// the object's end, with nothing found impossible.
TEST(RawlogPrecheck, ObjectsMrptWritesAreWalkedToTheirEnd) {
  const bool jpeg_off = mrpt::img::CImage::DISABLE_JPEG_COMPRESSION();
  for (bool jpeg : {false, true}) {
    mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(!jpeg);
    mrpt::obs::CSensoryFrame frame;
    frame.insert(scan2D());
    frame.insert(scan3D());
    frame.insert(greyImage());
    frame.insert(stereo());
    frame.insert(note());
    frame.insert(sonars());
    frame.insert(inertial());
    frame.insert(wheels(true));
    frame.insert(wheels(false));
    mrpt::obs::CActionCollection actions;
    mrpt::obs::CActionRobotMovement2D odometry;
    odometry.estimationMethod = mrpt::obs::CActionRobotMovement2D::emOdometry;
    actions.insert(odometry);
    // Scan matching with each pose distribution (the walk goes through each to the next).
    const mrpt::poses::CPose2D mean(0.3, 0.1, 0.02);
    const mrpt::poses::CPosePDF::Ptr pdfs[] = {
        mrpt::poses::CPosePDFGaussian::Create(mean), mrpt::poses::CPosePDFGaussianInf::Create(mean),
        mrpt::poses::CPosePDFParticles::Create(4), mrpt::poses::CPosePDFSOG::Create(2),
        mrpt::poses::CPosePDFGrid::Create(-0.5, 0.5, -0.5, 0.5, 0.5, M_PI / 2, -M_PI, M_PI)};
    for (const auto& pdf : pdfs) {
      mrpt::obs::CActionRobotMovement2D matched;
      matched.estimationMethod = mrpt::obs::CActionRobotMovement2D::emScan2DMatching;
      matched.poseChange = mrpt::containers::deepcopy_poly_ptr<mrpt::poses::CPosePDF::Ptr>(pdf);
      actions.insert(matched);
    }
    actions.insert(odometry);
    mrpt::obs::CActionRobotMovement3D moved;
    moved.poseChange.mean = mrpt::poses::CPose3D(0.4, 0.1, 0.0, 0.2, 0.0, 0.0);
    actions.insert(moved);
    actions.insert(odometry);
    const mrpt::serialization::CSerializable::Ptr bare[] = {scan2D(), scan3D(), greyImage(),
                                                            stereo(), note(),   sonars(),
                                                            inertial(), wheels(true)};
    std::vector<const mrpt::serialization::CSerializable*> objects = {&frame, &actions, &moved};
    for (const auto& o : bare) objects.push_back(o.get());
    for (const auto* o : objects) {
      SCOPED_TRACE(std::string(o->GetRuntimeClass()->className) + (jpeg ? " (JPEG)" : ""));
      const std::string bytes = serialized(*o);
      std::string why;
      EXPECT_EQ(walked(bytes, &why), bytes.size());
      EXPECT_EQ(why, "");
    }
  }
  mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(jpeg_off);
}

struct Corruption {
  const char* name;
  std::string object;       ///< the bytes of the object, as MRPT wrote them
  std::string field;        ///< the bytes of the field to corrupt (found once in `object`)
  std::size_t field_skip;   ///< bytes from the start of `field` to the value replaced
  std::string value;        ///< written over the value
  std::string reason_head;  ///< the reason up to " at byte "
  std::string reason_tail;  ///< the reason after the byte
};

std::vector<Corruption> corruptions(bool in_frame) {
  auto wrap = [&](const mrpt::obs::CObservation::Ptr& o) {
    if (!in_frame) return serialized(*o);
    mrpt::obs::CSensoryFrame f;
    f.insert(o);
    return serialized(f);
  };
  const std::string where = in_frame ? " (observation 1 of 1 in a CSensoryFrame): " : ": ";
  const std::string s2 = "corrupt CObservation2DRangeScan" + where;
  const std::string s3 = "corrupt CObservation3DRangeScan" + where;
  const std::string im = "corrupt CObservationImage" + where;
  const std::string st = "corrupt CObservationStereoImages" + where;
  const bool jpeg_off = mrpt::img::CImage::DISABLE_JPEG_COMPRESSION();
  mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(false);
  const std::string stereo_bytes = wrap(stereo());
  mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(true);  // raw colour pixels in the 3D scan
  const std::string scan3d_bytes = wrap(scan3D());
  mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(jpeg_off);
  const std::string ones = u32(0xFFFFFFFFu);
  return {
      {"scan size", wrap(scan2D()), u32(777), 0, ones, s2 + "scan size 4294967295",
       " (more than 1000000 rays)"},
      {"scan size just above", wrap(scan2D()), u32(777), 0, u32(1000001), s2 + "scan size 1000001",
       " (more than 1000000 rays)"},
      {"label", wrap(scan2D()), u32(10) + "LASERLABEL", 0, u32(2200000000u),
       s2 + "sensor label length 2200000000", " (more than 65536 bytes)"},
      {"3D points", scan3d_bytes, u32(555), 0, u32(0x40000000u), s3 + "3D point count 1073741824",
       " (more than 16777216 points)"},
      {"range image rows", scan3d_bytes, u32(33) + u32(44), 0, u32(70000),
       s3 + "range image rows 70000", " (more than 65535 rows)"},
      {"range image pixels", scan3d_bytes, u32(33) + u32(44), 0, u32(60000) + u32(60000),
       s3 + "range image pixels 3600000000", " (more than 16777216 pixels)"},
      // MRPT writes a layer's columns, then its rows, and reads rows, then columns.
      {"range layer", scan3d_bytes, "STRONGEST", 9, u32(70000), s3 + "range layer rows 70000",
       " (more than 65535 rows)"},
      {"intensity image width", scan3d_bytes, u32(static_cast<std::uint32_t>(-44)), 0,
       u32(static_cast<std::uint32_t>(-70000)), s3 + "image width 70000",
       " (more than 65535 pixels)"},
      {"grey image height", wrap(greyImage()), u32(37) + u32(29), 4, u32(0x80000000u),
       im + "image height 2147483648", " (more than 65535 pixels)"},
      {"comment", wrap(note()), u32(11) + "COMMENTTEXT", 0, ones,
       "corrupt CObservationComment" + where + "comment length 4294967295",
       " (more than 16777216 bytes)"},
      {"range measurements", wrap(sonars()), std::string("\x9a\x99\x99\x3e", 4) + u32(3), 4, ones,
       "corrupt CObservationRange" + where + "measurement count 4294967295",
       " (more than 65536 measurements)"},
      {"IMU label", wrap(inertial()), u32(8) + "IMULABEL", 0, ones,
       "corrupt CObservationIMU" + where + "sensor label length 4294967295",
       " (more than 65536 bytes)"},
      {"odometry label", wrap(wheels(true)), u32(6) + "WHEELS", 0, ones,
       "corrupt CObservationOdometry" + where + "sensor label length 4294967295",
       " (more than 65536 bytes)"},
      {"JPEG size", stereo_bytes, u32(48) + u32(40), 8, ones, st + "image JPEG size 4294967295",
       " (more than 268435456 bytes)"},
  };
}

// Each size MRPT would allocate from, corrupted in a rawlog written here, is damage at that object
// before MRPT reads it; the reason names the field, its value and its byte in the file.
TEST(RawlogPrecheck, CorruptSizesAreDamageNamingObjectFieldAndByte) {
  TempDir tmp;
  for (bool in_frame : {true, false}) {
    for (const Corruption& c : corruptions(in_frame)) {
      SCOPED_TRACE(std::string(c.name) + (in_frame ? " in a frame" : " bare"));
      const auto field_at = c.object.find(c.field);
      ASSERT_NE(field_at, std::string::npos);
      ASSERT_EQ(c.object.find(c.field, field_at + 1), std::string::npos) << "not unique";
      mrpt::obs::CObservationComment before;
      before.text = "before";
      const std::string head = serialized(before);
      std::string bytes = head + c.object;
      const std::size_t value_at = head.size() + field_at + c.field_skip;
      bytes.replace(value_at, c.value.size(), c.value);
      const fs::path file = tmp.path() / "corrupt.rawlog";
      std::ofstream(file, std::ios::binary)
          .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      RawlogReader reader(file.string());
      RawlogEntry e;
      ASSERT_TRUE(reader.next(e));
      EXPECT_EQ(e.className(), "CObservationComment");
      try {
        reader.next(e);
        ADD_FAILURE() << "the object was read";
      } catch (const RawlogError& err) {
        EXPECT_EQ(err.objectIndex(), 1u);
        EXPECT_EQ(err.byteOffset(), head.size());
        EXPECT_EQ(err.reason().rfind(c.reason_head + " at byte " + std::to_string(value_at), 0), 0u)
            << err.reason();
        EXPECT_EQ(err.reason().substr(err.reason().size() - c.reason_tail.size()), c.reason_tail);
      }
    }
  }
}

// MRPT decodes an image's JPEG with libjpeg's default error handler, which ends the process on a
// fatal error (found by fuzz_rawlog: an unknown marker after the image data; a JPEG cut by the
// end of the stream), and allocates what the JPEG's header states (libjpeg itself refuses more
// than 65,500 a side): all are damage at the object, found before MRPT decodes it.
TEST(RawlogPrecheck, JpegThatWouldEndTheProcessIsDamage) {
  TempDir tmp;
  const bool jpeg_off = mrpt::img::CImage::DISABLE_JPEG_COMPRESSION();
  mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(false);
  const std::string good = serialized(*stereo());
  mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(jpeg_off);
  const auto size_at = good.find(u32(48) + u32(40)) + 8;  // the left image's JPEG byte count
  ASSERT_NE(size_at, std::string::npos + 8);
  std::uint32_t jpeg_bytes = 0;
  for (int i = 3; i >= 0; --i)
    jpeg_bytes = (jpeg_bytes << 8) | static_cast<std::uint8_t>(good[size_at + i]);
  const std::size_t jpeg_at = size_at + 4;
  ASSERT_EQ(good.substr(jpeg_at, 2), "\xFF\xD8");  // start of image
  ASSERT_EQ(good.substr(jpeg_at + jpeg_bytes - 2, 2),
            "\xFF\xD9");  // end of image
  std::size_t head = 0;
  std::string bad_marker = good;
  bad_marker[jpeg_at + jpeg_bytes - 1] = '\x9A';
  const std::string bad_marker_reason = damageReason(tmp, bad_marker, &head);
  EXPECT_EQ(bad_marker_reason,
            "corrupt CObservationStereoImages: image JPEG of " + std::to_string(jpeg_bytes) +
                " bytes at byte " + std::to_string(head + jpeg_at) +
                " does not decode (Unsupported marker type 0x9a; MRPT's JPEG "
                "reader would end "
                "the process)");
  std::string huge = good;
  const auto sof = huge.find("\xFF\xC0", jpeg_at);  // baseline frame: length, precision, H, W
  ASSERT_LT(sof, jpeg_at + jpeg_bytes);
  huge.replace(sof + 5, 4, std::string("\x40\x00\x40\x00", 4));  // 16384 x 16384
  const std::string huge_reason = damageReason(tmp, huge, &head);
  EXPECT_EQ(huge_reason,
            "corrupt CObservationStereoImages: image JPEG at byte " +
                std::to_string(head + jpeg_at) +
                ": its header says 268435456 pixels (more than 16777216)");
  // The stream ends inside the JPEG's header (found by fuzz_rawlog: a 3D scan's JPEG image cut
  // by the end of the file, which MRPT decoded as far as it went, and libjpeg ended the
  // process: "JPEG datastream contains no image").
  const std::string cut = good.substr(0, jpeg_at + 100);
  EXPECT_EQ(damageReason(tmp, cut, &head),
            "corrupt CObservationStereoImages: image JPEG of " + std::to_string(jpeg_bytes) +
                " bytes at byte " + std::to_string(head + jpeg_at) +
                " is cut short by the end of the stream (MRPT would decode the part there is; "
                "its JPEG reader ends the process on a cut header)");
  EXPECT_EQ(damageReason(tmp, good, &head), "(read)");
}

// Whether MRPT reading the one serialized object ends the process (libjpeg's default error
// handler calls exit), in a child process.
bool mrptReadEndsTheProcess(const std::string& object) {
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    // Registered last, run first: the exit ends the child at once, without the exit handlers of
    // the libraries and the test (a tenth of a second).
    std::atexit([] { _exit(1); });
    if (std::freopen("/dev/null", "w", stderr) == nullptr) _exit(3);
    try {
      mrpt::io::CMemoryStream in;
      in.assignMemoryNotOwn(object.data(), object.size());
      mrpt::serialization::CSerializable::Ptr o;
      mrpt::serialization::archiveFrom(in) >> o;
    } catch (...) {
    }
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return !WIFEXITED(status) || WEXITSTATUS(status) != 0;
}

// The JPEG is decoded as MRPT decodes it, to the byte: an image whose JPEG byte count is cut
// short (the rest of the object as MRPT wrote it) is damage exactly where MRPT's decoder would
// end the process (found by fuzz_rawlog: a scan header cut by the byte count decoded with 10
// zero bytes after it, as the check used to pad it, but ends the process at the count: "Huffman
// table 0x0f was not defined"). Were the check to pass such a cut, the reader here would hand it
// to MRPT and this test's process would end.
TEST(RawlogPrecheck, JpegIsDamageExactlyWhereMrptsDecoderWouldEndTheProcess) {
  TempDir tmp;
  const bool jpeg_off = mrpt::img::CImage::DISABLE_JPEG_COMPRESSION();
  mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(false);
  mrpt::obs::CObservationImage camera;
  camera.image.resize(32, 24, mrpt::img::CH_RGB);
  for (int y = 0; y < 24; y += 4) {
    for (int x = 0; x < 32; x += 4) {
      camera.image.filledRectangle(x, y, x + 3, y + 3,
                                   mrpt::img::TColor(8 * x, 10 * y, 255 - 5 * (x + y)));
    }
  }
  const std::string good = serialized(camera);
  mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(jpeg_off);
  const std::size_t jpeg_at = good.find("\xFF\xD8\xFF");
  ASSERT_NE(jpeg_at, std::string::npos);
  std::uint32_t jpeg_bytes = 0;
  for (int i = 3; i >= 0; --i)
    jpeg_bytes = (jpeg_bytes << 8) | static_cast<std::uint8_t>(good[jpeg_at - 4 + i]);
  ASSERT_EQ(good.substr(jpeg_at + jpeg_bytes - 2, 2), "\xFF\xD9");
  std::size_t head = 0;
  int cuts = 0, ending = 0;
  // Every cut up to the end of the scan header (the markers: tables, frame, scan), then every
  // 13th byte of the entropy-coded data.
  const std::size_t scan = good.find("\xFF\xDA", jpeg_at) - jpeg_at;
  ASSERT_LT(scan, jpeg_bytes);
  for (std::uint32_t k = 0; k <= jpeg_bytes; k += (k < scan + 16 ? 1 : 13)) {
    const std::string cut = good.substr(0, jpeg_at - 4) + u32(k) + good.substr(jpeg_at, k) +
                            good.substr(jpeg_at + jpeg_bytes);
    const bool ends = mrptReadEndsTheProcess(cut);
    const std::string reason = damageReason(tmp, cut, &head);
    EXPECT_EQ(reason.find("image JPEG") != std::string::npos, ends)
        << k << " of " << jpeg_bytes << " JPEG bytes: " << reason;
    ++cuts;
    ending += ends;
  }
  EXPECT_GT(ending, 0);
  EXPECT_LT(ending, cuts);
}

// The frames of MRPT before version 2 carry an ID (and in version 0 a timestamp) before their
// count: that count is bounded as version 2's (found by fuzz_rawlog: a version-0 frame whose
// count, read past the timestamp, was 744,571,766 made MRPT allocate 12 GB of observation
// pointers); a version-0 frame's null observation, whose timestamp MRPT would set through the
// null pointer, is damage; sound old frames read.
TEST(RawlogPrecheck, OldSensoryFramesAreCheckedAsTheCurrentOne) {
  TempDir tmp;
  mrpt::obs::CObservationComment comment;
  comment.text = "old frame";
  const std::string obs = serialized(comment);
  const std::string name = "\x8D" "CSensoryFrame";
  const std::string id = u32(7), stamp(8, '\x01'), end = "\x88";
  const std::string v0 = name + '\x00' + id + stamp, v1 = name + '\x01' + id;
  std::size_t head = 0;
  EXPECT_EQ(damageReason(tmp, v0 + u32(1) + obs + end, &head), "(read)");
  EXPECT_EQ(damageReason(tmp, v1 + u32(1) + obs + end, &head), "(read)");
  const std::string huge = u32(744571766u);
  EXPECT_EQ(damageReason(tmp, v0 + huge + obs + end, &head),
            "corrupt CSensoryFrame: observation count 744571766 at byte " +
                std::to_string(head + v0.size()) + " (more than 4096 observations)");
  EXPECT_EQ(damageReason(tmp, v1 + huge + obs + end, &head),
            "corrupt CSensoryFrame: observation count 744571766 at byte " +
                std::to_string(head + v1.size()) + " (more than 4096 observations)");
  const std::string null_obs = std::string("\x87" "nullptr") + end;
  EXPECT_EQ(damageReason(tmp, v0 + u32(2) + null_obs + obs + end, &head),
            "corrupt CSensoryFrame: observation 1 of 2 is a null object (MRPT sets a version-0 "
            "frame's timestamp through each)");
}

// MRPT reads a class name as a C string, up to its first NUL, whatever its stated length: a
// name of 21 bytes, "CActionCollection" and 4 bytes more from a NUL on, is a CActionCollection
// to MRPT and to the check (found by fuzz_rawlog: its count, 1,665,221,526, made MRPT allocate
// gigabytes of action pointers).
TEST(RawlogPrecheck, ClassNamesEndAtTheirFirstNulAsMrptReadsThem) {
  TempDir tmp;
  const std::string name = std::string("CActionCollection") + std::string("\0\x01\0\0", 4);
  const std::string head = std::string(1, static_cast<char>(0x80 | name.size())) + name + '\0';
  std::size_t before = 0;
  const std::string reason = damageReason(tmp, head + u32(1665221526u) + "\x88", &before);
  EXPECT_EQ(reason,
            "corrupt CActionCollection: action count 1665221526 at byte " +
                std::to_string(before + head.size()) + " (more than 4096 actions)");
  EXPECT_EQ(damageReason(tmp, head + u32(0) + "\x88", &before), "(read)");
}

// MRPT keeps a collection's actions as deep-copying pointers made from what it read cast to a
// CAction: a null object or another class (found by fuzz_rawlog: a CPose2D) was copied
// through a null pointer (SEGV). Both are damage; the two action classes read.
TEST(RawlogPrecheck, CollectionsHoldOnlyActions) {
  TempDir tmp;
  const std::string head = "\x91" "CActionCollection" + std::string(1, '\0') + u32(2);
  mrpt::obs::CActionRobotMovement3D moved;
  const std::string action = serialized(moved);
  std::size_t before = 0;
  EXPECT_EQ(damageReason(tmp, head + std::string("\x87" "nullptr\x88") + action + "\x88", &before),
            "corrupt CActionCollection: action 1 of 2 is a null object");
  EXPECT_EQ(damageReason(tmp, head + serialized(mrpt::poses::CPose2D(1, 2, 0)) + action + "\x88",
                         &before),
            "corrupt CActionCollection: action 1 of 2 is a CPose2D, not an action");
  EXPECT_EQ(damageReason(tmp, head + action + action + "\x88", &before), "(read)");
}

// A TCamera before version 6 (MRPT reads versions 0-6) is walked as MRPT reads it: before version 4
// its intrinsics are a CMatrixD object, which MRPT reallocates to the size it reads before it
// checks the size (found by fuzz_rawlog: a version-2 camera in a 3D scan whose matrix claimed
// 1.7e18 bytes; the allocator returned null and MRPT wrote through it: SEGV).
TEST(RawlogPrecheck, OldCamerasAreWalkedAndTheirMatricesBounded) {
  TempDir tmp;
  const std::string scan = serialized(*scan3D());
  const std::string name = "\x92" "mrpt::img::TCamera";
  const std::string current = name + "\x06";
  const auto camera_at = scan.find(current);
  ASSERT_NE(camera_at, std::string::npos);
  const std::size_t name_at = camera_at + current.size() + 13 * 8 + 8;
  const auto name_length = static_cast<std::uint8_t>(scan[name_at]);  // "camera": < 256
  const std::size_t current_size = name_at + 4 + name_length + 1 + 1 - camera_at;
  ASSERT_EQ(scan[camera_at + current_size - 1], '\x88');
  const std::string doubles = [](int n) { return std::string(8 * n, '\0'); }(6);
  const std::string three = serialized(mrpt::math::CMatrixD(3, 3));
  const std::string resolution = u32(480) + u32(640);
  const auto withCamera = [&](const std::string& camera) {
    return std::string(scan).replace(camera_at, current_size, camera);
  };
  const std::string v0 = name + std::string(1, '\0') + doubles + three +
                         serialized(mrpt::math::CMatrixD(1, 5)) + "\x88";
  const std::string v2 = name + "\x02" + doubles + three + resolution + "\x88";
  const std::string v5 = name + "\x05" + doubles + std::string(7 * 8, '\0') + resolution +
                         u32(3) + "cam\x88";
  std::size_t head = 0;
  for (const std::string* camera : {&v0, &v2, &v5}) {
    EXPECT_EQ(damageReason(tmp, withCamera(*camera), &head), "(read)");
    std::string why;
    EXPECT_EQ(walked(withCamera(*camera), &why), withCamera(*camera).size()) << why;
  }
  std::string huge = v2;
  const std::size_t rows_at = huge.find("CMatrixD") + 9;
  huge.replace(rows_at, 8, u32(2000000000u) + u32(3));
  EXPECT_EQ(damageReason(tmp, withCamera(huge), &head),
            "corrupt CObservation3DRangeScan: camera intrinsics rows 2000000000 at byte " +
                std::to_string(head + camera_at + rows_at) + " (more than 65535 rows)");
}

// Sizes at their bounds are read by MRPT as usual (a 2D scan of 1,000,000 rays).
TEST(RawlogPrecheck, SizesAtTheBoundAreRead) {
  auto s = mrpt::obs::CObservation2DRangeScan::Create();
  s->resizeScan(upd::mrpt_bridge::detail::kMaxScanRays);
  const std::string bytes = serialized(*s);
  std::string why;
  EXPECT_EQ(walked(bytes, &why), bytes.size());
  EXPECT_EQ(why, "");
}

}  // namespace
