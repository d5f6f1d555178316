#pragma once
// Online passivity observer at the device port (DESIGN.md §5; Hannaford & Ryu, "Time-domain
// passivity control of haptic interfaces", IEEE T-RA 18(1), 2002). The virtual environment
// (haptic step + safety layer) is a one-port seen from the device: it receives the handle's
// velocity and returns a wrench. It is passive if the energy that has flowed into it is never
// negative; Hannaford & Ryu observe that energy by summing the port power each sample:
//   E_k = E_{k−1} − Δt (F_k·v_k + T_k·ω_k),        E_0 = 0
// with F, T the wrench SENT to the device (world, acting on the user's hand) and v, ω the
// handle's velocity (world). F·v is the power delivered to the hand, so −F·v flows into the
// environment: a spring F = −k x stores energy and gives it back (E oscillates ≥ 0 and returns
// to 0 over whole periods); a damper F = −b v dissipates it (E = b∫v² grows); an environment
// that generates energy (a negative damper, an unstable contact loop) drives E below zero.
//
// E < −threshold_J means the environment has put out more energy than it took in: active()
// turns true and stays true (latched, so the loop warns once), with the index of the first
// Update at which it happened. The threshold keeps rounding and the first-order sampling of
// the sum from raising a false alarm on a merely lossless environment.
//
// The environment's own weight. The rendered tool hangs on the coupling under gravity, so a hand
// that lowers it receives its weight's work through the port: F·v > 0 for as long as it descends,
// m g h in all (25 mJ for a 50 g tool lowered 5 cm), which the sum above would count as energy the
// environment generated, though it only gave up potential energy. Gravity is a second, lossless
// port: its work on the environment's bodies over the step, W_g = m g·Δx (positive as the tool
// descends), enters E as energy flowed in,
//   E_k = E_{k−1} − Δt (F_k·v_k + T_k·ω_k) + W_g,k ,
// i.e. E is the port's energy less the gain in potential energy, m g·(x_0 − x): still ≥ 0 for a
// passive environment (the rest is kinetic and spring energy, and what damping took), while a
// loop that generates energy still drives it below zero.
//
// The force F_k is held over [t_k, t_k+1) while the sum pairs it with v_k; Hannaford & Ryu
// discuss this one-sample ambiguity. Callers pass the velocity measured at the step the force
// was sent, as the haptic loop has it.
//
// Update allocates nothing and throws nothing: it runs inside the 1 kHz loop.

#include <Eigen/Core>

namespace hapsim::device {

// The work gravity does on a body of mass m_kg moved from x_before to x_after (world, m): m g·Δx,
// J (positive when it descends).
inline double CalcGravityWork(double m_kg, const Eigen::Vector3d& gravity_m_s2,
                              const Eigen::Vector3d& x_before_W_m,
                              const Eigen::Vector3d& x_after_W_m) {
  return m_kg * gravity_m_s2.dot(x_after_W_m - x_before_W_m);
}

class PassivityObserver {
 public:
  // threshold_J: how far below zero E may go before active(), J (≥ 0; a negative or NaN value
  // is taken as 0).
  explicit PassivityObserver(double threshold_J = 1e-3);

  // One sample: F, T sent to the device (world; N, N m); v, w the handle's linear and angular
  // velocity (world; m/s, rad/s); dt_s the sample period (> 0); gravity_work_J the work gravity
  // did on the rendered tool over the step, m g·(x_after − x_before) (J; CalcGravityWork). A
  // sample with a non-finite entry or a non-positive dt is ignored (counted in num_ignored) but
  // still counts as a step.
  void Update(const Eigen::Vector3d& F, const Eigen::Vector3d& T, const Eigen::Vector3d& v,
              const Eigen::Vector3d& w, double dt_s, double gravity_work_J = 0.0) noexcept;

  // Energy that has flowed into the environment, J (≥ 0: passive so far).
  double energy_in_J() const { return energy_in_J_; }
  // E has gone below −threshold_J at some step (latched).
  bool active() const { return first_active_step_ >= 0; }
  // Index (0-based, counting every Update) of the first step with E < −threshold_J; −1: none.
  long first_active_step() const { return first_active_step_; }
  // Number of Update calls, ignored ones included.
  long steps() const { return steps_; }
  // Number of Update calls ignored for a non-finite input or a non-positive dt.
  long num_ignored() const { return num_ignored_; }
  double threshold_J() const { return threshold_J_; }

 private:
  double threshold_J_;
  double energy_in_J_ = 0.0;
  long first_active_step_ = -1;
  long steps_ = 0;
  long num_ignored_ = 0;
};

}  // namespace hapsim::device
