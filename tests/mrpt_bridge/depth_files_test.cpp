// Depth PNGs as `upd analyze --intrinsics` and TUM folders read them: a written image reads
// back to the millimetre; a file that is not a PNG, one whose header claims an image larger than
// kMaxDepthSide a side or kMaxDepthPixels in all (refused before anything is allocated), a
// truncated one and an 8-bit one are refused with a message naming the file and what is wrong;
// a damaged one in one line with libpng's reason and nothing on stderr; an interlaced one reads
// as the plain one; so is a calibration YAML with a field that holds something other than
// numbers.
#include <gtest/gtest.h>
#include <png.h>

#include <opencv2/core.hpp>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "error_of.h"
#include "temp_dir.h"
#include "upd/mrpt_bridge/depth_files.h"

namespace upd {
namespace {

using test::readFileBytes;
using test::writeFileBytes;

// readDepthPng's error on path, or "" when it reads.
std::string readError(const std::string& path) {
  return test::errorOf([&] { mrpt_bridge::readDepthPng(path); });
}

core::DepthImage ramp(int width, int height) {
  core::DepthImage d;
  d.width = width, d.height = height;
  d.depth_m.resize(static_cast<std::size_t>(width) * height);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      d.depth_m[static_cast<std::size_t>(v) * width + u] =
          u == 0 ? 0.f : 0.5f + 0.01f * u + 0.02f * v;  // (column 0: invalid)
    }
  }
  return d;
}

TEST(DepthFiles, WrittenDepthReadsBackToTheMillimetre) {
  const test::TempDir tmp("depth-png");
  const std::string path = (tmp.path() / "d.png").string();
  const core::DepthImage d = ramp(64, 48);
  mrpt_bridge::writeDepthPng(path, d);
  const core::DepthImage r = mrpt_bridge::readDepthPng(path);
  ASSERT_EQ(r.width, 64);
  ASSERT_EQ(r.height, 48);
  for (std::size_t i = 0; i < d.depth_m.size(); ++i) {
    EXPECT_NEAR(r.depth_m[i], d.depth_m[i], 0.0005f + 1e-6f) << "pixel " << i;
  }
}

TEST(DepthFiles, DamagedOrForeignFilesAreRefusedNamingTheFile) {
  const test::TempDir tmp("depth-png-bad");
  const std::string good = (tmp.path() / "good.png").string();
  mrpt_bridge::writeDepthPng(good, ramp(32, 24));
  const std::string bytes = readFileBytes(good);
  ASSERT_GT(bytes.size(), 40u);

  // Not a PNG: text, and a 16-bit TIFF (OpenCV would decode it by its content).
  const std::string text = (tmp.path() / "text.png").string();
  writeFileBytes(text, "depth");
  EXPECT_NE(readError(text).find("text.png: not a PNG image"), std::string::npos)
      << readError(text);
  const std::string tiff = (tmp.path() / "tiff.png").string();
  std::vector<unsigned char> tiff_bytes;
  ASSERT_TRUE(cv::imencode(".tiff", cv::Mat(24, 32, CV_16UC1, cv::Scalar(1000)), tiff_bytes));
  writeFileBytes(tiff, std::string(tiff_bytes.begin(), tiff_bytes.end()));
  EXPECT_NE(readError(tiff).find("tiff.png: not a PNG image"), std::string::npos)
      << readError(tiff);

  // A header claiming 100,000 x 100,000 pixels (40 GB as 16-bit): refused by its size.
  std::string huge = bytes;
  for (std::size_t at : {16u, 20u}) {
    const std::uint32_t side = 100000;
    for (int b = 0; b < 4; ++b) huge[at + b] = static_cast<char>(side >> (24 - 8 * b));
  }
  const std::string big = (tmp.path() / "big.png").string();
  writeFileBytes(big, huge);
  EXPECT_NE(readError(big).find("big.png: 100000 x 100000 pixels by its header"),
            std::string::npos)
      << readError(big);
  // 16,000 x 16,000 (within a side, within OpenCV's own limit of 2^30 pixels: 512 MB that
  // OpenCV would allocate): refused by its pixels.
  for (std::size_t at : {16u, 20u}) {
    const std::uint32_t side = 16000;
    for (int b = 0; b < 4; ++b) huge[at + b] = static_cast<char>(side >> (24 - 8 * b));
  }
  writeFileBytes(big, huge);
  EXPECT_NE(readError(big).find("big.png: 16000 x 16000 pixels by its header"),
            std::string::npos)
      << readError(big);

  // Cut in the middle of its data, and empty.
  const std::string cut = (tmp.path() / "cut.png").string();
  writeFileBytes(cut, bytes.substr(0, bytes.size() / 2));
  EXPECT_NE(readError(cut).find("cut.png: "), std::string::npos);
  const std::string empty = (tmp.path() / "empty.png").string();
  writeFileBytes(empty, "");
  EXPECT_NE(readError(empty).find("empty.png: not a PNG image"), std::string::npos);

  // An 8-bit image.
  const std::string eight = (tmp.path() / "eight.png").string();
  ASSERT_TRUE(cv::imwrite(eight, cv::Mat(24, 32, CV_8UC1, cv::Scalar(7))));
  EXPECT_NE(readError(eight).find("eight.png: 8-bit, 1 channel(s)"), std::string::npos)
      << readError(eight);
}

