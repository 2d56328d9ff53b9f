// The rawlog pre-check on what robots record beside depth images (3D movements, point clouds, the
// observations of a frame behind one the check does not know): each size MRPT allocates from,
// corrupted in bytes MRPT wrote, is damage at its object.
#include "rawlog_bytes.h"
#include "upd/mrpt_bridge/rawlog_reader.h"

#include <mrpt/maps/CColouredPointsMap.h>
#include <mrpt/maps/CPointsMapXYZI.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/maps/CWeightedPointsMap.h>
#include <mrpt/obs/CActionRobotMovement3D.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/gnss_messages.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationRGBD360.h>
#include <mrpt/obs/CObservationRange.h>
#include <mrpt/obs/CObservationVelodyneScan.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;
using upd::mrpt_bridge::RawlogEntry;
using upd::mrpt_bridge::RawlogReader;
using upd::test::damageReason;
using upd::test::serialized;
using upd::test::TempDir;
using upd::test::u32;
using upd::test::walked;

// A 3D movement's velocity flags and velocities are each a count MRPT resizes to, then the
// elements (MRPT writes 6 of each): a count past 6 is damage, in a collection or bare.
TEST(RawlogPrecheck, ThreeDMovementVelocityCountsAreBounded) {
  TempDir tmp;
  const std::string moved = serialized(mrpt::obs::CActionRobotMovement3D());
  const std::size_t velocities_at = moved.size() - 1 - 8 - 6 * 4 - 4;  // before the timestamp
  const std::size_t flags_at = velocities_at - 6 - 4;
  ASSERT_EQ(moved.substr(flags_at, 4), u32(6));
  ASSERT_EQ(moved.substr(velocities_at, 4), u32(6));
  const std::string head = "\x91" "CActionCollection" + std::string(1, '\0') + u32(1);
  std::size_t before = 0;
  for (const auto& [at, field] : {std::pair{flags_at, "velocity flag count"},
                                  std::pair{velocities_at, "velocity count"}}) {
    const std::string bad = std::string(moved).replace(at, 4, u32(0xFFFFFFFFu));
    const std::string in_collection = damageReason(tmp, head + bad + "\x88", &before);
    EXPECT_EQ(in_collection,
              "corrupt CActionRobotMovement3D (action 1 of 1 in a CActionCollection): " +
                  std::string(field) + " 4294967295 at byte " +
                  std::to_string(before + head.size() + at) + " (more than 6 components)");
    const std::string alone = damageReason(tmp, bad, &before);
    EXPECT_EQ(alone, "corrupt CActionRobotMovement3D: " + std::string(field) +
                         " 4294967295 at byte " + std::to_string(before + at) +
                         " (more than 6 components)");
  }
  EXPECT_EQ(damageReason(tmp, head + moved + "\x88", &before), "(read)");
}

// Range finders of the layouts MRPT reads (versions 0-3: the IDs from 3, the label from 1, the
// timestamp from 2) read, and a corrupt measurement count in each is damage (found by
// fuzz_rawlog: a version-2 list resized to 6.5 GB when the walk knew only version 3).
TEST(RawlogPrecheck, OldRangeFindersAreWalkedAndTheirCountsBounded) {
  TempDir tmp;
  const std::string pose = serialized(mrpt::poses::CPose3D(0.1, 0.0, 0.2, 0.0, 0.0, 0.0));
  const std::string floats(12, '\0'), distance(4, '\0'), label = u32(2) + "US";
  const std::string name = "\x9c" "mrpt::obs::CObservationRange";
  std::size_t before = 0;
  for (int version = 0; version <= 3; ++version) {
    SCOPED_TRACE(version);
    std::string measurements;
    for (int i = 0; i < 2; ++i) {
      measurements += (version >= 3 ? std::string(2, '\0') : std::string()) + pose + distance;
    }
    const std::string head = name + static_cast<char>(version) + floats;
    const std::string tail = (version >= 1 ? label : std::string()) +
                             (version >= 2 ? std::string(8, '\0') : std::string()) + "\x88";
    EXPECT_EQ(damageReason(tmp, head + u32(2) + measurements + tail, &before), "(read)");
    const std::string reason =
        damageReason(tmp, head + u32(2000000000u) + measurements + tail, &before);
    EXPECT_EQ(reason, "corrupt CObservationRange: measurement count 2000000000 at byte " +
                          std::to_string(before + head.size()) + " (more than 65536 measurements)");
  }
}

