// occtrack_ros_node: the ROS 1 adapter over planners::Tracker (docs/ros.md). It keeps the latest scan, robot
// odometry and target, and on a timer at `rate` runs one Tracker step and publishes the command (cmd_vel, body
// frame), the plan and the candidates. Everything the Tracker refuses (NaN scan, stale target, ...) gives a zero
// Twist and the reason on `status`; the node adds the checks only it can make (nothing received yet, frames).
#include <ros/ros.h>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <sensor_msgs/LaserScan.h>
#include <std_msgs/String.h>
#include <visualization_msgs/MarkerArray.h>

#include <exception>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "bridge.hpp"
#include "conversions.hpp"

namespace occtrack::ros_adapter {
namespace {

/// What a reason says, without its numbers: "target: stale, # s old (target_timeout # s)". A stop's reason
/// can carry a figure that changes every tick (a stale estimate's age); the log shows a reason when this
/// changes, so that one stop is one line, not one a tick.
std::string log_key(const std::string& reason) {
  std::string key;
  key.reserve(reason.size());
  for (std::size_t i = 0; i < reason.size();) {
    const auto digit = [&](std::size_t k) { return k < reason.size() && reason[k] >= '0' && reason[k] <= '9'; };
    if (digit(i) || (reason[i] == '-' && digit(i + 1))) {
      ++i;
      while (i < reason.size() && (digit(i) || reason[i] == '.')) ++i;
      key += '#';
    } else {
      key += reason[i++];
    }
  }
  return key;
}

class TrackerNode {
 public:
  TrackerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : config_(read_config(pnh)), tracker_(config_) {
    pnh.param<std::string>("world_frame", world_frame_, "odom");
    pnh.param("max_candidates", max_candidates_, 30);
    std::string target_type;
    pnh.param<std::string>("target_type", target_type, "pose");
    double velocity_window = 0.1;
    pnh.param("target_velocity_window", velocity_window, velocity_window);
    differences_.emplace(velocity_window);

    scan_sub_ = nh.subscribe("scan", 1, &TrackerNode::on_scan, this);
    odom_sub_ = nh.subscribe("odom", 1, &TrackerNode::on_odom, this);
    if (target_type == "odometry") {
      target_sub_ = nh.subscribe("target", 1, &TrackerNode::on_target_odometry, this);
    } else if (target_type == "pose") {
      target_sub_ = nh.subscribe("target", 10, &TrackerNode::on_target_pose, this);  // every pose, for differences
    } else {
      throw std::invalid_argument("~target_type must be \"pose\" or \"odometry\", got \"" + target_type + "\"");
    }
    cmd_pub_ = nh.advertise<geometry_msgs::Twist>("cmd_vel", 1);
    plan_pub_ = nh.advertise<nav_msgs::Path>("plan", 1);
    candidates_pub_ = nh.advertise<visualization_msgs::MarkerArray>("candidates", 1);
    status_pub_ = nh.advertise<std_msgs::String>("status", 1);
    timer_ = nh.createTimer(ros::Duration(config_.planning_period), &TrackerNode::on_timer, this);
    ROS_INFO("occtrack: planner %s (shield %s) at %.1f Hz; target from %s; %s", config_.planner.c_str(),
             config_.shield ? "on" : "off", 1.0 / config_.planning_period, target_type.c_str(),
             describe_settings(config_).c_str());
  }

 private:
  static TrackerConfig read_config(ros::NodeHandle& pnh) {
    TrackerConfig s = default_tracker_config();  // the Tracker's defaults: cvae, safety layer on
    pnh.param<std::string>("planner", s.planner, s.planner);
    pnh.param<std::string>("model", s.model, s.model);
    pnh.param("batch", s.batch, s.batch);
    pnh.param("shield", s.shield, s.shield);
    pnh.param("predictor", s.predictor, s.predictor);
    pnh.param("passive_turn", s.passive_turn, s.passive_turn);  // the safety layer refuses bad values by name
    pnh.param("standoff", s.standoff, s.standoff);
    pnh.param("moving_speed_max", s.moving_speed_max, s.moving_speed_max);
    // The ranking's two options; the ranking refuses bad values by name.
    pnh.param("tracking_weight", s.tracking_weight, s.tracking_weight);
    if (double reach = 0.0; pnh.getParam("moving_reach", reach)) s.moving_reach = reach;
    double rate = 20.0;
    pnh.param("rate", rate, rate);
    if (!(rate > 0.0 && rate <= 1000.0)) throw std::invalid_argument("~rate must lie in (0, 1000] Hz");
    s.planning_period = 1.0 / rate;  // the safety layer certifies for one period
    pnh.param("accel_max", s.accel_max, s.accel_max);
    pnh.param("response_time", s.response_time, s.response_time);
    pnh.param("latency", s.latency, s.latency);
    pnh.param("target_timeout", s.target_timeout, s.target_timeout);
    pnh.param("scan_timeout", s.scan_timeout, s.scan_timeout);
    pnh.param("odom_timeout", s.robot_timeout, s.robot_timeout);
    pnh.param("future_tolerance", s.future_tolerance, s.future_tolerance);
    pnh.param("min_valid_share", s.min_valid_share, s.min_valid_share);
    pnh.param("max_invalid_gap", s.max_invalid_gap, s.max_invalid_gap);
    return s;
  }

