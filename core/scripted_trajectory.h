#pragma once
// Scripted trajectories (DESIGN.md §5): a pose follows a list of waypoints (press, slide,
// release, …), so a run is repeatable and every haptic mode can be measured against the
// reference on the same motion. The device handle follows one (device.trajectory), and so does a
// rigid object moved by a script (objects[].rigid.trajectory, contact/rigid_objects.h).
//
// Between waypoints i and i + 1 (times t_i < t_{i+1}, T = t_{i+1} − t_i), with the smoothstep
//   u = (t − t_i)/T,   s = 3u² − 2u³,   ṡ = 6u(1 − u)/T        (s(0) = 0, s(1) = 1, ṡ = 0 at both)
// the pose and its exact time derivatives are
//   x(t) = x_i + s (x_{i+1} − x_i)                          v(t) = ṡ (x_{i+1} − x_i)
//   q(t) = exp(s θ_i) q_i,   θ_i = log(q_{i+1} q_i⁻¹)       ω(t) = ṡ θ_i          (world frame)
// q(t) is the slerp from q_i to q_{i+1} at parameter s along the shorter arc (|θ_i| ≤ π; a turn
// of more than π between two waypoints goes the other way round: split it). Since exp(s θ_i)
// turns about a fixed axis, dR/dt = [ṡ θ_i]× R, so ω = ṡ θ_i exactly.
// The motion is C¹ with zero velocity at every waypoint: the handle comes to rest at each one.
// Before the first and after the last waypoint it holds still there. The buttons are held
// piecewise constant: those of waypoint i from t_i up to t_{i+1}.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "core/virtual_coupling.h"

namespace hapsim {

struct Waypoint {
  double t_s = 0.0;                                          // time, s
  Eigen::Vector3d x_W_m = Eigen::Vector3d::Zero();           // device position, world, m
  Eigen::Quaterniond q_WD = Eigen::Quaterniond::Identity();  // device orientation (normalised)
  int buttons = 0;  // DeviceState::buttons from this waypoint to the next
};

class ScriptedTrajectory {
 public:
  // Throws std::invalid_argument if `waypoints` is empty, a time, position or quaternion is not
  // finite, a quaternion is zero, or the times are not strictly increasing. Quaternions are
  // normalised.
  explicit ScriptedTrajectory(std::vector<Waypoint> waypoints);

  // Pose and velocity of the handle at time t_s (any time: held before the start and after the
  // end; a NaN time gives the first waypoint). Allocates nothing: called at the haptic rate.
  DeviceState Sample(double t_s) const;

  // Time from the first to the last waypoint, s (0 for a single waypoint).
  double duration_s() const { return end_time_s() - start_time_s(); }
  double start_time_s() const { return waypoints_.front().t_s; }
  double end_time_s() const { return waypoints_.back().t_s; }
  const std::vector<Waypoint>& waypoints() const { return waypoints_; }

 private:
  DeviceState Hold(int waypoint) const;

  std::vector<Waypoint> waypoints_;
  std::vector<Eigen::Vector3d> theta_W_rad_;  // (num waypoints − 1) θ_i = log(q_{i+1} q_i⁻¹), rad
};

}  // namespace hapsim