// A GNSS observation's label and message count, corrupted in one MRPT wrote, are damage (found by
// fuzz_rawlog: a label of 4.1 GB, allocated before the stream ended).
TEST(RawlogPrecheck, GnssLabelAndMessageCountAreBounded) {
  TempDir tmp;
  auto gps = mrpt::obs::CObservationGPS::Create();
  gps->sensorLabel = "GNSSLABEL";
  mrpt::obs::gnss::Message_NMEA_GGA gga;
  gga.fields.latitude_degrees = 36.7;
  gps->setMsg(gga);
  const std::string good = serialized(*gps);
  std::size_t before = 0;
  EXPECT_EQ(damageReason(tmp, good, &before), "(read)");
  const std::size_t label_at = good.find(u32(9) + "GNSSLABEL");
  const std::size_t count_at =
      label_at + 4 + 9 + serialized(mrpt::poses::CPose3D()).size() + 1;  // after the flag
  ASSERT_EQ(good.substr(count_at, 4), u32(1));
  const std::string long_label = std::string(good).replace(label_at, 4, u32(0xF6000000u));
  const std::string label = damageReason(tmp, long_label, &before);
  EXPECT_EQ(label, "corrupt CObservationGPS: sensor label length 4127195136 at byte " +
                       std::to_string(before + label_at) + " (more than 65536 bytes)");
  const std::string many = std::string(good).replace(count_at, 4, u32(5000));
  const std::string count = damageReason(tmp, many, &before);
  EXPECT_EQ(count, "corrupt CObservationGPS: message count 5000 at byte " +
                       std::to_string(before + count_at) + " (more than 1024 messages)");
}

// A GNSS observation holding a message of every type MRPT builds (a Novatel frame's body and
// Topcon's satellites not empty) is walked to its end; a corrupt Novatel frame body length (MRPT allocated and
// zeroed 1 GiB for one, 2.3 s) or Topcon satellite count (1 GiB, 0.6 s) is damage at its byte.
TEST(RawlogPrecheck, GnssMessagesAreWalked) {
  namespace gnss = mrpt::obs::gnss;
  TempDir tmp;
  auto gps = mrpt::obs::CObservationGPS::Create();
  for (int type = 0; type < 5000; ++type) {
    // (emplace: gnss_message_ptr's assignment copies the message and leaks the one it held)
    auto* m = gnss::gnss_message::Factory(static_cast<gnss::gnss_message_type_t>(type));
    if (m) gps->messages.emplace(m->message_type, gnss::gnss_message_ptr(m));
  }
  ASSERT_GE(gps->messages.size(), 20u);
  auto& frame = dynamic_cast<gnss::Message_NV_OEM6_GENERIC_FRAME&>(
      *gps->messages[gnss::NV_OEM6_GENERIC_FRAME].get());
  frame.msg_body = {0x11, 0x22, 0x33, 0x44};  // MRPT reads back 4 bytes of a body
  auto& sats = dynamic_cast<gnss::Message_TOPCON_SATS&>(*gps->messages[gnss::TOPCON_SATS].get());
  sats.USIs = {3, 7, 9};
  sats.ELs = {40, 50, 60};
  sats.AZs = {0x2A5A, 120, 300};
  // (Novatel's ranges and versions stay empty: MRPT packs them to 1-byte alignment, their lists
  // included, and UBSan reports any call on those lists from an instrumented build.)
  const std::string good = serialized(*gps);
  std::string why;
  EXPECT_EQ(walked(good, &why), good.size()) << why;
  std::size_t before = 0;
  EXPECT_EQ(damageReason(tmp, good, &before), "(read)");

  const std::size_t body_at = good.find(u32(4) + "\x11\x22\x33\x44");
  ASSERT_NE(body_at, std::string::npos);
  EXPECT_EQ(damageReason(tmp, std::string(good).replace(body_at, 4, u32(1u << 30)), &before),
            "corrupt CObservationGPS: Novatel frame body length 1073741824 at byte " +
                std::to_string(before + body_at) + " (more than 65536 bytes)");
  const std::size_t ids_at = good.find(u32(3) + "\x03\x07\x09");
  ASSERT_NE(ids_at, std::string::npos);
  EXPECT_EQ(damageReason(tmp, std::string(good).replace(ids_at, 4, u32(1u << 30)), &before),
            "corrupt CObservationGPS: satellite ID count 1073741824 at byte " +
                std::to_string(before + ids_at) + " (more than 4096 satellites)");
  const std::size_t azimuths_at = good.find(u32(3) + "\x5A\x2A");
  ASSERT_NE(azimuths_at, std::string::npos);
  EXPECT_EQ(damageReason(tmp, std::string(good).replace(azimuths_at, 4, u32(0xFFFFFFF0u)), &before),
            "corrupt CObservationGPS: azimuth count 4294967280 at byte " +
                std::to_string(before + azimuths_at) + " (more than 4096 satellites)");
  // A block length other than the type's, or a type MRPT does not know: MRPT says so.
  mrpt::obs::CObservationGPS one;
  one.setMsg(gnss::Message_NV_OEM6_BESTPOS());
  const std::string bestpos = serialized(one);
  const std::size_t type_at = bestpos.find(u32(gnss::NV_OEM6_BESTPOS));
  ASSERT_NE(type_at, std::string::npos);
  for (const std::string& bad : {std::string(bestpos).replace(type_at + 4, 4, u32(7)),
                                 std::string(bestpos).replace(type_at, 4, u32(4999))}) {
    const std::string reason = damageReason(tmp, bad, &before);
    EXPECT_NE(reason, "(read)");
    EXPECT_EQ(reason.find("corrupt CObservationGPS:"), std::string::npos) << reason;
  }
}

