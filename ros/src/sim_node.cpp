// occtrack_ros_sim: occtrack's simulated world (sim::World) at real time, for trying the node without a robot
// and for the closed-loop test (docs/ros.md). It reads a scenario file, integrates a holonomic robot from
// cmd_vel (body frame; acceleration-bounded, as the offline simulator) and publishes with current stamps:
// scan (LaserScan in the body frame), odom (the robot), target (PoseStamped) and target_odom (Odometry), and
// target_visible (std_msgs/Bool: the line of sight from robot to target is clear).
//
// The robot may turn at a constant rate (~yaw, ~yaw_rate), so that the body-frame conversions are exercised.
// Faults for tests, read again every 0.25 s: ~nan_scan (every beam NaN) and ~target_delay (s: the target is
// published as it was that long ago, stamped then).
#include <ros/ros.h>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/LaserScan.h>
#include <std_msgs/Bool.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>
#include <string>

#include "bridge.hpp"
#include "conversions.hpp"

namespace occtrack::ros_adapter {
namespace {

class SimNode {
 public:
  SimNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : pnh_(pnh), world_(require(pnh, "scenario")) {
    double physics_rate = 100.0, publish_rate = 50.0, scan_rate = 20.0;
    pnh.param("physics_rate", physics_rate, physics_rate);
    pnh.param("publish_rate", publish_rate, publish_rate);
    pnh.param("scan_rate", scan_rate, scan_rate);
    pnh.param("yaw", yaw_, 0.0);
    pnh.param("yaw_rate", yaw_rate_, 0.0);
    pnh.param("accel_max", accel_max_, 2.0);
    pnh.param("command_timeout", command_timeout_, 0.5);
    pnh.param("wait_for_command", waiting_, true);
    pnh.param<std::string>("world_frame", world_frame_, "odom");
    pnh.param<std::string>("base_frame", base_frame_, "base_link");
    pnh.param<std::string>("target_frame", target_frame_, "target");
    for (double rate : {physics_rate, publish_rate, scan_rate})
      if (!(rate > 0.0 && rate <= 1000.0)) throw std::invalid_argument("rates must lie in (0, 1000] Hz");
    dt_ = 1.0 / physics_rate;
    publish_period_ = 1.0 / publish_rate;
    scan_period_ = 1.0 / scan_rate;
    position_ = world_.robot_start();
    velocity_ = world_.robot_start_velocity();

    cmd_sub_ = nh.subscribe("cmd_vel", 1, &SimNode::on_cmd_vel, this);
    scan_pub_ = nh.advertise<sensor_msgs::LaserScan>("scan", 1);
    odom_pub_ = nh.advertise<nav_msgs::Odometry>("odom", 10);
    target_pub_ = nh.advertise<geometry_msgs::PoseStamped>("target", 10);
    target_odom_pub_ = nh.advertise<nav_msgs::Odometry>("target_odom", 10);
    visible_pub_ = nh.advertise<std_msgs::Bool>("target_visible", 10);
    start_ = ros::Time::now();
    timer_ = nh.createTimer(ros::Duration(dt_), &SimNode::on_timer, this);
    ROS_INFO("occtrack sim: %s, %d beams, %s", world_.name().c_str(), world_.beams(),
             waiting_ ? "world time starts at the first cmd_vel" : "running");
  }

 private:
  static std::string require(ros::NodeHandle& pnh, const std::string& name) {
    std::string value;
    if (!pnh.getParam(name, value) || value.empty()) throw std::invalid_argument("~" + name + " must be set");
    return value;
  }

  void on_cmd_vel(const geometry_msgs::Twist::ConstPtr& msg) {
    command_body_ = Vec2(msg->linear.x, msg->linear.y);
    if (!command_body_.allFinite()) {  // a base would refuse it too
      ROS_ERROR_THROTTLE(1.0, "occtrack sim: non-finite cmd_vel, braking");
      command_body_ = Vec2::Zero();
    }
    command_time_ = ros::Time::now();
    waiting_ = false;
  }

  void on_timer(const ros::TimerEvent&) {
    const ros::Time now = ros::Time::now();
    if (waiting_) start_ = now;  // the world waits (time 0) until the planner is up
    // Integrate in fixed steps up to the wall clock (at most 0.5 s behind: a stalled machine skips ahead).
    const double t = (now - start_).toSec();
    if (t - sim_time_ > 0.5) sim_time_ = t - 0.5;
    const bool commanded = (now - command_time_).toSec() <= command_timeout_;  // else the base brakes
    while (sim_time_ + dt_ <= t) {
      const Vec2 command = commanded ? rotate(command_body_, yaw_) : Vec2::Zero();
      velocity_ = WorldBridge::follow(velocity_, command, accel_max_, dt_);
      position_ += velocity_ * dt_;
      if (!waiting_) yaw_ = std::remainder(yaw_ + yaw_rate_ * dt_, 2.0 * M_PI);
      sim_time_ += dt_;
    }
    if (world_.clearance(position_, sim_time_) < world_.robot_radius())
      ROS_WARN_THROTTLE(1.0, "occtrack sim: the robot is in collision at t = %.2f s", sim_time_);

    const double wall = now.toSec();
    if (due(next_faults_, 0.25, wall)) read_faults();
    if (due(next_publish_, publish_period_, wall)) publish_state(now);
    if (due(next_scan_, scan_period_, wall)) publish_scan(now);
  }

