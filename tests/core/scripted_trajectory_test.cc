// Tests of core/scripted_trajectory.h: waypoints hit exactly, velocities are the exact time
// derivatives of the interpolation (against central differences), zero velocity at waypoints,
// hold before and after, the slerp takes the shorter arc, bad input throws, Sample allocates
// nothing.

#include "core/scripted_trajectory.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "core/rigid_tool.h"
#include "core/virtual_coupling.h"
#include "tests/allocation_counter.h"

namespace hapsim {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Central differences with step h: truncation h²/6·|x'''| (|x'''| ≤ 12|Δx|/T³ ~ 1 m/s³ here, so
// ~1e-13) plus rounding ~ε|x|/h ~ 1e-11. 1e-8 leaves room and is still ~1e-6 of the velocities.
constexpr double kFdStep_s = 1e-6;
constexpr double kFdTolerance = 1e-8;

Eigen::Quaterniond Rotation(double angle_rad, const Eigen::Vector3d& axis) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle_rad, axis.normalized()));
}

// Press, slide with a twist, release; uneven segment lengths.
std::vector<Waypoint> PressSlideRelease() {
  return {
      {0.0, Eigen::Vector3d(0.0, 0.0, 0.071), Eigen::Quaterniond::Identity(), 0},
      {0.2, Eigen::Vector3d(0.0, 0.0, 0.071), Eigen::Quaterniond::Identity(), 0},
      {1.0, Eigen::Vector3d(0.0, 0.0, 0.066), Rotation(0.3, Eigen::Vector3d(1, 0, 0)), 1},
      {2.0, Eigen::Vector3d(0.02, 0.0, 0.066), Rotation(-0.5, Eigen::Vector3d(1, 2, 3)), 1},
      {2.8, Eigen::Vector3d(0.02, 0.01, 0.071), Rotation(2.5, Eigen::Vector3d(0, 1, 1)), 0},
      {3.0, Eigen::Vector3d(0.02, 0.01, 0.071), Rotation(2.5, Eigen::Vector3d(0, 1, 1)), 0},
  };
}

void ExpectAtRest(const DeviceState& state, const Waypoint& waypoint) {
  EXPECT_EQ(state.x_W_m, waypoint.x_W_m);
  EXPECT_EQ(state.q_WD.coeffs(), waypoint.q_WD.coeffs());
  EXPECT_EQ(state.v_W_m_s, Eigen::Vector3d::Zero());
  EXPECT_EQ(state.w_W_rad_s, Eigen::Vector3d::Zero());
}

// The button is held from a waypoint up to the next: pressed on [1.0, 2.8) here, released at 2.8.
TEST(ScriptedTrajectoryTest, ButtonsHoldFromEachWaypointToTheNext) {
  const ScriptedTrajectory trajectory(PressSlideRelease());
  for (const double t_s : {-1.0, 0.0, 0.5, 0.999999}) EXPECT_EQ(trajectory.Sample(t_s).buttons, 0);
  for (const double t_s : {1.0, 1.5, 2.0, 2.799999}) EXPECT_EQ(trajectory.Sample(t_s).buttons, 1);
  for (const double t_s : {2.8, 2.9, 3.0, 10.0}) EXPECT_EQ(trajectory.Sample(t_s).buttons, 0);
}

TEST(ScriptedTrajectoryTest, WaypointsAreHitExactlyAtRest) {
  const std::vector<Waypoint> given = PressSlideRelease();
  const ScriptedTrajectory trajectory(given);
  ASSERT_EQ(trajectory.waypoints().size(), given.size());
  for (std::size_t i = 0; i < given.size(); ++i) {
    SCOPED_TRACE(i);
    ExpectAtRest(trajectory.Sample(given[i].t_s), trajectory.waypoints()[i]);
    EXPECT_EQ(trajectory.waypoints()[i].x_W_m, given[i].x_W_m);
    EXPECT_LT((trajectory.waypoints()[i].q_WD.coeffs() - given[i].q_WD.coeffs()).norm(), 1e-15);
  }
  EXPECT_EQ(trajectory.start_time_s(), 0.0);
  EXPECT_EQ(trajectory.end_time_s(), 3.0);
  EXPECT_EQ(trajectory.duration_s(), 3.0);
}