// A Velodyne scan as MRPT writes it (version 2: raw packets, a calibration, points with their
// timestamps, azimuths, laser IDs and the points of each laser) is walked to its end; each count
// MRPT resizes a list to, corrupted, is damage at its byte.
TEST(RawlogPrecheck, VelodyneScanCountsAreBounded) {
  TempDir tmp;
  mrpt::obs::CObservationVelodyneScan scan;
  scan.sensorLabel = "VLP16";
  scan.scan_packets.resize(3);
  scan.calibration.laser_corrections.resize(16);
  auto& cloud = scan.point_cloud;
  for (int i = 0; i < 5; ++i) {
    cloud.x.push_back(1.0f + i);
    cloud.y.push_back(2.0f);
    cloud.z.push_back(0.5f);
    cloud.intensity.push_back(200);
    cloud.timestamp.push_back(mrpt::Clock::fromDouble(100.0 + i));
    cloud.azimuth.push_back(0.1f * i);
    cloud.laser_id.push_back(static_cast<int16_t>(i));
  }
  cloud.pointsForLaserID = {{0, 1, 2}, {3, 4}};
  const std::string good = serialized(scan);
  std::string why;
  EXPECT_EQ(walked(good, &why), good.size()) << why;
  std::size_t before = 0;
  EXPECT_EQ(damageReason(tmp, good, &before), "(read)");
  using Scan = mrpt::obs::CObservationVelodyneScan;
  const std::size_t label_at = good.find(u32(5) + "VLP16");
  ASSERT_NE(label_at, std::string::npos);
  // After the label, the range limits and the sensor pose: packets, lasers, points; at the end,
  // the per-laser lists (before the two lists of 3 and 2 points and the end flag).
  const std::size_t packets_at =
      label_at + 4 + 5 + 2 * sizeof(double) + serialized(mrpt::poses::CPose3D()).size();
  const std::size_t lasers_at = packets_at + 4 + 3 * sizeof(Scan::TVelodyneRawPacket);
  const std::size_t x_at = lasers_at + 4 + 16 * sizeof(mrpt::obs::VelodyneCalibration::PerLaserCalib);
  const std::size_t per_laser_at = good.size() - 1 - (4 + 3 * 8) - (4 + 2 * 8) - 4;
  const struct {
    std::size_t at;
    std::uint32_t written, corrupt;
    std::string field, bound;
  } cases[] = {
      {packets_at, 3, 0xFFFFFFF0u, "packet count 4294967280", "65536 packets"},
      {lasers_at, 16, 5000000u, "laser count 5000000", "4096 lasers"},
      {x_at, 5, 1u << 30, "point x count 1073741824", "16777216 points"},
      {per_laser_at, 2, 5000u, "points-per-laser list count 5000", "4096 lasers"},
      {per_laser_at + 4, 3, 1u << 30, "laser point count 1073741824", "16777216 points"},
  };
  for (const auto& k : cases) {
    ASSERT_EQ(good.substr(k.at, 4), u32(k.written)) << k.field;
    EXPECT_EQ(damageReason(tmp, std::string(good).replace(k.at, 4, u32(k.corrupt)), &before),
              "corrupt CObservationVelodyneScan: " + k.field + " at byte " +
                  std::to_string(before + k.at) + " (more than " + k.bound + ")");
  }
}

