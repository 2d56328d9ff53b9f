// Compressed depth images (image_transport's compressedDepth plugin) read back: PNG and RVL,
// millimetres and inverse depth, the plugin's older format string, and damaged or foreign
// messages refused with one line.
#include "compressed_depth.h"
#include "error_of.h"
#include "upd/ros1/conversions.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

namespace {

using namespace upd;

// A w x h depth image from 0.4 to ~6 m in whole millimetres, with holes (0) in runs.
core::DepthImage depthWithHoles(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> mm(400, 6000), hole(0, 9);
  core::DepthImage d;
  d.width = w;
  d.height = h;
  d.depth_m.resize(static_cast<std::size_t>(w) * h);
  for (std::size_t i = 0; i < d.depth_m.size(); ++i) {
    const bool gap = hole(rng) == 0 || (i / 7) % 5 == 0;  // scattered holes and runs of them
    d.depth_m[i] = gap ? 0.f : static_cast<float>(mm(rng)) * 0.001f;
  }
  return d;
}

std::string errorOf(const sensor_msgs::CompressedImage& m) {
  return test::errorOf<ros1::MessageError>([&] { ros1::depthFromCompressedDepth(m); });
}

TEST(CompressedDepth, MillimetresComeBackExactlyByPngAndRvl) {
  const core::DepthImage d = depthWithHoles(37, 23, 1);
  for (const char* codec : {"png", "rvl"}) {
    const core::DepthImage back =
        ros1::depthFromCompressedDepth(test::compressedDepthOf(d, "16UC1", codec));
    EXPECT_EQ(back.width, 37);
    EXPECT_EQ(back.height, 23);
    ASSERT_EQ(back.depth_m.size(), d.depth_m.size());
    for (std::size_t i = 0; i < d.depth_m.size(); ++i) {
      // (The raw Image path's value of the same millimetres, holes 0.)
      const float want = static_cast<float>(std::lround(d.depth_m[i] * 1000.f)) * 0.001f;
      ASSERT_EQ(back.depth_m[i], want) << codec << " pixel " << i;
    }
  }
}

TEST(CompressedDepth, InverseDepthComesBackWithinItsQuantization) {
  const core::DepthImage d = depthWithHoles(40, 30, 2);
  const float q = 100.f, a = q * (q + 1.f);
  for (const char* codec : {"png", "rvl"}) {
    const core::DepthImage back =
        ros1::depthFromCompressedDepth(test::compressedDepthOf(d, "32FC1", codec, 10.f, q));
    ASSERT_EQ(back.depth_m.size(), d.depth_m.size());
    for (std::size_t i = 0; i < d.depth_m.size(); ++i) {
      const float z = d.depth_m[i];
      if (z == 0.f) {
        EXPECT_EQ(back.depth_m[i], 0.f) << "a hole stays a hole";
        continue;
      }
      // A code is the truncation of a / z + b: one code step is z^2 / a at depth z.
      EXPECT_NEAR(back.depth_m[i], z, 1.01f * z * z / a + 1e-6f) << codec << " pixel " << i;
    }
  }
}

TEST(CompressedDepth, RvlRoundTripsAnyCodes) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> value(0, 65535), run(0, 40);
  for (int trial = 0; trial < 20; ++trial) {
    core::DepthImage d;
    d.width = 1 + trial * 13;
    d.height = 1 + trial % 7;
    d.depth_m.clear();
    while (d.depth_m.size() < static_cast<std::size_t>(d.width) * d.height) {
      const int n = run(rng);
      const bool zeros = run(rng) % 2 == 0;
      for (int k = 0; k < n; ++k) d.depth_m.push_back(zeros ? 0.f : value(rng) % 9000 * 0.001f);
    }
    d.depth_m.resize(static_cast<std::size_t>(d.width) * d.height);
    const core::DepthImage back =
        ros1::depthFromCompressedDepth(test::compressedDepthOf(d, "16UC1", "rvl"));
    for (std::size_t i = 0; i < d.depth_m.size(); ++i) {
      ASSERT_EQ(back.depth_m[i], static_cast<float>(std::lround(d.depth_m[i] * 1000.f)) * 0.001f)
          << "trial " << trial << " pixel " << i;
    }
  }
}

TEST(CompressedDepth, TheOlderFormatWithoutACodecIsPng) {
  const core::DepthImage d = depthWithHoles(9, 4, 4);
  sensor_msgs::CompressedImage m = test::compressedDepthOf(d, "16UC1", "png");
  m.format = "16UC1; compressedDepth";
  EXPECT_EQ(ros1::depthFromCompressedDepth(m).depth_m.size(), d.depth_m.size());
}

TEST(CompressedDepth, DamagedOrForeignMessagesGiveOneLine) {
  const core::DepthImage d = depthWithHoles(32, 24, 5);
  const sensor_msgs::CompressedImage png = test::compressedDepthOf(d, "16UC1", "png");
  const sensor_msgs::CompressedImage rvl = test::compressedDepthOf(d, "16UC1", "rvl");
  const auto with = [](sensor_msgs::CompressedImage m, auto change) {
    change(m);
    return m;
  };
  const struct {
    sensor_msgs::CompressedImage msg;
    const char* says;
  } cases[] = {
      {with(png, [](auto& m) { m.format = "16UC1; compressedDepth jpeg"; }), "expected '16UC1"},
      {with(png, [](auto& m) { m.format = "bgr8; compressedDepth png"; }), "expected '16UC1"},
      {with(png, [](auto& m) { m.format = "jpeg"; }), "expected '16UC1"},
      {with(png, [](auto& m) { m.data.resize(12); }), "12 bytes of data"},
      {with(png, [](auto& m) { m.data[13] ^= 0xff; }), "not a PNG image"},
      {with(png, [](auto& m) { m.data[m.data.size() / 2] ^= 0x5a; }), "damaged PNG"},
      {with(png, [](auto& m) { m.data.resize(m.data.size() - 20); }), "damaged PNG"},
      {with(rvl, [](auto& m) { m.data.resize(m.data.size() / 2); }), "cut short"},
      {with(rvl, [](auto& m) { m.data.resize(16); }), "no size"},
      {with(rvl, [](auto& m) { std::memset(m.data.data() + 12, 0, 4); }), "RVL size 0 x 24"},
      {with(rvl, [](auto& m) { m.data[15] = 0x40; }), "pixels a side"},
      {with(rvl, [](auto& m) { std::memset(m.data.data() + 20, 0xff, m.data.size() - 20); }),
       "damaged or cut short"},
      {with(test::compressedDepthOf(d, "32FC1", "png"),
            [](auto& m) {
              const float nan = std::nanf("");
              std::memcpy(m.data.data() + 4, &nan, 4);
            }),
       "not finite"},
  };
  for (const auto& c : cases) {
    const std::string e = errorOf(c.msg);
    EXPECT_NE(e.find(c.says), std::string::npos) << "'" << e << "' lacks '" << c.says << "'";
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    EXPECT_NE(e.find("compressed depth image (format '"), std::string::npos) << e;
  }
  // An 8-bit PNG (a colour image's plugin, not the depth one) is named as such.
  sensor_msgs::CompressedImage eight = png;
  std::vector<std::uint8_t> png8;
  cv::imencode(".png", cv::Mat(4, 4, CV_8UC1, cv::Scalar(7)), png8);
  eight.data.resize(12);
  eight.data.insert(eight.data.end(), png8.begin(), png8.end());
  EXPECT_NE(errorOf(eight).find("8-bit, 1 channel(s); a depth image is 16-bit single channel"),
            std::string::npos)
      << errorOf(eight);
}

}  // namespace
