#include "upd/ros1/ros_base.h"

#include "upd/core/params.h"

#include <geometry_msgs/Twist.h>
#include <tf2/exceptions.h>

#include <cmath>
#include <thread>

namespace upd::ros1 {

namespace {

double yawOf(const geometry_msgs::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

}  // namespace

void RosBaseParams::validate() const {
  core::requireParam(odom_timeout_s > 0, "RosBaseParams", "odom_timeout_s", odom_timeout_s,
                     "must be > 0");
  for (const auto* s : {&cmd_vel_topic, &odom_topic, &base_frame, &world_frame}) {
    if (s->empty()) throw std::invalid_argument("RosBaseParams: a topic or frame name is empty");
  }
}

RosRobotBase::RosRobotBase(ros::NodeHandle& nh, const RosBaseParams& params,
                           const tf2_ros::Buffer* tf)
    : params_(params), tf_(tf) {
  params_.validate();
  cmd_pub_ = nh.advertise<geometry_msgs::Twist>(params_.cmd_vel_topic, 1);
  ros::NodeHandle own(nh);
  own.setCallbackQueue(&queue_);
  odom_sub_ = own.subscribe(params_.odom_topic, 5, &RosRobotBase::onOdom, this);
  spinner_ = std::make_unique<ros::AsyncSpinner>(1, &queue_);
  spinner_->start();
}

RosRobotBase::~RosRobotBase() {
  spinner_->stop();
  odom_sub_.shutdown();
}

void RosRobotBase::onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
  const std::lock_guard<std::mutex> lock(mutex_);
  odom_ = msg;
}

bool RosRobotBase::hasOdometry() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return odom_ != nullptr;
}

std::string RosRobotBase::lastError() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return last_error_;
}

bool RosRobotBase::readState(nav::BaseState& state) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (!odom_) {
    last_error_ = "no odometry on " + params_.odom_topic;
    return false;
  }
  const double age = (ros::Time::now() - odom_->header.stamp).toSec();
  if (age > params_.odom_timeout_s) {
    last_error_ = "odometry on " + params_.odom_topic + " is stale (" + std::to_string(age) +
                  " s old, limit " + std::to_string(params_.odom_timeout_s) + " s)";
    return false;
  }
  const auto& p = odom_->pose.pose;
  state.pose_odom_robot = {p.position.x, p.position.y, yawOf(p.orientation)};
  state.pose_world_robot = state.pose_odom_robot;
  state.velocity = {odom_->twist.twist.linear.x, odom_->twist.twist.angular.z};
  if (tf_ && params_.world_frame != odom_->header.frame_id &&
      tf_->canTransform(params_.world_frame, params_.base_frame, ros::Time(0))) {
    try {
      const auto t = tf_->lookupTransform(params_.world_frame, params_.base_frame, ros::Time(0));
      state.pose_world_robot = {t.transform.translation.x, t.transform.translation.y,
                                yawOf(t.transform.rotation)};
    } catch (const tf2::TransformException& e) {
      last_error_ = std::string("tf ") + params_.world_frame + " -> " + params_.base_frame +
                    ": " + e.what();
      return false;
    }
  }
  last_error_.clear();
  return true;
}

bool RosRobotBase::sendVelocity(const nav::Twist2D& command) {
  geometry_msgs::Twist t;
  t.linear.x = command.v_mps;
  t.angular.z = command.w_radps;
  cmd_pub_.publish(t);
  return true;
}

bool RosRobotBase::stop(bool) { return sendVelocity({}); }

double RosRobotBase::timeS() const { return ros::Time::now().toSec(); }

namespace {

// The node handle of makeRosBase's base lives as long as the base.
class OwnedRosBase : public nav::RobotBase {
 public:
  explicit OwnedRosBase(const RosBaseParams& params) : base_(nh_, params, nullptr) {}
  ~OwnedRosBase() override { base_.stop(false); }
  bool readState(nav::BaseState& s) override { return base_.readState(s); }
  bool sendVelocity(const nav::Twist2D& c) override { return base_.sendVelocity(c); }
  bool stop(bool e) override { return base_.stop(e); }
  double timeS() const override { return base_.timeS(); }
  std::string lastError() const override { return base_.lastError(); }
  RosRobotBase& base() { return base_; }

 private:
  ros::NodeHandle nh_;
  RosRobotBase base_;
};

}  // namespace

std::unique_ptr<nav::RobotBase> makeRosBase(const RosBaseParams& params, double wait_s) {
  if (!ros::isInitialized()) {
    int argc = 0;
    ros::init(argc, nullptr, "upd_live", ros::init_options::NoSigintHandler);
  }
  if (!ros::master::check()) {
    throw std::runtime_error("no ROS master at " + ros::master::getURI() +
                             " (start roscore or set ROS_MASTER_URI)");
  }
  auto owned = std::make_unique<OwnedRosBase>(params);
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s);
  while (!owned->base().hasOdometry() && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (!owned->base().hasOdometry()) {
    throw std::runtime_error("no odometry on " + params.odom_topic + " within " +
                             std::to_string(wait_s) + " s");
  }
  return owned;
}

}  // namespace upd::ros1
