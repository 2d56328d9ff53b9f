// The ROS 1 message conversions: round trips, the occupancy scale, the scored cloud's fields,
// and malformed messages rejected with one line naming the field.
#include "upd/ros1/conversions.h"
#include "error_of.h"

#include <gtest/gtest.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include <cmath>
#include <cstring>
#include <limits>

namespace {

using namespace upd;

core::DepthImage rampDepth(int w, int h) {
  core::DepthImage d;
  d.width = w;
  d.height = h;
  d.depth_m.resize(static_cast<std::size_t>(w) * h);
  for (std::size_t i = 0; i < d.depth_m.size(); ++i) d.depth_m[i] = 0.5f + 0.001f * static_cast<float>(i % 997);
  d.depth_m[3] = 0.f;  // an invalid pixel
  return d;
}

core::CameraIntrinsics smallCamera() {
  core::CameraIntrinsics K;
  K.width = 8;
  K.height = 6;
  K.fx = K.fy = 7.0;
  K.cx = 3.5;
  K.cy = 2.5;
  return K;
}

std::string errorOf(const std::function<void()>& f) {
  return test::errorOf<ros1::MessageError>(f);
}

TEST(RosConversions, DepthRoundTripsThroughBothEncodings) {
  const core::DepthImage d = rampDepth(8, 6);
  for (const char* enc : {"16UC1", "32FC1"}) {
    const sensor_msgs::Image img = ros1::imageFromDepth(d, enc);
    EXPECT_EQ(img.encoding, enc);
    const core::DepthImage back = ros1::depthFromImage(img);
    ASSERT_EQ(back.width, 8);
    ASSERT_EQ(back.height, 6);
    for (std::size_t i = 0; i < d.depth_m.size(); ++i) {
      EXPECT_NEAR(back.depth_m[i], d.depth_m[i], std::string(enc) == "16UC1" ? 5e-4 : 1e-7) << i;
    }
    EXPECT_EQ(back.depth_m[3], 0.f);
  }
}

TEST(RosConversions, CameraInfoRoundTripsAndGivesTheCloudOfDepthToCloud) {
  const core::CameraIntrinsics K = smallCamera();
  const sensor_msgs::CameraInfo info = ros1::cameraInfoFromIntrinsics(K);
  const core::CameraIntrinsics back = ros1::intrinsicsFromCameraInfo(info);
  EXPECT_EQ(back.width, K.width);
  EXPECT_EQ(back.height, K.height);
  EXPECT_EQ(back.fx, K.fx);
  EXPECT_EQ(back.cy, K.cy);
  const core::DepthImage d = rampDepth(8, 6);
  const core::PointCloud c = ros1::cloudFromDepthImage(ros1::imageFromDepth(d, "32FC1"), info);
  const core::PointCloud ref = core::depthToCloud(d, K);
  ASSERT_TRUE(c.isOrganized());
  ASSERT_EQ(c.size(), ref.size());
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!ref.isFinite(i)) {
      EXPECT_FALSE(c.isFinite(i));
      continue;
    }
    EXPECT_FLOAT_EQ(c.x[i], ref.x[i]);
    EXPECT_FLOAT_EQ(c.z[i], ref.z[i]);
  }
}

TEST(RosConversions, PointCloud2RoundTripKeepsLayoutAndNaN) {
  core::PointCloud c;
  c.resizeOrganized(4, 3);
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (i == 5) continue;  // stays NaN
    c.x[i] = static_cast<float>(i);
    c.y[i] = -static_cast<float>(i);
    c.z[i] = 1.f + i;
  }
  const core::PointCloud back = ros1::cloudFromPointCloud2(ros1::pointCloud2FromCloud(c));
  EXPECT_EQ(back.width, 4u);
  EXPECT_EQ(back.height, 3u);
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (i == 5) {
      EXPECT_FALSE(back.isFinite(i));
      continue;
    }
    EXPECT_EQ(back.x[i], c.x[i]);
    EXPECT_EQ(back.y[i], c.y[i]);
    EXPECT_EQ(back.z[i], c.z[i]);
  }
}

TEST(RosConversions, MalformedMessagesGiveOneLineNamingTheField) {
  sensor_msgs::Image img = ros1::imageFromDepth(rampDepth(8, 6), "16UC1");
  sensor_msgs::Image bad = img;
  bad.encoding = "rgb8";
  EXPECT_NE(errorOf([&] { ros1::depthFromImage(bad); }).find("encoding 'rgb8'"), std::string::npos);
  bad = img;
  bad.data.resize(bad.data.size() - 2);
  EXPECT_NE(errorOf([&] { ros1::depthFromImage(bad); }).find("do not match"), std::string::npos);

  sensor_msgs::CameraInfo info = ros1::cameraInfoFromIntrinsics(smallCamera());
  sensor_msgs::CameraInfo zero = info;
  zero.K.fill(0.0);
  EXPECT_NE(errorOf([&] { ros1::intrinsicsFromCameraInfo(zero); }).find("zero intrinsics"),
            std::string::npos);
  sensor_msgs::CameraInfo other = info;
  other.width = 16;
  EXPECT_NE(errorOf([&] { ros1::cloudFromDepthImage(img, other); }).find("but CameraInfo 16 x 6"),
            std::string::npos);

  core::PointCloud c;
  c.push_back(1, 2, 3);
  sensor_msgs::PointCloud2 pc = ros1::pointCloud2FromCloud(c);
  sensor_msgs::PointCloud2 no_z = pc;
  no_z.fields.pop_back();
  EXPECT_NE(errorOf([&] { ros1::cloudFromPointCloud2(no_z); }).find("no field 'z'"),
            std::string::npos);
  sensor_msgs::PointCloud2 short_data = pc;
  short_data.data.pop_back();
  EXPECT_NE(errorOf([&] { ros1::cloudFromPointCloud2(short_data); }).find("do not match"),
            std::string::npos);
  for (const std::string& e : {errorOf([&] { ros1::depthFromImage(bad); })}) {
    EXPECT_EQ(e.find('\n'), std::string::npos) << "one line: " << e;
  }
}

