#include "core/scripted_trajectory.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/rigid_tool.h"

namespace hapsim {
namespace {

void Require(bool condition, int waypoint, const std::string& message) {
  if (!condition) {
    throw std::invalid_argument("ScriptedTrajectory: waypoint " + std::to_string(waypoint) + " " +
                                message);
  }
}

}  // namespace

ScriptedTrajectory::ScriptedTrajectory(std::vector<Waypoint> waypoints)
    : waypoints_(std::move(waypoints)) {
  if (waypoints_.empty()) throw std::invalid_argument("ScriptedTrajectory: no waypoints");
  for (std::size_t i = 0; i < waypoints_.size(); ++i) {
    Waypoint& waypoint = waypoints_[i];
    const int index = static_cast<int>(i);
    Require(std::isfinite(waypoint.t_s), index, "has a time that is not finite");
    Require(waypoint.x_W_m.allFinite(), index, "has a position that is not finite");
    Require(waypoint.q_WD.coeffs().allFinite(), index, "has a quaternion that is not finite");
    Require(waypoint.q_WD.norm() > 0.0, index, "has a zero quaternion");
    waypoint.q_WD.normalize();
    if (i > 0) {
      Require(waypoint.t_s > waypoints_[i - 1].t_s, index,
              "is not later than the waypoint before it (times must strictly increase)");
      // CalcRotationVector picks the shorter of q and −q, so the slerp takes the shorter arc.
      theta_W_rad_.push_back(CalcRotationVector(waypoint.q_WD * waypoints_[i - 1].q_WD.inverse()));
    }
  }
}

DeviceState ScriptedTrajectory::Hold(int waypoint) const {
  DeviceState state;  // zero velocities
  state.x_W_m = waypoints_[waypoint].x_W_m;
  state.q_WD = waypoints_[waypoint].q_WD;
  state.buttons = waypoints_[waypoint].buttons;
  return state;
}

DeviceState ScriptedTrajectory::Sample(double t_s) const {
  const int last = static_cast<int>(waypoints_.size()) - 1;
  if (!(t_s > waypoints_.front().t_s)) return Hold(0);  // also a NaN time
  if (t_s >= waypoints_.back().t_s) return Hold(last);
  // The segment [t_i, t_{i+1}) holding t_s: the first waypoint later than t_s is i + 1.
  const auto later =
      std::upper_bound(waypoints_.begin(), waypoints_.end(), t_s,
                       [](double t, const Waypoint& waypoint) { return t < waypoint.t_s; });
  const int i = static_cast<int>(later - waypoints_.begin()) - 1;
  const Waypoint& from = waypoints_[i];
  const Waypoint& to = waypoints_[i + 1];

  const double period_s = to.t_s - from.t_s;
  const double u = (t_s - from.t_s) / period_s;
  const double s = u * u * (3.0 - 2.0 * u);
  const double s_dot_1_s = 6.0 * u * (1.0 - u) / period_s;

  DeviceState state;
  state.x_W_m = from.x_W_m + s * (to.x_W_m - from.x_W_m);
  state.v_W_m_s = s_dot_1_s * (to.x_W_m - from.x_W_m);
  state.q_WD = CalcQuaternionExp(s * theta_W_rad_[i]) * from.q_WD;
  state.w_W_rad_s = s_dot_1_s * theta_W_rad_[i];
  state.buttons = from.buttons;
  return state;
}

}  // namespace hapsim
