// occtrack_ros_check: the closed-loop test's judge (ros/test/closed_loop.sh). It listens to the node's cmd_vel
// and status and the simulator's target_visible, in phases (wall-clock windows), and sets the simulator's fault
// parameters between them:
//   1. tracking: cmd_vel arrives at >= min_rate_share of ~rate, every command finite, the target in sight in
//      >= min_visible_share of the samples;
//   2. NaN scan (~nan_scan on): every command an exact zero Twist, still at the rate, status naming the scan;
//   3. stale target (~target_delay 2 s, beyond the node's 0.5 s timeout): the same, status naming the target;
//   4. recovered (faults off): finite commands again, some of them moving, status "tracking".
// Prints one line per phase with the measured figures and exits 0 when every check held, 1 otherwise.
#include <ros/callback_queue.h>
#include <ros/ros.h>

#include <geometry_msgs/Twist.h>
#include <std_msgs/Bool.h>
#include <std_msgs/String.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace {

struct Window {
  int commands = 0, non_finite = 0, non_zero = 0, visible = 0, visible_samples = 0;
  double largest_gap = 0.0;  // s between two commands
  std::string last_status;
};

class Checker {
 public:
  explicit Checker(ros::NodeHandle& nh) {
    cmd_sub_ = nh.subscribe("cmd_vel", 100, &Checker::on_cmd, this);
    status_sub_ = nh.subscribe("status", 100, &Checker::on_status, this);
    visible_sub_ = nh.subscribe("target_visible", 100, &Checker::on_visible, this);
  }

  /// Spins until the first command arrives (the node has loaded its model and the simulator is up).
  bool wait_for_first_command(double timeout) {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(timeout);
    while (ros::ok() && window_.commands == 0 && ros::WallTime::now() < until) spin_for(0.05);
    return window_.commands > 0;
  }
  /// Spins for `seconds` and returns what arrived meanwhile.
  Window collect(double seconds) {
    window_ = Window{};
    last_command_ = ros::WallTime();
    spin_for(seconds);
    return window_;
  }
  void spin_for(double seconds) {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(seconds);
    while (ros::ok() && ros::WallTime::now() < until) {
      ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.01));
    }
  }

 private:
  void on_cmd(const geometry_msgs::Twist::ConstPtr& msg) {
    const ros::WallTime now = ros::WallTime::now();
    if (!last_command_.isZero()) window_.largest_gap = std::max(window_.largest_gap, (now - last_command_).toSec());
    last_command_ = now;
    ++window_.commands;
    const double values[] = {msg->linear.x, msg->linear.y, msg->linear.z, msg->angular.x, msg->angular.y, msg->angular.z};
    bool finite = true, zero = true;
    for (double v : values) {
      finite = finite && std::isfinite(v);
      zero = zero && v == 0.0;
    }
    if (!finite) ++window_.non_finite;
    if (!zero) ++window_.non_zero;
  }
  void on_status(const std_msgs::String::ConstPtr& msg) { window_.last_status = msg->data; }
  void on_visible(const std_msgs::Bool::ConstPtr& msg) {
    ++window_.visible_samples;
    if (msg->data) ++window_.visible;
  }

  ros::Subscriber cmd_sub_, status_sub_, visible_sub_;
  Window window_;
  ros::WallTime last_command_;
};

bool check(bool ok, const char* what) {
  if (!ok) std::printf("  FAILED: %s\n", what);
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "occtrack_ros_check");
  ros::NodeHandle nh, pnh("~");
  double rate = 20.0, duration = 8.0, fault_duration = 2.0, settle = 1.0;
  double min_rate_share = 0.8, min_visible_share = 0.9;
  std::string sim = "/occtrack_ros_sim";
  pnh.param("rate", rate, rate);
  pnh.param("duration", duration, duration);
  pnh.param("fault_duration", fault_duration, fault_duration);
  pnh.param("settle", settle, settle);
  pnh.param("min_rate_share", min_rate_share, min_rate_share);
  pnh.param("min_visible_share", min_visible_share, min_visible_share);
  pnh.param("sim", sim, sim);
  Checker checker(nh);
  bool ok = true;

  if (!checker.wait_for_first_command(60.0)) {
    std::printf("FAILED: no cmd_vel within 60 s\n");
    return 1;
  }
  // Phase 1: tracking.
  const Window w = checker.collect(duration);
  const double command_rate = w.commands / duration;
  const double in_sight = w.visible_samples > 0 ? double(w.visible) / w.visible_samples : 0.0;
  std::printf("tracking: %.1f s, %d commands (%.2f Hz, %.0f%% of %.0f Hz, largest gap %.3f s), %d non-finite, "
              "target in sight %.1f%% of %d samples, status \"%s\"\n",
              duration, w.commands, command_rate, 100.0 * command_rate / rate, rate, w.largest_gap, w.non_finite,
              100.0 * in_sight, w.visible_samples, w.last_status.c_str());
  ok &= check(command_rate >= min_rate_share * rate, "cmd_vel rate below min_rate_share of the planning rate");
  ok &= check(w.non_finite == 0, "non-finite cmd_vel");
  ok &= check(w.non_zero > 0, "the robot never moved");
  ok &= check(in_sight >= min_visible_share, "target in sight less than min_visible_share of the time");

  // Phases 2 and 3: faults; the node must publish exact zero Twists at its rate and say why.
  struct Fault {
    const char* name;
    bool nan_scan;
    double target_delay;
    const char* status;
  };
  for (const Fault& f : {Fault{"NaN scan", true, 0.0, "stopped: scan"}, Fault{"stale target", false, 2.0, "stopped: target: stale"}}) {
    ros::param::set(sim + "/nan_scan", f.nan_scan);
    ros::param::set(sim + "/target_delay", f.target_delay);
    checker.spin_for(settle);
    const Window fw = checker.collect(fault_duration);
    std::printf("%s: %d commands (%.2f Hz), %d non-zero, %d non-finite, status \"%s\"\n", f.name, fw.commands,
                fw.commands / fault_duration, fw.non_zero, fw.non_finite, fw.last_status.c_str());
    ok &= check(fw.commands >= min_rate_share * rate * fault_duration, "too few commands while stopped");
    ok &= check(fw.non_zero == 0 && fw.non_finite == 0, "a command other than a zero Twist while stopped");
    ok &= check(fw.last_status.rfind(f.status, 0) == 0, "status does not give the reason");
  }

  // Phase 4: the faults cleared, tracking resumes.
  ros::param::set(sim + "/nan_scan", false);
  ros::param::set(sim + "/target_delay", 0.0);
  checker.spin_for(settle);
  const Window rw = checker.collect(fault_duration);
  std::printf("recovered: %d commands, %d non-zero, %d non-finite, status \"%s\"\n", rw.commands, rw.non_zero,
              rw.non_finite, rw.last_status.c_str());
  ok &= check(rw.non_zero > 0 && rw.non_finite == 0, "no finite moving command after the faults cleared");
  ok &= check(rw.last_status == "tracking", "status is not \"tracking\" after the faults cleared");

  std::printf("%s\n", ok ? "PASSED" : "FAILED");
  return ok ? 0 : 1;
}