  // True when a periodic task is due at `wall`; keeps its schedule at the period (not timer tick + period).
  static bool due(double& next, double period, double wall) {
    if (wall < next) return false;
    next = std::max(next + period, wall - period);  // after a stall, catch up once instead of in a burst
    return true;
  }

  void read_faults() {
    pnh_.getParamCached("nan_scan", nan_scan_);
    pnh_.getParamCached("target_delay", target_delay_);
  }

  void publish_state(const ros::Time& now) {
    nav_msgs::Odometry odom;
    odom.header.stamp = now;
    odom.header.frame_id = world_frame_;
    odom.child_frame_id = base_frame_;
    odom.pose.pose.position.x = position_.x();
    odom.pose.pose.position.y = position_.y();
    odom.pose.pose.orientation = quaternion_of(yaw_);
    const Vec2 body_velocity = rotate(velocity_, -yaw_);  // ROS: the twist is in the child frame
    odom.twist.twist.linear.x = body_velocity.x();
    odom.twist.twist.linear.y = body_velocity.y();
    odom.twist.twist.angular.z = waiting_ ? 0.0 : yaw_rate_;
    odom_pub_.publish(odom);

    // The target as it was target_delay ago (0: now), stamped then; its frame is aligned with the world's.
    const double t = std::max(0.0, sim_time_ - target_delay_);
    const Vec2 target = world_.target_position(t), target_velocity = world_.target_velocity(t);
    geometry_msgs::PoseStamped pose;
    pose.header.stamp = now - ros::Duration(target_delay_);
    pose.header.frame_id = world_frame_;
    pose.pose.position.x = target.x();
    pose.pose.position.y = target.y();
    pose.pose.orientation = quaternion_of(0.0);
    target_pub_.publish(pose);
    nav_msgs::Odometry target_odom;
    target_odom.header = pose.header;
    target_odom.child_frame_id = target_frame_;
    target_odom.pose.pose = pose.pose;
    target_odom.twist.twist.linear.x = target_velocity.x();
    target_odom.twist.twist.linear.y = target_velocity.y();
    target_odom_pub_.publish(target_odom);

    std_msgs::Bool visible;
    visible.data = !world_.blocked(position_, world_.target_position(sim_time_), sim_time_);
    visible_pub_.publish(visible);
  }

  void publish_scan(const ros::Time& now) {
    world_.scan(position_, sim_time_, scan_);
    if (nan_scan_) scan_.ranges.assign(scan_.ranges.size(), std::numeric_limits<double>::quiet_NaN());
    to_laser_scan(scan_, yaw_, laser_);
    laser_.header.stamp = now;
    laser_.header.frame_id = base_frame_;  // the laser is aligned with the body
    scan_pub_.publish(laser_);
  }

  ros::NodeHandle pnh_;
  WorldBridge world_;
  double dt_ = 0.01, publish_period_ = 0.02, scan_period_ = 0.05;
  double yaw_ = 0.0, yaw_rate_ = 0.0, accel_max_ = 2.0, command_timeout_ = 0.5;
  bool waiting_ = true, nan_scan_ = false;
  double target_delay_ = 0.0;
  std::string world_frame_, base_frame_, target_frame_;
  Vec2 position_ = Vec2::Zero(), velocity_ = Vec2::Zero(), command_body_ = Vec2::Zero();
  ros::Time start_, command_time_;
  double sim_time_ = 0.0, next_publish_ = 0.0, next_scan_ = 0.0, next_faults_ = 0.0;
  ros::Subscriber cmd_sub_;
  ros::Publisher scan_pub_, odom_pub_, target_pub_, target_odom_pub_, visible_pub_;
  ros::Timer timer_;
  core::Scan scan_;
  sensor_msgs::LaserScan laser_;
};

}  // namespace
}  // namespace occtrack::ros_adapter

int main(int argc, char** argv) {
  ros::init(argc, argv, "occtrack_ros_sim");
  ros::NodeHandle nh, pnh("~");
  try {
    occtrack::ros_adapter::SimNode node(nh, pnh);
    ros::spin();
  } catch (const std::exception& e) {  // a missing or invalid scenario: say so and exit non-zero
    ROS_FATAL("occtrack sim: %s", e.what());
    return 1;
  }
  return 0;
}