TEST(RosConversions, OccupancyIsPercentNonTraversableAndMinusOneUnknown) {
  maps::GridParams gp;
  gp.extent_m = 2.0;
  gp.cell_size_m = 0.5;
  gp.follow_robot = false;
  maps::TraversabilityGrid grid(gp);
  grid.at(0, 0).hits = 5;
  grid.at(0, 0).logodds_nontrav = -4.f;  // traversable
  grid.at(1, 0).hits = 5;
  grid.at(1, 0).logodds_nontrav = 4.f;  // non-traversable
  grid.at(2, 1).hits = 5;
  grid.at(2, 1).logodds_nontrav = 0.f;  // undecided
  const nav_msgs::OccupancyGrid msg = ros1::occupancyGridFromGrid(grid);
  ASSERT_EQ(msg.info.width, 4u);
  ASSERT_EQ(msg.info.height, 4u);
  EXPECT_FLOAT_EQ(msg.info.resolution, 0.5f);
  EXPECT_DOUBLE_EQ(msg.info.origin.position.x, grid.xMin());
  EXPECT_DOUBLE_EQ(msg.info.origin.position.y, grid.yMin());
  EXPECT_EQ(msg.data[0], 2);    // 1 / (1 + e^4) = 0.018
  EXPECT_EQ(msg.data[1], 98);   // row-major from y min: cell (1, 0)
  EXPECT_EQ(msg.data[4 + 2], 50);
  EXPECT_EQ(msg.data[3], -1);   // never observed
}

TEST(RosConversions, ScoredCloudHasTheSixFieldsWithTheirValues) {
  core::ScoredFrame f;
  f.cloud_world.push_back(1, 2, 3);
  f.cloud_world.push_back(4, 5, 6);
  f.upd.zeta = {0.9f, 0.2f};
  f.classes.label = {core::Label::Traversable, core::Label::NonTraversable};
  f.classes.cost = {0.1f, 1.0f};
  const sensor_msgs::PointCloud2 msg = ros1::pointCloud2FromScored(f);
  std::vector<std::string> names;
  for (const auto& fl : msg.fields) names.push_back(fl.name);
  EXPECT_EQ(names, (std::vector<std::string>{"x", "y", "z", "zeta", "label", "cost"}));
  ASSERT_EQ(msg.width * msg.height, 2u);
  // The fields are packed (a point is 21 bytes): the floats are read byte by byte.
  using Bytes = sensor_msgs::PointCloud2ConstIterator<std::uint8_t>;
  Bytes x(msg, "x"), zeta(msg, "zeta"), cost(msg, "cost"), label(msg, "label");
  const auto get = [](const Bytes& field, std::size_t k) {
    float v = 0;
    std::memcpy(&v, &field[k * sizeof(float)], sizeof v);
    return v;
  };
  EXPECT_EQ(msg.point_step, 21u);
  ++x, ++zeta, ++cost, ++label;
  EXPECT_EQ(get(x, 0), 4.f);
  EXPECT_EQ(get(x, 2), 6.f);
  EXPECT_FLOAT_EQ(get(zeta, 0), 0.2f);
  EXPECT_EQ(*label, 1);
  EXPECT_FLOAT_EQ(get(cost, 0), 1.0f);
  // The xyz part reads back as a cloud.
  EXPECT_EQ(ros1::cloudFromPointCloud2(msg).size(), 2u);
}

TEST(RosConversions, RouteMarkersAndTransforms) {
  const auto m = ros1::routeMarkers({{0, 0}, {1, 0}, {2, 1}}, {{2, 1}}, "map");
  ASSERT_EQ(m.markers.size(), 2u);
  EXPECT_EQ(m.markers[0].points.size(), 3u);
  EXPECT_EQ(m.markers[0].header.frame_id, "map");
  EXPECT_EQ(m.markers[1].points.size(), 1u);
  const auto empty = ros1::routeMarkers({}, {}, "map");
  EXPECT_EQ(empty.markers[0].action, visualization_msgs::Marker::DELETE);

  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  p.translation() = Eigen::Vector3d(1, -2, 0.5);
  const Eigen::Isometry3d back = ros1::isometryFromTransform(ros1::transformFromIsometry(p));
  EXPECT_TRUE(back.isApprox(p, 1e-12));
  geometry_msgs::Transform zero;
  zero.rotation.w = 0;
  EXPECT_THROW(ros1::isometryFromTransform(zero), ros1::MessageError);
}

}  // namespace