// A CObservationRGBD360 keeps its cameras' range images in MRPT's aligned matrices, sized from
// the rows and columns before the pixels (a corrupt size can end the process there): each
// camera's sides are bounded as an image's.
TEST(RawlogPrecheck, Rgbd360RangeImageSizesAreBounded) {
  TempDir tmp;
  mrpt::obs::CObservationRGBD360 rig;
  rig.hasRangeImage = true;
  rig.rangeImages[0].setZero(31, 41);
  rig.rangeImages[1].setZero(23, 19);
  rig.hasIntensityImage = true;
  for (auto& image : rig.intensityImages) {
    image.resize(12, 10, mrpt::img::CH_GRAY);
    image.filledRectangle(0, 0, 11, 9, mrpt::img::TColor(0, 0, 0));
  }
  rig.sensorLabel = "RIG360";
  const std::string good = serialized(rig);
  std::string why;
  EXPECT_EQ(walked(good, &why), good.size()) << why;
  std::size_t before = 0;
  EXPECT_EQ(damageReason(tmp, good, &before), "(read)");
  const std::size_t first = good.find(u32(31) + u32(41)), second = good.find(u32(23) + u32(19));
  ASSERT_NE(first, std::string::npos);
  ASSERT_NE(second, std::string::npos);
  const struct {
    std::size_t at;
    std::string corrupt, field, bound;
    std::size_t named_at;
  } cases[] = {
      {first, u32(70000), "range image rows 70000", "65535 rows", first},
      {second + 4, u32(0xFFFFFFFFu), "range image columns 4294967295", "65535 columns", second + 4},
      {second, u32(60000) + u32(60000), "range image pixels 3600000000", "16777216 pixels", second},
  };
  for (const auto& k : cases) {
    EXPECT_EQ(damageReason(tmp, std::string(good).replace(k.at, k.corrupt.size(), k.corrupt),
                           &before),
              "corrupt CObservationRGBD360: " + k.field + " at byte " +
                  std::to_string(before + k.named_at) + " (more than " + k.bound + ")");
  }
}

// MRPT reads a bool as a raw byte into the bool: a flag byte other than 0 or 1 (MRPT writes no
// other) is a bool whose every use is undefined (found by fuzz_rawlog under UBSan: a 3D scan's
// intensity image flag of 3, loaded by the cloud conversion). Each flag the walk reads is damage
// at any other value.
TEST(RawlogPrecheck, FlagsOtherThanZeroOrOneAreDamage) {
  TempDir tmp;
  mrpt::obs::CObservation3DRangeScan scan;
  scan.hasPoints3D = false;
  scan.hasRangeImage = true;
  scan.rangeImage_setSize(4, 5);
  scan.rangeImage.setZero();
  const std::string depth = serialized(scan);
  const std::size_t sides_at = depth.find(u32(4) + u32(5));
  ASSERT_NE(sides_at, std::string::npos);
  const std::size_t intensity_at = sides_at + 8 + 4 * 5 * 2;  // after the range image
  ASSERT_EQ(depth[intensity_at], '\0');
  ASSERT_EQ(depth[sides_at - 5], '\1');  // the range image flag, before rangeUnits
  mrpt::obs::CObservationOdometry odometry;
  const std::string wheels = serialized(odometry);
  const std::size_t encoders_at = wheels.size() - 1 - 1 - 1;  // encoders, velocities, end flag
  ASSERT_EQ(wheels[encoders_at], '\0');
  const struct {
    std::string bytes;
    std::size_t at;
    std::string why;
  } cases[] = {
      {depth, intensity_at, "corrupt CObservation3DRangeScan: intensity image flag 3"},
      {depth, sides_at - 5, "corrupt CObservation3DRangeScan: range image flag 3"},
      {wheels, encoders_at, "corrupt CObservationOdometry: encoders flag 3"},
  };
  std::size_t before = 0;
  for (const auto& k : cases) {
    ASSERT_EQ(damageReason(tmp, k.bytes, &before), "(read)");
    std::string bad = k.bytes;
    bad[k.at] = '\3';
    EXPECT_EQ(damageReason(tmp, bad, &before),
              k.why + " at byte " + std::to_string(before + k.at) + " (a flag is 0 or 1)");
  }
}