  void on_scan(const sensor_msgs::LaserScan::ConstPtr& msg) { scan_msg_ = msg; }
  void on_odom(const nav_msgs::Odometry::ConstPtr& msg) { odom_ = msg; }
  void on_target_pose(const geometry_msgs::PoseStamped::ConstPtr& msg) {
    const Vec2 p(msg->pose.position.x, msg->pose.position.y);
    differences_->add(msg->header.stamp.toSec(), p);
    target_ = Stamped{p, differences_->velocity(), msg->header.stamp.toSec()};
    target_frame_ = msg->header.frame_id;
  }
  void on_target_odometry(const nav_msgs::Odometry::ConstPtr& msg) {
    const auto& pose = msg->pose.pose;
    const Vec2 body_velocity(msg->twist.twist.linear.x, msg->twist.twist.linear.y);
    target_ = Stamped{Vec2(pose.position.x, pose.position.y),
                                       rotate(body_velocity, yaw_of(pose.orientation)), msg->header.stamp.toSec()};
    target_frame_ = msg->header.frame_id;
  }

  /// Why the node cannot even ask the Tracker (empty: it can).
  std::string missing() const {
    if (!odom_) return "odom: none received";
    if (!target_) return "target: none received";
    const auto foreign = [&](const std::string& frame) { return !frame.empty() && frame != world_frame_; };
    if (foreign(odom_->header.frame_id))
      return "odom: frame \"" + odom_->header.frame_id + "\" is not world_frame \"" + world_frame_ + "\"";
    if (foreign(target_frame_))
      return "target: frame \"" + target_frame_ + "\" is not world_frame \"" + world_frame_ + "\"";
    return {};
  }

  void on_timer(const ros::TimerEvent&) {
    const ros::Time now = ros::Time::now();
    std::string reason = missing();
    geometry_msgs::Twist twist;  // zero unless the Tracker commands otherwise
    if (reason.empty()) {
      const auto& pose = odom_->pose.pose;
      const double yaw = yaw_of(pose.orientation);
      const Vec2 body_velocity(odom_->twist.twist.linear.x, odom_->twist.twist.linear.y);
      const Stamped robot{Vec2(pose.position.x, pose.position.y), rotate(body_velocity, yaw),
                                       odom_->header.stamp.toSec()};
      if (scan_msg_) to_scan(*scan_msg_, yaw, scan_);  // the laser is aligned with the body: add the yaw
      const TrackerStep& out = tracker_.step(now.toSec(), robot, *target_, scan_msg_ ? &scan_ : nullptr);
      reason = *out.reason;
      if (out.beyond_envelope)
        ROS_WARN_THROTTLE(10.0,
                          "occtrack: moving obstacles look faster than the safety layer assumes (~moving_speed_max "
                          "%g m/s); if they are, raise it (docs/safety.md)",
                          config_.moving_speed_max);
      twist = to_twist(out.command, yaw);  // zero when stopped (and for a non-finite yaw, already refused)
      publish_plan(out, now);
    }
    cmd_pub_.publish(twist);
    std::string key = log_key(reason);
    if (key != last_logged_) {  // log changes only: a stop lasts many cycles
      if (reason.empty()) ROS_INFO("occtrack: tracking");
      else ROS_WARN("occtrack: stopped: %s", reason.c_str());
      last_logged_ = std::move(key);
    }
    std_msgs::String status;
    status.data = reason.empty() ? "tracking" : "stopped: " + reason;
    status_pub_.publish(status);
  }

  void publish_plan(const TrackerStep& out, const ros::Time& now) {
    std_msgs::Header header;
    header.stamp = now;
    header.frame_id = world_frame_;
    if (plan_pub_.getNumSubscribers() > 0) {
      to_path(*out.plan, header, path_);
      plan_pub_.publish(path_);
    }
    if (candidates_pub_.getNumSubscribers() > 0) {
      to_markers(*out.candidates, header, max_candidates_, markers_);
      candidates_pub_.publish(markers_);
    }
  }

  TrackerConfig config_;
  TrackerBridge tracker_;
  std::string world_frame_;
  int max_candidates_ = 30;
  std::optional<VelocityFromPoses> differences_;
  ros::Subscriber scan_sub_, odom_sub_, target_sub_;
  ros::Publisher cmd_pub_, plan_pub_, candidates_pub_, status_pub_;
  ros::Timer timer_;
  sensor_msgs::LaserScan::ConstPtr scan_msg_;
  nav_msgs::Odometry::ConstPtr odom_;
  std::optional<Stamped> target_;
  std::string target_frame_;
  std::string last_logged_ = "(none yet)";  // log_key of the last reason logged
  core::Scan scan_;  // reused from cycle to cycle
  nav_msgs::Path path_;
  visualization_msgs::MarkerArray markers_;
};

}  // namespace
}  // namespace occtrack::ros_adapter

int main(int argc, char** argv) {
  ros::init(argc, argv, "occtrack_ros_node");
  ros::NodeHandle nh, pnh("~");
  try {
    occtrack::ros_adapter::TrackerNode node(nh, pnh);
    ros::spin();
  } catch (const std::exception& e) {  // bad parameters or model file: say so and exit non-zero
    ROS_FATAL("occtrack: %s", e.what());
    return 1;
  }
  return 0;
}