TEST(ScriptedTrajectoryTest, ContinuousWithZeroVelocityArrivingAtWaypoints) {
  const ScriptedTrajectory trajectory(PressSlideRelease());
  constexpr double kJustBefore_s = 1e-9;
  for (const Waypoint& waypoint : trajectory.waypoints()) {
    SCOPED_TRACE(waypoint.t_s);
    const DeviceState before = trajectory.Sample(waypoint.t_s - kJustBefore_s);
    // Position error ~ s(1) − s(1 − δ/T) ~ 3(δ/T)² |Δx|; velocity ~ 6 δ/T² |Δx|: both tiny.
    EXPECT_LT((before.x_W_m - waypoint.x_W_m).norm(), 1e-12);
    EXPECT_LT(before.q_WD.angularDistance(waypoint.q_WD), 1e-9);
    EXPECT_LT(before.v_W_m_s.norm(), 1e-9);
    EXPECT_LT(before.w_W_rad_s.norm(), 1e-7);
  }
}

TEST(ScriptedTrajectoryTest, HoldsBeforeTheFirstAndAfterTheLastWaypoint) {
  std::vector<Waypoint> waypoints = PressSlideRelease();
  for (Waypoint& waypoint : waypoints) waypoint.t_s += 0.5;  // starts later than t = 0
  const ScriptedTrajectory trajectory(waypoints);
  for (const double t_s : {-1.0, 0.0, 0.25, 0.5})
    ExpectAtRest(trajectory.Sample(t_s), waypoints[0]);
  for (const double t_s : {3.5, 3.6, 100.0, std::numeric_limits<double>::infinity()}) {
    ExpectAtRest(trajectory.Sample(t_s), trajectory.waypoints().back());
  }
  ExpectAtRest(trajectory.Sample(std::nan("")), waypoints[0]);
  EXPECT_EQ(trajectory.duration_s(), 3.0);
}

TEST(ScriptedTrajectoryTest, SingleWaypointHoldsForever) {
  const Waypoint only{1.0, Eigen::Vector3d(1, 2, 3), Rotation(1.0, Eigen::Vector3d(0, 0, 1))};
  const ScriptedTrajectory trajectory({only});
  for (const double t_s : {-5.0, 1.0, 7.0}) ExpectAtRest(trajectory.Sample(t_s), only);
  EXPECT_EQ(trajectory.duration_s(), 0.0);
}

TEST(ScriptedTrajectoryTest, FollowsTheSmoothstep) {
  const ScriptedTrajectory trajectory(
      {{1.0, Eigen::Vector3d(0, 0, 0), Rotation(0.0, Eigen::Vector3d(0, 0, 1))},
       {3.0, Eigen::Vector3d(4, 0, 0), Rotation(1.2, Eigen::Vector3d(0, 0, 1))}});
  // t = 1.5: u = 1/4, s = 3/16 − 2/64 = 5/32, ṡ = 6·(1/4)(3/4)/2 s⁻¹ = 9/16 s⁻¹.
  const DeviceState quarter = trajectory.Sample(1.5);
  EXPECT_NEAR(quarter.x_W_m.x(), 4.0 * 5.0 / 32.0, 1e-15);
  EXPECT_NEAR(quarter.v_W_m_s.x(), 4.0 * 9.0 / 16.0, 1e-15);
  EXPECT_NEAR(quarter.q_WD.angularDistance(Rotation(1.2 * 5.0 / 32.0, Eigen::Vector3d(0, 0, 1))),
              0.0, 1e-15);
  EXPECT_LT((quarter.w_W_rad_s - Eigen::Vector3d(0, 0, 1.2 * 9.0 / 16.0)).norm(), 1e-15);
  // Midpoint: s = 1/2 and the largest speed, ṡ = 3/(2T).
  const DeviceState middle = trajectory.Sample(2.0);
  EXPECT_NEAR(middle.x_W_m.x(), 2.0, 1e-15);
  EXPECT_NEAR(middle.v_W_m_s.x(), 4.0 * 3.0 / 4.0, 1e-15);
}

TEST(ScriptedTrajectoryTest, VelocitiesAreTheDerivativesOfThePose) {
  const ScriptedTrajectory trajectory(PressSlideRelease());
  std::mt19937 random(7);
  std::uniform_real_distribution<double> time_s(0.0, 3.0);
  int num_checked = 0;
  while (num_checked < 200) {
    const double t_s = time_s(random);
    // The acceleration jumps at a waypoint: keep the difference stencil inside one segment.
    bool near_waypoint = false;
    for (const Waypoint& waypoint : trajectory.waypoints()) {
      near_waypoint = near_waypoint || std::abs(t_s - waypoint.t_s) < 2.0 * kFdStep_s;
    }
    if (near_waypoint) continue;
    SCOPED_TRACE(t_s);
    const DeviceState state = trajectory.Sample(t_s);
    const DeviceState after = trajectory.Sample(t_s + kFdStep_s);
    const DeviceState before = trajectory.Sample(t_s - kFdStep_s);
    const Eigen::Vector3d v_fd = (after.x_W_m - before.x_W_m) / (2.0 * kFdStep_s);
    // World angular velocity: q(t + h) = exp(ω 2h) q(t − h) to second order.
    const Eigen::Vector3d w_fd =
        CalcRotationVector(after.q_WD * before.q_WD.inverse()) / (2.0 * kFdStep_s);
    EXPECT_LT((state.v_W_m_s - v_fd).norm(), kFdTolerance);
    EXPECT_LT((state.w_W_rad_s - w_fd).norm(), kFdTolerance);
    EXPECT_NEAR(state.q_WD.norm(), 1.0, 1e-14);
    ++num_checked;
  }
}