// A 3D scan's pixel labels as MRPT writes them (a label matrix, label names) are walked to the
// scan's end; the matrix sides MRPT resizes to, the name count and a name's length, corrupted,
// are damage at their bytes.
TEST(RawlogPrecheck, PixelLabelSizesAreBounded) {
  TempDir tmp;
  mrpt::obs::CObservation3DRangeScan scan;
  scan.hasPoints3D = false;
  auto* labels = new mrpt::obs::TPixelLabelInfo<2>();
  labels->setSize(3, 7);
  labels->setLabelName(1, "floor");
  labels->setLabelName(5, "wall");
  scan.pixelLabels = mrpt::obs::TPixelLabelInfoBase::Ptr(labels);
  const std::string good = serialized(scan);
  std::string why;
  EXPECT_EQ(walked(good, &why), good.size()) << why;
  std::size_t before = 0;
  EXPECT_EQ(damageReason(tmp, good, &before), "(read)");
  const std::size_t rows_at = good.find(u32(3) + u32(7));
  const std::size_t names_at = good.find(u32(2) + u32(1) + u32(5) + "floor");
  const std::size_t wall_at = good.find(u32(4) + "wall");
  ASSERT_NE(rows_at, std::string::npos);
  ASSERT_NE(names_at, std::string::npos);
  ASSERT_NE(wall_at, std::string::npos);
  const struct {
    std::size_t at;
    std::uint32_t corrupt;
    std::string field, bound;
  } cases[] = {
      {rows_at, 70000, "pixel label rows 70000", "65535 rows"},
      {names_at, 1u << 30, "label name count 1073741824", "65536 names"},
      {wall_at, 0xF0000000u, "label name length 4026531840", "65536 bytes"},
  };
  for (const auto& k : cases) {
    EXPECT_EQ(damageReason(tmp, std::string(good).replace(k.at, 4, u32(k.corrupt)), &before),
              "corrupt CObservation3DRangeScan: " + k.field + " at byte " +
                  std::to_string(before + k.at) + " (more than " + k.bound + ")");
  }
}

// A point cloud observation's map: MRPT resizes every field to the count it reads (its aligned
// allocator does not fail: a corrupt count had the process killed for memory, 22 GB resident)
// and a coloured map's channels to counts of their own. Each is bounded as a 3D scan's points, in
// every points map class; sound clouds and a null one read.
TEST(RawlogPrecheck, PointCloudCountsAreBounded) {
  TempDir tmp;
  const mrpt::maps::CPointsMap::Ptr maps[] = {
      mrpt::maps::CSimplePointsMap::Create(), mrpt::maps::CColouredPointsMap::Create(),
      mrpt::maps::CPointsMapXYZI::Create(), mrpt::maps::CWeightedPointsMap::Create()};
  std::size_t before = 0;
  for (const auto& map : maps) {
    const std::string name = map->GetRuntimeClass()->className;
    SCOPED_TRACE(name);
    for (int i = 0; i < 5; ++i) map->insertPoint(0.1f * i, 0.2f, 0.3f);
    mrpt::obs::CObservationPointCloud o;
    o.pointcloud = map;
    const std::string good = serialized(o);
    EXPECT_EQ(damageReason(tmp, good, &before), "(read)");
    const std::size_t count_at = good.find(name) + name.size() + 1;  // after the version byte
    ASSERT_EQ(good.substr(count_at, 4), u32(5));
    std::vector<std::pair<std::size_t, std::string>> counts = {{count_at, "point count"}};
    if (name == "mrpt::maps::CColouredPointsMap") {
      const std::size_t red_at = count_at + 4 + 15 * 4;
      ASSERT_EQ(good.substr(red_at, 4), u32(5));
      counts.push_back({red_at, "red count"});
    }
    for (const auto& [at, field] : counts) {
      const std::string reason =
          damageReason(tmp, std::string(good).replace(at, 4, u32(0xFFFFFFFFu)), &before);
      EXPECT_EQ(reason, "corrupt CObservationPointCloud: " + field + " 4294967295 at byte " +
                            std::to_string(before + at) + " (more than 16777216 points)");
    }
  }
  mrpt::obs::CObservationPointCloud none;
  EXPECT_EQ(damageReason(tmp, serialized(none), &before), "(read)");
}

