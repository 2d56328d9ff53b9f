// The `upd ros` node against a real ROS master on the loopback (roscore on a free port): real
// depth frames in, the grid and the scored cloud out; malformed messages and missing transforms
// stop the robot with one log line; in a generated world, a simulated base that integrates
// /cmd_vel into /odom and tf, and a camera rendered at its pose, the node drives to a goal and
// stops there, and it stops the robot when the frames stop coming.
#include "compressed_depth.h"
#include "real_frame.h"
#include "ros_master.h"
#include "test_data.h"
#include "apps/run_upd.h"

#include "upd/nav/nav_config.h"
#include "upd/ros1/conversions.h"
#include "upd/ros1/ros_base.h"
#include "upd/sim/render.h"
#include "upd/sim/robot.h"
#include "upd/sim/terrain.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <atomic>
#include <functional>
#include <memory>
#include <cmath>
#include <map>
#include <mutex>
#include <thread>

namespace {

using namespace upd;

const std::string kConfigDir = std::string(UPD_SOURCE_DIR) + "/config";

// `upd ros` as a child process, with private parameters as remappings.
std::unique_ptr<test::Child> startNode(const test::RosMasterOnLoopback& master,
                                       std::vector<std::string> extra) {
  std::vector<std::string> argv{UPD_BINARY, "ros", "--config", kConfigDir + "/dune-kinect.ini",
                                "--nav-config", kConfigDir + "/dune-nav.ini"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return std::make_unique<test::Child>(argv, (master.dir() / "upd_ros.log").string());
}

// What the test hears from the node.
struct Outputs {
  std::mutex m;
  nav_msgs::OccupancyGrid::ConstPtr grid;
  sensor_msgs::PointCloud2::ConstPtr cloud;
  geometry_msgs::Twist::ConstPtr cmd;
  int cmds = 0;
};

template <class Pred>
bool spinUntil(Pred pred, double timeout_s, const std::function<void()>& tick = {}) {
  const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(timeout_s);
  ros::WallRate rate(50);
  while (ros::WallTime::now() < until) {
    ros::spinOnce();
    if (tick) tick();
    if (pred()) return true;
    rate.sleep();
  }
  return false;
}

std::size_t countLines(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (auto p = text.find(needle); p != std::string::npos; p = text.find(needle, p + 1)) ++n;
  return n;
}

class RosNode : public ::testing::Test {
 public:
  // One master per process (ros::init once); ctest runs every test in a process of its own.
  static void SetUpTestSuite() {
    master = std::make_unique<test::RosMasterOnLoopback>("upd_test_robot");
  }
  static void TearDownTestSuite() { master.reset(); }
  void SetUp() override {
    nh = std::make_unique<ros::NodeHandle>();
    grid_sub = nh->subscribe<nav_msgs::OccupancyGrid>(
        "/upd/traversability", 1, [this](const nav_msgs::OccupancyGrid::ConstPtr& g) { out.grid = g; });
    cloud_sub = nh->subscribe<sensor_msgs::PointCloud2>(
        "/upd/cloud", 1, [this](const sensor_msgs::PointCloud2::ConstPtr& c) { out.cloud = c; });
    cmd_sub = nh->subscribe<geometry_msgs::Twist>("/cmd_vel", 10,
                                                  [this](const geometry_msgs::Twist::ConstPtr& c) {
                                                    out.cmd = c;
                                                    ++out.cmds;
                                                  });
    depth_pub = nh->advertise<sensor_msgs::Image>("/camera/depth/image_raw", 2);
    packed_pub = nh->advertise<sensor_msgs::CompressedImage>(
        "/camera/depth/image_raw/compressedDepth", 2);
    info_pub = nh->advertise<sensor_msgs::CameraInfo>("/camera/depth/camera_info", 2);
    odom_pub = nh->advertise<nav_msgs::Odometry>("/odom", 5);
    goal_pub = nh->advertise<geometry_msgs::PoseStamped>("/move_base_simple/goal", 1, true);
  }
  void TearDown() override {
    node.reset();
    tf.reset();
    static_tf.reset();
    grid_sub.shutdown();
    cloud_sub.shutdown();
    cmd_sub.shutdown();
    depth_pub.shutdown();
    packed_pub.shutdown();
    info_pub.shutdown();
    odom_pub.shutdown();
    goal_pub.shutdown();
    nh.reset();
  }

  void publishFrame(const core::DepthImage& depth, const core::CameraIntrinsics& K,
                    const std::string& frame, const ros::Time& t, const char* enc = "16UC1") {
    sensor_msgs::CameraInfo info = ros1::cameraInfoFromIntrinsics(K);
    sensor_msgs::Image image = ros1::imageFromDepth(depth, "16UC1");
    image.encoding = enc;
    info.header.frame_id = image.header.frame_id = frame;
    info.header.stamp = image.header.stamp = t;
    info_pub.publish(info);
    depth_pub.publish(image);
  }
  void publishOdom(const Eigen::Isometry3d& pose, double v, double w, const ros::Time& t) {
    if (!tf) tf = std::make_unique<tf2_ros::TransformBroadcaster>();
    tf->sendTransform(ros1::stampedTransform(pose, "odom", "base_link", t));
    nav_msgs::Odometry o;
    o.header.frame_id = "odom";
    o.header.stamp = t;
    o.child_frame_id = "base_link";
    const geometry_msgs::Transform tr = ros1::transformFromIsometry(pose);
    o.pose.pose.position.x = tr.translation.x;
    o.pose.pose.position.y = tr.translation.y;
    o.pose.pose.position.z = tr.translation.z;
    o.pose.pose.orientation = tr.rotation;
    o.twist.twist.linear.x = v;
    o.twist.twist.angular.z = w;
    odom_pub.publish(o);
  }
  // spinUntil's tick: every 0.3 s of wall time, the robot at rest on /odom, then publish(t).
  std::function<void()> restingTick(std::function<void(const ros::Time&)> publish) {
    auto next = std::make_shared<ros::WallTime>();
    return [this, next, publish] {
      if (ros::WallTime::now() < *next) return;
      *next = ros::WallTime::now() + ros::WallDuration(0.3);
      const ros::Time t = ros::Time::now();
      publishOdom(Eigen::Isometry3d::Identity(), 0, 0, t);
      publish(t);
    };
  }
  void sendStatic(const Eigen::Isometry3d& base_camera) {
    static_tf = std::make_unique<tf2_ros::StaticTransformBroadcaster>();
    static_tf->sendTransform(
        ros1::stampedTransform(base_camera, "base_link", "camera_optical", ros::Time::now()));
  }

  static std::unique_ptr<test::RosMasterOnLoopback> master;
  std::unique_ptr<ros::NodeHandle> nh;
  ros::Subscriber grid_sub, cloud_sub, cmd_sub;
  ros::Publisher depth_pub, packed_pub, info_pub, odom_pub, goal_pub;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf;
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_tf;
  std::unique_ptr<test::Child> node;
  Outputs out;
};


std::unique_ptr<test::RosMasterOnLoopback> RosNode::master;

int knownCells(const nav_msgs::OccupancyGrid& g) {
  int n = 0;
  for (const auto v : g.data) n += v >= 0;
  return n;
}

TEST_F(RosNode, RealFramesGiveTheGridAndTheScoredCloudBadOnesOneLineEach) {
  UPD_REQUIRE_SHARED_FILE(png, "rtabmap/rgbd/depth/17.png");
  UPD_REQUIRE_SHARED_FILE(yaml, "rtabmap/rgbd/calib/17.yaml");
  const test::RealFrame f = test::loadRealFrame(png, yaml);
  sendStatic(f.pose_base_optical);
  node = startNode(*master, {"_odom_timeout_s:=2.0"});  // odometry here at 3 Hz only
  std::string frame = "camera_optical", encoding = "16UC1";
  const auto tick = restingTick(
      [&](const ros::Time& t) { publishFrame(f.depth, f.K, frame, t, encoding.c_str()); });
  ASSERT_TRUE(spinUntil([&] { return out.grid && knownCells(*out.grid) > 100 && out.cloud; }, 40,
                        tick))
      << node->log();
  // No map frame in tf: the grid is in odom. 0 traversable .. 100 non-traversable, -1 unknown.
  EXPECT_EQ(out.grid->header.frame_id, "odom");
  int floor = 0;
  for (const auto v : out.grid->data) {
    ASSERT_TRUE(v == -1 || (v >= 0 && v <= 100)) << int(v);
    floor += v >= 0 && v < 50;  // the traversable side: each frame that sees it so lowers it
  }
  std::map<int, int> histogram;
  for (const auto v : out.grid->data) ++histogram[v < 0 ? -1 : v / 10 * 10];
  std::string hist;
  for (const auto& [v, k] : histogram) hist += " " + std::to_string(v) + ":" + std::to_string(k);
  EXPECT_GT(floor, 100) << "the room's floor is traversable; histogram" << hist;
  std::vector<std::string> names;
  for (const auto& fl : out.cloud->fields) names.push_back(fl.name);
  EXPECT_EQ(names, (std::vector<std::string>{"x", "y", "z", "zeta", "label", "cost"}));
  EXPECT_EQ(out.cloud->header.frame_id, "odom");
  std::size_t n = 0, traversable = 0;
  for (sensor_msgs::PointCloud2ConstIterator<std::uint8_t> l(*out.cloud, "label"); l != l.end(); ++l) {
    ASSERT_LE(*l, 2);
    ++n;
    traversable += *l == 0;
  }
  EXPECT_GT(n, 1000u);
  EXPECT_GT(traversable, n / 10);

  // Malformed frames, then a frame tf cannot place: one line each, however many arrive. (Each
  // kind is sent until the node has reported it, then 1.5 s more: a node still busy with the
  // real frames, as under a sanitizer, drops the first ones from its queue.)
  const auto reported = [&](const char* line) {
    return [&node = node, line] { return countLines(node->log(), line) > 0; };
  };
  encoding = "rgb8";
  EXPECT_TRUE(spinUntil(reported("encoding 'rgb8'"), 30, tick)) << node->log();
  spinUntil([] { return false; }, 1.5, tick);
  encoding = "16UC1";
  frame = "nowhere";
  EXPECT_TRUE(spinUntil(reported("no transform odom -> nowhere"), 30, tick)) << node->log();
  spinUntil([] { return false; }, 1.5, tick);
  node->stop();
  const std::string log = node->log();
  EXPECT_EQ(countLines(log, "encoding 'rgb8'"), 1u) << log;
  EXPECT_EQ(countLines(log, "no transform odom -> nowhere"), 1u) << log;
  EXPECT_GE(countLines(log, "robot stopped"), 2u) << log;
}

// With `_image_transport:=compressedDepth` the node reads the depth as image_transport's
// compressed depth plugin publishes it (an RVL stream here), and maps as from raw images.
TEST_F(RosNode, CompressedDepthFramesGiveTheGrid) {
  UPD_REQUIRE_SHARED_FILE(png, "rtabmap/rgbd/depth/17.png");
  UPD_REQUIRE_SHARED_FILE(yaml, "rtabmap/rgbd/calib/17.yaml");
  const test::RealFrame f = test::loadRealFrame(png, yaml);
  sendStatic(f.pose_base_optical);
  node = startNode(*master, {"_odom_timeout_s:=2.0", "_image_transport:=compressedDepth"});
  std::string format = "16UC1; compressedDepth rvl";
  const auto tick = restingTick([&](const ros::Time& t) {
    sensor_msgs::CameraInfo info = ros1::cameraInfoFromIntrinsics(f.K);
    sensor_msgs::CompressedImage packed = test::compressedDepthOf(f.depth, "16UC1", "rvl");
    packed.format = format;
    info.header.frame_id = packed.header.frame_id = "camera_optical";
    info.header.stamp = packed.header.stamp = t;
    info_pub.publish(info);
    packed_pub.publish(packed);
  });
  ASSERT_TRUE(spinUntil([&] { return out.grid && knownCells(*out.grid) > 100; }, 40, tick))
      << node->log();
  format = "16UC1; compressedDepth jpeg";
  EXPECT_TRUE(spinUntil([&] { return countLines(node->log(), "compressedDepth jpeg") > 0; }, 30,
                        tick))
      << node->log();
  node->stop();
  EXPECT_NE(node->log().find("/camera/depth/image_raw/compressedDepth: compressed depth image"),
            std::string::npos)
      << node->log();
}

// A simulated differential-drive base in a generated world: integrates the last /cmd_vel
// (zero when older than 0.5 s), publishes /odom and odom -> base_link, and renders the depth
// camera at its pose every 0.2 s while frames_on.
struct SimRobot {
  SimRobot(RosNode& t, const nav::NavConfig& c, const sim::WorldSpec& w)
      : test(t), config(c), world(w), xy_yaw(w.start_xy_yaw), K(sim::simulatedIntrinsics(c.camera)) {}
  void tick() {
    const ros::WallTime now = ros::WallTime::now();
    const double dt = last.isZero() ? 0.0 : (now - last).toSec();
    last = now;
    if (test.out.cmd && test.out.cmds != seen_cmds) {
      seen_cmds = test.out.cmds;
      cmd_time = now;
    }
    const bool fresh = test.out.cmd && (now - cmd_time).toSec() < 0.5;
    const double v = fresh ? test.out.cmd->linear.x : 0.0, w = fresh ? test.out.cmd->angular.z : 0.0;
    xy_yaw.z() += w * dt;
    xy_yaw.x() += v * dt * std::cos(xy_yaw.z());
    xy_yaw.y() += v * dt * std::sin(xy_yaw.z());
    const Eigen::Isometry3d body = sim::bodyPoseOnTerrain(world.terrain, xy_yaw, config.body);
    const ros::Time t = ros::Time::now();
    test.publishOdom(body, v, w, t);
    if (!frames_on || now < next_frame) return;
    next_frame = now + ros::WallDuration(0.2);
    const core::DepthImage d = sim::renderDepth(world.terrain, body * sim::cameraOnRobot(config.camera),
                                                K, config.depth_noise, ++frames);
    test.publishFrame(d, K, "camera_optical", t);
  }
  double distanceTo(const Eigen::Vector2d& p) const { return (xy_yaw.head<2>() - p).norm(); }

  RosNode& test;
  const nav::NavConfig& config;
  const sim::WorldSpec& world;
  Eigen::Vector3d xy_yaw;
  core::CameraIntrinsics K;
  ros::WallTime last, cmd_time, next_frame;
  int seen_cmds = 0;
  std::uint32_t frames = 0;
  bool frames_on = true;
};

void sendGoal(ros::Publisher& pub, const Eigen::Vector2d& goal) {
  geometry_msgs::PoseStamped g;
  g.header.frame_id = "odom";
  g.header.stamp = ros::Time::now();
  g.pose.position.x = goal.x();
  g.pose.position.y = goal.y();
  g.pose.orientation.w = 1.0;
  pub.publish(g);
}

TEST_F(RosNode, DrivesASimulatedBaseToAReachableGoalAndStopsThere) {
  const nav::NavConfig config =
      nav::loadNavConfig(kConfigDir + "/dune-kinect.ini", kConfigDir + "/dune-nav.ini");
  const sim::WorldSpec world = sim::makeWorld("mixed");  // an open lane along y = 0
  SimRobot robot(*this, config, world);
  sendStatic(sim::cameraOnRobot(config.camera));
  // Generous timeouts: on a loaded CI machine a frame may take a second to arrive (the stale
  // case has its own test).
  node = startNode(*master, {"--exit-after-goal", "_sensor_timeout_s:=3.0", "_odom_timeout_s:=2.0"});
  ASSERT_TRUE(spinUntil([&] { return out.grid != nullptr; }, 30, [&] { robot.tick(); }))
      << node->log();
  const Eigen::Vector2d goal = world.start_xy_yaw.head<2>() + Eigen::Vector2d(2.5, 0.0);
  sendGoal(goal_pub, goal);
  ASSERT_TRUE(spinUntil([&] { return node->waitExit(0) >= 0; }, 60, [&] { robot.tick(); }))
      << "the node did not end the goal; robot " << robot.distanceTo(goal) << " m from it\n"
      << node->log();
  EXPECT_EQ(node->waitExit(0), 0) << node->log();
  EXPECT_LT(robot.distanceTo(goal), config.navigator.target_allowed_distance_m + 0.15);
  spinUntil([] { return false; }, 0.2);
  ASSERT_TRUE(out.cmd);
  EXPECT_EQ(out.cmd->linear.x, 0.0) << "the last command stops the robot";
  EXPECT_EQ(out.cmd->angular.z, 0.0);
  EXPECT_NE(node->log().find("goal reached"), std::string::npos) << node->log();
}

TEST_F(RosNode, StopsTheRobotWhenTheFramesStop) {
  const nav::NavConfig config =
      nav::loadNavConfig(kConfigDir + "/dune-kinect.ini", kConfigDir + "/dune-nav.ini");
  const sim::WorldSpec world = sim::makeWorld("mixed");
  SimRobot robot(*this, config, world);
  sendStatic(sim::cameraOnRobot(config.camera));
  node = startNode(*master, {"--exit-after-goal", "_sensor_timeout_s:=0.6"});
  ASSERT_TRUE(spinUntil([&] { return out.grid != nullptr; }, 30, [&] { robot.tick(); }))
      << node->log();
  sendGoal(goal_pub, world.goal_xy);
  ASSERT_TRUE(spinUntil([&] { return out.cmds > 3 && out.cmd->linear.x > 0; }, 30,
                        [&] { robot.tick(); }))
      << node->log();
  robot.frames_on = false;  // the camera dies; odometry goes on
  ASSERT_TRUE(spinUntil([&] { return node->waitExit(0) >= 0; }, 10, [&] { robot.tick(); }))
      << node->log();
  EXPECT_EQ(node->waitExit(0), 3);
  const std::string log = node->log();
  EXPECT_NE(log.find("sensor data stale"), std::string::npos) << log;
  EXPECT_NE(log.find("sensor_timeout_s = 0.6"), std::string::npos) << log;
  spinUntil([] { return false; }, 0.2);
  EXPECT_EQ(out.cmd->linear.x, 0.0);
  EXPECT_EQ(out.cmd->angular.z, 0.0);
}

// The base `upd live --base ros` drives: odometry in, Twist out; none without odometry.
TEST_F(RosNode, LiveBaseReadsOdometryAndSendsCommands) {
  try {
    ros1::makeRosBase({}, 0.3);
    ADD_FAILURE() << "a base without odometry";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no odometry on /odom"), std::string::npos) << e.what();
  }
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(1.5, -0.5, 0);
  pose.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::atomic<bool> done{false};
  std::thread odom([&] {
    while (!done) {
      publishOdom(pose, 0.2, 0.1, ros::Time::now());
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  {
    const auto base = ros1::makeRosBase({}, 5.0);
    nav::BaseState s;
    ASSERT_TRUE(base->readState(s));
    EXPECT_NEAR(s.pose_world_robot.x_m, 1.5, 1e-9);
    EXPECT_NEAR(s.pose_world_robot.yaw_rad, 0.3, 1e-9);
    EXPECT_NEAR(s.velocity.v_mps, 0.2, 1e-9);
    ASSERT_TRUE(base->sendVelocity({0.25, -0.1}));
    EXPECT_TRUE(spinUntil([&] { return out.cmd && out.cmd->linear.x == 0.25; }, 5.0,
                          [&] { base->sendVelocity({0.25, -0.1}); }));
    EXPECT_EQ(out.cmd->angular.z, -0.1);
  }
  done = true;
  odom.join();
  EXPECT_TRUE(spinUntil([&] { return out.cmd && out.cmd->linear.x == 0.0; }, 2.0))
      << "the base stops the robot when it goes";
}

// share/ros is the ROS package upd_nav: roslaunch resolves its launch file to the entry script,
// which runs this build's `upd ros`.
TEST(RosLaunch, TheLaunchFileResolvesToTheUpdRosNode) {
  const std::string pkg = std::string(UPD_DATA_BUILD_DIR) + "/ros";
  test::TempDir home;
  const auto r = test::runCommand("ROS_HOME=" + home.path().string() + " ROS_PACKAGE_PATH=" + pkg +
                                  " roslaunch --args /upd upd_nav upd.launch");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(pkg + "/upd_ros --config "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("dune-nav.ini"), std::string::npos) << r.output;
  const auto help = test::runCommand(pkg + "/upd_ros --help");
  EXPECT_EQ(help.exit_code, 0) << help.output;
  EXPECT_NE(help.output.find("usage: upd ros"), std::string::npos) << help.output;
}

}  // namespace