// A 16-bit grey PNG of d's values in millimetres, Adam7-interlaced (OpenCV writes none), by
// libpng.
void writeInterlaced(const std::string& path, const core::DepthImage& d) {
  FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr) << path;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_init_io(png, f);
  png_set_IHDR(png, info, static_cast<png_uint_32>(d.width), static_cast<png_uint_32>(d.height),
               16, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_ADAM7, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_set_swap(png);  // (the rows below in the host's order, little-endian here)
  std::vector<std::uint16_t> mm(d.depth_m.size());
  for (std::size_t i = 0; i < mm.size(); ++i) {
    mm[i] = static_cast<std::uint16_t>(std::lround(d.depth_m[i] * 1000));
  }
  std::vector<png_bytep> rows(static_cast<std::size_t>(d.height));
  for (int v = 0; v < d.height; ++v) {
    rows[static_cast<std::size_t>(v)] =
        reinterpret_cast<png_bytep>(mm.data() + static_cast<std::size_t>(v) * d.width);
  }
  png_write_image(png, rows.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(f);
}

TEST(DepthFiles, InterlacedPngReadsAsThePlainOne) {
  const test::TempDir tmp("depth-png-interlaced");
  const core::DepthImage d = ramp(37, 29);  // (not a multiple of Adam7's 8 x 8 passes)
  const std::string plain = (tmp.path() / "plain.png").string();
  const std::string interlaced = (tmp.path() / "interlaced.png").string();
  mrpt_bridge::writeDepthPng(plain, d);
  writeInterlaced(interlaced, d);
  ASSERT_EQ(readFileBytes(interlaced).at(28), 1) << "IHDR's interlace method: Adam7";
  const core::DepthImage a = mrpt_bridge::readDepthPng(plain);
  const core::DepthImage b = mrpt_bridge::readDepthPng(interlaced);
  ASSERT_EQ(b.width, 37);
  ASSERT_EQ(b.height, 29);
  ASSERT_EQ(a.depth_m.size(), b.depth_m.size());
  for (std::size_t i = 0; i < a.depth_m.size(); ++i) {
    ASSERT_EQ(a.depth_m[i], b.depth_m[i]) << "pixel " << i;
  }
}

// A damaged PNG: one line naming the file and libpng's reason, and nothing on stderr (libpng's
// own handler prints its errors there, and OpenCV's decoder keeps that handler).
TEST(DepthFiles, DamagedPngIsOneLineAndNothingOnStderr) {
  const test::TempDir tmp("depth-png-damaged");
  const std::string good = (tmp.path() / "good.png").string();
  mrpt_bridge::writeDepthPng(good, ramp(64, 48));
  const std::string bytes = readFileBytes(good);
  ASSERT_GT(bytes.size(), 100u);
  std::string bad_header = bytes, bad_data = bytes;
  bad_header[28] ^= 0x01;  // IHDR's interlace byte: its CRC no longer matches
  for (std::size_t i = 50; i < 60; ++i) bad_data[i] ^= 0x5a;  // inside IDAT's compressed data
  const std::pair<std::string, std::string> cases[] = {
      {bad_header, "damaged PNG (IHDR: CRC error)"},
      {bad_data, "damaged PNG ("},
      {bytes.substr(0, bytes.size() - 20), "damaged PNG ("},  // IEND cut off
  };
  int n = 0;
  for (const auto& [damaged, expected] : cases) {
    const std::string path = (tmp.path() / ("damaged" + std::to_string(n++) + ".png")).string();
    writeFileBytes(path, damaged);
    testing::internal::CaptureStderr();
    const std::string what = readError(path);
    const std::string printed = testing::internal::GetCapturedStderr();
    EXPECT_NE(what.find("depth image " + path + ": " + expected), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_EQ(printed, "") << path;
  }
}

// The calibrations users have load: ROS's camera_info (comments, a quoted name), RTAB-Map's
// (its lists over several lines, a local_transform) and what OpenCV's own writer gives
// (!!opencv-matrix with its dt).
TEST(DepthFiles, RosRtabmapAndOpenCvCalibrationsLoad) {
  const test::TempDir tmp("depth-yaml-good");
  const std::string ros = (tmp.path() / "ros.yaml").string();
  std::ofstream(ros) << "# from camera_calibration\nimage_width: 640\nimage_height: 480\n"
                        "camera_name: 'head camera'\ncamera_matrix:\n  rows: 3\n  cols: 3\n"
                        "  data: [525, 0, 319.5, 0, 525, 239.5, 0, 0, 1]  # pixels\n"
                        "distortion_model: plumb_bob\ndistortion_coefficients:\n  rows: 1\n"
                        "  cols: 5\n  data: [0, 0, 0, 0, 0]\n";
  const std::string rtabmap = (tmp.path() / "rtabmap.yaml").string();
  std::ofstream(rtabmap) << "%YAML:1.0\n---\ncamera_name: \"17\"\nimage_width: 640\n"
                            "image_height: 480\ncamera_matrix:\n   rows: 3\n   cols: 3\n"
                            "   data: [ 525., 0., 3.1950000000000000e+02, 0., 525.,\n"
                            "       2.3950000000000000e+02, 0., 0., 1. ]\nlocal_transform:\n"
                            "   rows: 3\n   cols: 4\n   data: [ 0., 0., 1., 0.1, -1., 0., 0., 0.,\n"
                            "       0., -1., 0., 0.4 ]\n";
  const std::string opencv = (tmp.path() / "opencv.yaml").string();
  {
    cv::FileStorage fs(opencv, cv::FileStorage::WRITE);
    fs << "image_width" << 640 << "image_height" << 480;
    fs << "camera_matrix" << (cv::Mat_<double>(3, 3) << 525, 0, 319.5, 0, 525, 239.5, 0, 0, 1);
    fs << "distortion_coefficients" << (cv::Mat_<double>(1, 5) << 0.1, 0, 0, 0, 0);
  }
  for (const std::string& path : {ros, rtabmap, opencv}) {
    const mrpt_bridge::DepthCalibration c = mrpt_bridge::loadDepthCalibration(path);
    EXPECT_EQ(c.K.width, 640) << path;
    EXPECT_EQ(c.K.height, 480) << path;
    EXPECT_DOUBLE_EQ(c.K.fx, 525.0) << path;
    EXPECT_DOUBLE_EQ(c.K.cy, 239.5) << path;
    EXPECT_EQ(c.camera_on_robot.has_value(), path == rtabmap) << path;
    EXPECT_EQ(c.has_distortion, path == opencv) << path;
  }
}

// Calibrations the fuzzer found to end or hang the process (OpenCV threw through the reader, or
// its parser looped forever) are refused in one line naming the file and the field or line: a
// matrix element that is a word, bytes in a list, a key with no name, a document marker with
// text after it, text after the document's end, a control byte, a byte beyond ASCII.
TEST(DepthFiles, CalibrationsThatEndedOrHungTheProcessOrAreEmptyAreRefused) {
  const test::TempDir tmp("depth-yaml");
  const std::string not_a_line = "is not a line of a calibration";
  // Each case: the file's name, its text and what the message says after the file's name.
  const std::string cases[][3] = {
      {"ros.yaml",
       "image_width: 16\nimage_height: 12\ncamera_matrix:\n  rows: 3\n"
       "  cols: 3\n  data: [13.1, 0, 7.5, 0, focal, 5.5, 0, 0, 1]\n",
       "'camera_matrix' is not a list of numbers"},
      {"rtabmap.yaml",
       "%YAML:1.0\n---\nimage_width: 16\nimage_height: 12\ncamera_matrix:\n   rows: 3\n"
       "   cols: 3\n   data: [ 13.1, 0., 7.5, 0., 13.1, 5.5, 0., 0., 1. ]\n"
       "distortion_coefficients:\n   rows: 1\n   cols: 5\n"
       "   data: [ 0.1, \"\\xff\\xff\", 0., 0., 0. ]\n",
       "line 12: '   data: [ 0.1, \""},
      // A key with no name (OpenCV's parser threw std::length_error through the reader).
      {"nameless.yaml",
       "%YAML:1.0\n---\nimage_width: 16\nlocal_transform:\n   rows: 3\n"
       "   :d aat[ 0., 0., 1. ]\n",
       "line 6: '   :d aat[ 0., 0., 1. ]' " + not_a_line},
      // A document marker with text after it, and text after the document's end, on which
      // OpenCV's parser loops forever; a control byte, a byte beyond ASCII.
      {"marker.yaml", "%YAML:1.0\n---e:h\nima-\nc", "line 2: '---e:h' " + not_a_line},
      {"ended.yaml", "...\n-", "line 2: text after '...', the end of the document"},
      {"control.yaml", "image_width: 16\nimage_height: 1\x01\n",
       "line 2: byte 1: a control character, not text"},
      {"latin.yaml", "camera_name: \"cam\xe9ra\"\nimage_width: 16\n",
       "line 1: byte 233: not ASCII (a calibration is ASCII)"},
      // Empty, and only a comment and the directive: said so, not as the first field missing.
      {"empty.yaml", "", "empty: no fields"},
      {"comment.yaml", "%YAML:1.0\n---\n# camera: to be calibrated\n", "empty: no fields"},
  };
  for (const auto& [name, text, field] : cases) {
    const std::string path = tmp.file(name);
    writeFileBytes(path, text);
    const std::string what = test::errorOf([&] { mrpt_bridge::loadDepthCalibration(path); });
    EXPECT_NE(what.find("calibration " + path + ": " + field), std::string::npos)
        << name << ": " << what;
  }
}

}  // namespace
}  // namespace upd