// A walk of a whole frame would stop at the first observation of a layout it does not know (a
// point cloud's map options), and MRPT would read the rest unchecked (found by fuzz_rawlog: a
// coloured cloud's channel count, behind an IMU reading the walk did not know then, made MRPT
// allocate gigabytes). The reader hands MRPT a frame one observation at a time, each checked at
// its own start; an element of another kind (found by fuzz_rawlog: a CActionCollection in a
// frame, whose action count MRPT resized its list to, 6.5 GB), or a missing end flag, is damage;
// a version-0 frame's timestamp is set on its observations, as MRPT does.
TEST(RawlogPrecheck, FrameElementsAreEachCheckedAtTheirStart) {
  TempDir tmp;
  auto cloud = mrpt::obs::CObservationPointCloud::Create();
  auto points = mrpt::maps::CSimplePointsMap::Create();
  points->insertPoint(1.0f, 2.0f, 0.5f);
  cloud->pointcloud = points;
  mrpt::obs::CSensoryFrame frame;
  frame.insert(cloud);
  frame.insert(cloud);
  const std::string good = serialized(frame);
  std::string why;
  EXPECT_EQ(walked(good, &why), 0u) << "the walk was to stop at the first cloud's map options";
  std::size_t before = 0;
  EXPECT_EQ(damageReason(tmp, good, &before), "(read)");
  const std::string name = "CSimplePointsMap";
  const std::size_t count_at = good.rfind(name) + name.size() + 1;
  const std::string reason =
      damageReason(tmp, std::string(good).replace(count_at, 4, u32(0xFFFFFFFFu)), &before);
  EXPECT_EQ(reason, "corrupt CObservationPointCloud (observation 2 of 2 in a CSensoryFrame): "
                    "point count 4294967295 at byte " + std::to_string(before + count_at) +
                        " (more than 16777216 points)");
  const std::string v2 = "\x8D" "CSensoryFrame\x02" + u32(1);
  EXPECT_EQ(damageReason(tmp, v2 + serialized(mrpt::poses::CPose2D(1, 2, 0)) + "\x88", &before),
            "corrupt CSensoryFrame: observation 1 of 1 is a CPose2D, not an observation");
  const std::string collection = "\x9D" "mrpt::obs::CActionCollection" + std::string(1, '\0') +
                                 u32(0xFFFFFFF0u) + "\x88";
  EXPECT_EQ(damageReason(tmp, v2 + collection + "\x88", &before),
            "corrupt CSensoryFrame: observation 1 of 1 is a CActionCollection, not an observation");
  mrpt::obs::CObservationComment comment;
  EXPECT_EQ(damageReason(tmp, v2 + serialized(comment) + "\x77", &before),
            "corrupt CSensoryFrame: no end flag after its 1 observation");
  const std::int64_t ticks = 0x0102030405060708;
  std::string stamp(8, '\0');
  for (int i = 0; i < 8; ++i) stamp[i] = static_cast<char>((ticks >> (8 * i)) & 0xFF);
  const fs::path file = tmp.path() / "v0.rawlog";
  const std::string v0 = "\x8D" "CSensoryFrame" + std::string(1, '\0') + u32(7) + stamp + u32(1) +
                         serialized(comment) + "\x88";
  std::ofstream(file, std::ios::binary).write(v0.data(), static_cast<std::streamsize>(v0.size()));
  RawlogReader reader(file.string());
  RawlogEntry e;
  ASSERT_TRUE(reader.next(e));
  EXPECT_EQ(e.observation->timestamp, mrpt::Clock::time_point(mrpt::Clock::duration(ticks)));
}

}  // namespace
