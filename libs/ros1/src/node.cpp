#include "upd/ros1/node.h"

#include "upd/core/params.h"
#include "upd/nav/navigation_loop.h"
#include "upd/ros1/conversions.h"

#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/OccupancyGrid.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2/exceptions.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include <optional>

namespace upd::ros1 {

void RosNodeParams::validate() const {
  base.validate();
  core::requireParam(image_transport == "raw" || image_transport == "compressedDepth",
                     "RosNodeParams", "image_transport", image_transport,
                     "must be raw or compressedDepth");
  core::requireParam(sensor_timeout_s > 0, "RosNodeParams", "sensor_timeout_s", sensor_timeout_s,
                     "must be > 0");
  core::requireParam(tf_timeout_s >= 0, "RosNodeParams", "tf_timeout_s", tf_timeout_s,
                     "must be >= 0");
  core::requireParam(control_rate_hz > 0, "RosNodeParams", "control_rate_hz", control_rate_hz,
                     "must be > 0");
  core::requireParam(grid_period_s >= 0, "RosNodeParams", "grid_period_s", grid_period_s,
                     "must be >= 0");
}

std::string RosNodeParams::depthImageTopic() const {
  return image_transport == "raw" ? depth_topic : compressedDepthTopic(depth_topic);
}

RosNodeParams loadRosNodeParams(const ros::NodeHandle& pnh, RosNodeParams p) {
  // Every field is the private parameter of its name; nh.param keeps the default when unset.
  const auto read = [&pnh](const char* name, auto& value, const char*) {
    pnh.param(name, value, value);
  };
  p.visit(read);
  p.validate();
  return p;
}

struct TraversabilityNode::Impl {
  Impl(ros::NodeHandle& nh, const RosNodeParams& p, const nav::NavConfig& config)
      : params(p), listener(tf), base(nh, p.base, &tf),
        loop(base, config, nav::ObstacleDetector::Upd) {
    grid_pub = nh.advertise<nav_msgs::OccupancyGrid>(p.grid_topic, 1, /*latch=*/true);
    cloud_pub = nh.advertise<sensor_msgs::PointCloud2>(p.cloud_topic, 1);
    route_pub = nh.advertise<visualization_msgs::MarkerArray>(p.route_topic, 1, true);
    depth_sub = p.image_transport == "raw"
                    ? nh.subscribe(p.depthImageTopic(), 2, &Impl::onDepth, this)
                    : nh.subscribe(p.depthImageTopic(), 2, &Impl::onPacked, this);
    info_sub = nh.subscribe(p.camera_info_topic, 2, &Impl::onInfo, this);
    points_sub = nh.subscribe(p.points_topic, 2, &Impl::onPoints, this);
    goal_sub = nh.subscribe(p.goal_topic, 1, &Impl::onGoal, this);
  }

  RosNodeParams params;
  tf2_ros::Buffer tf;
  tf2_ros::TransformListener listener;
  RosRobotBase base;
  nav::NavigationLoop loop;
  ros::Publisher grid_pub, cloud_pub, route_pub;
  ros::Subscriber depth_sub, info_sub, points_sub, goal_sub;

  sensor_msgs::CameraInfo::ConstPtr info;
  sensor_msgs::Image::ConstPtr pending_depth;
  sensor_msgs::CompressedImage::ConstPtr pending_packed;  ///< (image_transport compressedDepth)
  sensor_msgs::PointCloud2::ConstPtr pending_points;
  std::string world_frame;  ///< resolved at the first frame
  std::optional<ros::Time> last_frame;
  ros::Time last_grid;
  bool driving = false;
  std::optional<NodeEnd> goal_end;
  int frames = 0;
  std::string last_problem;  ///< the last problem logged, so that a repeated one is logged once

  void onDepth(const sensor_msgs::Image::ConstPtr& m) { pending_depth = m; }
  void onPacked(const sensor_msgs::CompressedImage::ConstPtr& m) { pending_packed = m; }
  void onInfo(const sensor_msgs::CameraInfo::ConstPtr& m) { info = m; }
  void onPoints(const sensor_msgs::PointCloud2::ConstPtr& m) { pending_points = m; }
  void onGoal(const geometry_msgs::PoseStamped::ConstPtr& m);

