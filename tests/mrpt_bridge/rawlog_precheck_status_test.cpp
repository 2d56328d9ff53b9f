// The rawlog pre-check on a rotating LiDAR's scans and a robot's battery state: walked to their
// end as MRPT writes them, each size MRPT allocates a dynamic matrix or vector by (whose aligned
// allocator returns null on a size it cannot give, and MRPT writes through it) damage past its
// bound, in bytes MRPT wrote.
#include "rawlog_bytes.h"

#include <mrpt/obs/CObservationBatteryState.h>
#include <mrpt/obs/CObservationRotatingScan.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>

namespace {

using upd::test::damageReason;
using upd::test::reasonWith;
using upd::test::serialized;
using upd::test::TempDir;
using upd::test::u32;
using upd::test::walked;

std::string u16(std::uint16_t v) {
  return {static_cast<char>(v & 0xFF), static_cast<char>(v >> 8)};
}

std::string bytesOf(double v) {
  std::string s(sizeof v, '\0');
  std::memcpy(s.data(), &v, sizeof v);
  return s;
}

}  // namespace

TEST(RawlogPrecheck, RotatingScanImageSizesAreBounded) {
  TempDir tmp;
  mrpt::obs::CObservationRotatingScan scan;
  scan.sensorLabel = "OS1";
  scan.lidarModel = "OS1-64";
  scan.rowCount = 3;
  scan.columnCount = 5;
  scan.rangeResolution = 0.01;
  scan.rangeImage.setZero(3, 5);
  scan.intensityImage.setZero(3, 5);
  for (int i = 0; i < 15; ++i) {
    scan.rangeImage(i / 5, i % 5) = static_cast<std::uint16_t>(0x1234 + i);
    scan.intensityImage(i / 5, i % 5) = static_cast<std::uint8_t>(0xA0 + i);
  }
  scan.rangeOtherLayers["STRONGEST"].setZero(3, 5);
  const std::string good = serialized(scan);
  std::string why;
  EXPECT_EQ(walked(good, &why), good.size()) << why;
  std::size_t head = 0;
  EXPECT_EQ(damageReason(tmp, good, &head), "(read)");

  // Each matrix's columns and rows (16 bits each) before its data.
  const std::size_t range_at = good.find(u16(5) + u16(3) + u16(0x1234));
  const std::size_t intensity_at = good.find(u16(5) + u16(3) + "\xA0");
  const std::size_t layers_at = intensity_at + 4 + 15;
  ASSERT_NE(range_at, std::string::npos);
  ASSERT_NE(intensity_at, std::string::npos);
  ASSERT_EQ(good.substr(layers_at, 2), u16(1));
  const struct {
    std::size_t at;
    std::string value, reason;
  } cases[] = {
      {range_at, u16(65535) + u16(65535), "range image pixels 4294836225"},
      {intensity_at, u16(5000) + u16(5000), "intensity image pixels 25000000"},
  };
  for (const auto& k : cases) {
    EXPECT_EQ(reasonWith(tmp, good, k.at, k.value, &head),
              "corrupt CObservationRotatingScan: " + k.reason + " at byte " +
                  std::to_string(head + k.at) + " (more than 16777216 pixels)");
  }
  EXPECT_EQ(reasonWith(tmp, good, layers_at, u16(60000), &head),
            "corrupt CObservationRotatingScan: range layer count 60000 at byte " +
                std::to_string(head + layers_at) + " (more than 256 layers)");
}

TEST(RawlogPrecheck, BatteryStateCountsAreBounded) {
  TempDir tmp;
  mrpt::obs::CObservationBatteryState battery;
  battery.sensorLabel = "BMS";
  battery.voltageMainRobotBattery = 24.2;
  battery.voltageMainRobotBatteryIsValid = true;
  battery.voltageOtherBatteries.resize(3);
  for (int i = 0; i < 3; ++i) battery.voltageOtherBatteries[i] = 1.5 + i;
  battery.voltageOtherBatteriesValid.assign(3, true);
  const std::string good = serialized(battery);
  std::string why;
  EXPECT_EQ(walked(good, &why), good.size()) << why;
  std::size_t head = 0;
  EXPECT_EQ(damageReason(tmp, good, &head), "(read)");

  const std::size_t voltages_at = good.find(u32(3) + bytesOf(1.5));
  const std::size_t valid_at = voltages_at + 4 + 3 * sizeof(double);
  ASSERT_NE(voltages_at, std::string::npos);
  ASSERT_EQ(good.substr(valid_at, 4), u32(3));
  EXPECT_EQ(reasonWith(tmp, good, voltages_at, u32(0xFFFFFFF0u), &head),
            "corrupt CObservationBatteryState: battery voltage count 4294967280 at byte " +
                std::to_string(head + voltages_at) + " (more than 4096 batteries)");
  EXPECT_EQ(reasonWith(tmp, good, valid_at, u32(1u << 31), &head),
            "corrupt CObservationBatteryState: battery validity count 2147483648 at byte " +
                std::to_string(head + valid_at) + " (more than 4096 batteries)");
}