TEST(ScriptedTrajectoryTest, SlerpTakesTheShorterArc) {
  // q and −q are the same rotation: the handle must not turn at all.
  const Eigen::Quaterniond q = Rotation(0.7, Eigen::Vector3d(1, 1, 0));
  const Eigen::Quaterniond minus_q(-q.w(), -q.x(), -q.y(), -q.z());
  const ScriptedTrajectory same(
      {{0.0, Eigen::Vector3d::Zero(), q}, {1.0, Eigen::Vector3d::Zero(), minus_q}});
  EXPECT_LT(same.Sample(0.5).w_W_rad_s.norm(), 1e-15);
  EXPECT_LT(same.Sample(0.5).q_WD.angularDistance(q), 1e-15);
  // From 0 to 3π/2 about z is −π/2 the short way round.
  const ScriptedTrajectory turn(
      {{0.0, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity()},
       {1.0, Eigen::Vector3d::Zero(), Rotation(1.5 * kPi, Eigen::Vector3d(0, 0, 1))}});
  EXPECT_LT(turn.Sample(0.5).q_WD.angularDistance(Rotation(-0.25 * kPi, Eigen::Vector3d(0, 0, 1))),
            1e-14);
  EXPECT_LT(turn.Sample(0.5).w_W_rad_s.z(), 0.0);
}

TEST(ScriptedTrajectoryTest, NormalisesQuaternions) {
  const Eigen::Quaterniond scaled(Eigen::Vector4d(0.0, 0.0, 0.0, 2.0));  // (x, y, z, w): 2·identity
  const ScriptedTrajectory trajectory({{0.0, Eigen::Vector3d::Zero(), scaled}});
  EXPECT_EQ(trajectory.Sample(0.0).q_WD.coeffs(), Eigen::Quaterniond::Identity().coeffs());
}

TEST(ScriptedTrajectoryTest, BadInputThrows) {
  EXPECT_THROW(ScriptedTrajectory({}), std::invalid_argument);
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  const Eigen::Quaterniond identity = Eigen::Quaterniond::Identity();
  const double nan = std::nan("");
  const std::vector<std::vector<Waypoint>> bad = {
      {{0.0, zero, identity}, {0.0, zero, identity}},                         // equal times
      {{1.0, zero, identity}, {2.0, zero, identity}, {1.5, zero, identity}},  // decreasing
      {{nan, zero, identity}},                                                // NaN time
      {{0.0, zero, identity}, {std::numeric_limits<double>::infinity(), zero, identity}},
      {{0.0, Eigen::Vector3d(0, nan, 0), identity}},    // NaN position
      {{0.0, zero, Eigen::Quaterniond(0, 0, 0, 0)}},    // zero quaternion
      {{0.0, zero, Eigen::Quaterniond(nan, 0, 0, 0)}},  // NaN quaternion
  };
  for (std::size_t i = 0; i < bad.size(); ++i) {
    EXPECT_THROW(ScriptedTrajectory{bad[i]}, std::invalid_argument) << "case " << i;
  }
  try {
    ScriptedTrajectory({{1.0, zero, identity}, {2.0, zero, identity}, {1.5, zero, identity}});
    ADD_FAILURE() << "no error for decreasing times";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("waypoint 2"), std::string::npos) << error.what();
  }
}

TEST(ScriptedTrajectoryTest, SampleAllocatesNothing) {
  const ScriptedTrajectory trajectory(PressSlideRelease());
  double checksum = 0.0;
  if (!AllocationCounter::enabled()) GTEST_SKIP() << "allocations not counted (sanitizer build)";
  const AllocationCounter counter;  // counts operator new and malloc (Eigen uses the latter)
  for (int k = -100; k <= 3100; ++k) checksum += trajectory.Sample(k * 1e-3).x_W_m.sum();
  EXPECT_EQ(counter.count(), 0);
  EXPECT_TRUE(std::isfinite(checksum));
}

}  // namespace
}  // namespace hapsim