  void problem(const std::string& line);
  bool resolveWorldFrame(const ros::Time& stamp);
  std::optional<Eigen::Isometry3d> lookup(const std::string& target, const std::string& source,
                                          const ros::Time& stamp);
  bool basePoseKnown();
  void processPending();
  void processCloud(core::PointCloud cloud, const std_msgs::Header& header);
  void publishGrid(const ros::Time& stamp, bool force);
  void publishRoute();
  void control();
  void endGoal(NodeEnd end, const std::string& line);
};

// One line per distinct problem (not one per frame), and the robot stopped.
void TraversabilityNode::Impl::problem(const std::string& line) {
  base.stop(false);
  if (line == last_problem) return;
  last_problem = line;
  ROS_ERROR("upd: %s; robot stopped", line.c_str());
}

bool TraversabilityNode::Impl::resolveWorldFrame(const ros::Time& stamp) {
  if (!world_frame.empty()) return true;
  const std::string& base_frame = params.base.base_frame;
  for (const std::string& f : {params.base.world_frame, params.odom_frame}) {
    if (tf.canTransform(f, base_frame, stamp, ros::Duration(params.tf_timeout_s))) {
      world_frame = f;
      ROS_INFO("upd: world frame '%s' (tf %s -> %s)", f.c_str(), f.c_str(), base_frame.c_str());
      return true;
    }
  }
  problem("no transform " + params.base.world_frame + " or " + params.odom_frame + " -> " +
          base_frame + " in tf");
  return false;
}

std::optional<Eigen::Isometry3d> TraversabilityNode::Impl::lookup(const std::string& target,
                                                                  const std::string& source,
                                                                  const ros::Time& stamp) {
  try {
    const auto t =
        tf.lookupTransform(target, source, stamp, ros::Duration(params.tf_timeout_s));
    return isometryFromTransform(t.transform);
  } catch (const tf2::TransformException& e) {
    (void)e;  // its text holds the time: the line would differ for every frame
    problem("no transform " + target + " -> " + source + " in tf (at the message's stamp)");
  } catch (const MessageError& e) {
    problem(std::string("transform ") + target + " -> " + source + ": " + e.what());
  }
  return std::nullopt;
}

// The loop reads the robot pose from the base for every frame and plan: without odometry
// there is nothing to map or drive with.
bool TraversabilityNode::Impl::basePoseKnown() {
  nav::BaseState s;
  if (base.readState(s)) return true;
  problem("no robot pose: " + base.lastError());
  return false;
}

void TraversabilityNode::Impl::processPending() {
  if (pending_depth || pending_packed) {
    const auto image = pending_depth;
    const auto packed = pending_packed;
    pending_depth.reset();
    pending_packed.reset();
    const std::string topic = params.depthImageTopic();
    if (!info) {
      problem("depth image on " + topic + " but no CameraInfo on " + params.camera_info_topic +
              " yet");
      return;
    }
    try {
      const core::DepthImage depth =
          image ? depthFromImage(*image) : depthFromCompressedDepth(*packed);
      processCloud(cloudFromDepthImage(depth, *info), image ? image->header : packed->header);
    } catch (const MessageError& e) {
      problem(topic + ": " + e.what());
    }
  }
  if (pending_points) {
    const auto msg = pending_points;
    pending_points.reset();
    try {
      processCloud(cloudFromPointCloud2(*msg), msg->header);
    } catch (const MessageError& e) {
      problem(params.points_topic + ": " + e.what());
    }
  }
}

void TraversabilityNode::Impl::processCloud(core::PointCloud cloud,
                                            const std_msgs::Header& header) {
  if (!resolveWorldFrame(header.stamp)) return;
  const auto world_sensor = lookup(world_frame, header.frame_id, header.stamp);
  if (!world_sensor) return;
  const auto world_base = lookup(world_frame, params.base.base_frame, header.stamp);
  if (!world_base) return;
  if (!basePoseKnown()) return;
  const core::PointCloud cloud_world = core::transformCloud(cloud, *world_sensor);
  const nav::FrameEvidence& ev =
      loop.addFrame(cloud_world, header.stamp.toSec(), world_base->translation().z());
  ++frames;
  last_frame = ros::Time::now();
  last_problem.clear();
  sensor_msgs::PointCloud2 out = pointCloud2FromScored(ev);
  out.header.frame_id = world_frame;
  out.header.stamp = header.stamp;
  cloud_pub.publish(out);
  publishGrid(header.stamp, false);
}

void TraversabilityNode::Impl::publishGrid(const ros::Time& stamp, bool force) {
  const double since = (stamp - last_grid).toSec();  // < 0 after a jump back (a bag replayed)
  if (!force && !last_grid.isZero() && since >= 0 && since < params.grid_period_s) return;
  last_grid = stamp;
  nav_msgs::OccupancyGrid msg = occupancyGridFromGrid(loop.grid());
  msg.header.frame_id = world_frame;
  msg.header.stamp = stamp;
  msg.info.map_load_time = stamp;
  grid_pub.publish(msg);
}

void TraversabilityNode::Impl::publishRoute() {
  const nav::Route& r = loop.route();
  visualization_msgs::MarkerArray m = routeMarkers(r.path_world, r.waypoints, world_frame);
  for (auto& marker : m.markers) marker.header.stamp = ros::Time::now();
  route_pub.publish(m);
}

void TraversabilityNode::Impl::onGoal(const geometry_msgs::PoseStamped::ConstPtr& m) {
  if (!resolveWorldFrame(ros::Time(0))) return;
  Eigen::Vector3d goal(m->pose.position.x, m->pose.position.y, m->pose.position.z);
  if (!m->header.frame_id.empty() && m->header.frame_id != world_frame) {
    const auto t = lookup(world_frame, m->header.frame_id, ros::Time(0));
    if (!t) return;
    goal = *t * goal;
  }
  if (!basePoseKnown()) return;
  ROS_INFO("upd: goal (%.2f, %.2f) in %s: navigating", goal.x(), goal.y(), world_frame.c_str());
  loop.navigateTo(goal.head<2>());  // the first goal builds the navigator: seconds, no spinning
  // Staleness counts from the goal: the robot did not move while the navigator was built.
  if (last_frame) last_frame = ros::Time::now();
  driving = true;
  goal_end.reset();
  publishRoute();
}

void TraversabilityNode::Impl::endGoal(NodeEnd end, const std::string& line) {
  loop.finish();  // cancels the navigator and sends a zero command
  base.stop(false);
  driving = false;
  goal_end = end;
  if (end == NodeEnd::GoalReached) {
    ROS_INFO("upd: %s; robot stopped", line.c_str());
  } else {
    ROS_ERROR("upd: %s; robot stopped", line.c_str());
  }
}

void TraversabilityNode::Impl::control() {
  if (!driving) return;
  const double since = last_frame ? (ros::Time::now() - *last_frame).toSec() : 1e9;
  if (since > params.sensor_timeout_s) {
    endGoal(NodeEnd::GoalFailed,
            "sensor data stale: no frame for " +
                (last_frame ? std::to_string(since) + " s" : std::string("ever")) +
                " (sensor_timeout_s = " + std::to_string(params.sensor_timeout_s) + ")");
    return;
  }
  const std::size_t route_points = loop.route().path_world.size();
  nav::NavState state;
  try {
    state = loop.step();
  } catch (const std::runtime_error& e) {  // the base lost its pose while planning
    endGoal(NodeEnd::GoalFailed, std::string(e.what()) + ": " + base.lastError());
    return;
  }
  if (loop.route().path_world.size() != route_points) publishRoute();
  if (state == nav::NavState::Navigating) return;
  const nav::NavOutcome o = loop.outcome();
  if (state == nav::NavState::Idle && o.target_reached) {
    endGoal(NodeEnd::GoalReached, "goal reached");
  } else {
    endGoal(NodeEnd::GoalFailed, std::string("navigation failed (") + nav::toString(state) +
                                     (o.error_code.empty() ? "" : " " + o.error_code) +
                                     (base.lastError().empty() ? "" : ": " + base.lastError()) +
                                     (o.error_message.empty() ? "" : ": " + o.error_message) +
                                     ")");
  }
}

TraversabilityNode::TraversabilityNode(ros::NodeHandle& nh, const RosNodeParams& params,
                                       const nav::NavConfig& config)
    : impl_(std::make_unique<Impl>(nh, params, config)) {}

TraversabilityNode::~TraversabilityNode() {
  if (impl_->driving) impl_->loop.finish();
  impl_->base.stop(false);
}

int TraversabilityNode::framesProcessed() const { return impl_->frames; }

NodeEnd TraversabilityNode::spin(bool exit_after_goal) {
  ros::Rate rate(impl_->params.control_rate_hz);
  while (ros::ok()) {
    ros::spinOnce();
    impl_->processPending();
    impl_->control();
    if (exit_after_goal && impl_->goal_end) return *impl_->goal_end;
    rate.sleep();
  }
  return NodeEnd::Shutdown;
}

}  // namespace upd::ros1
