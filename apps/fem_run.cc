#include "apps/fem_run.h"

#include <stdexcept>


namespace hapsim::apps {

FemRunRecord RunFem(const config::Body& body, const fem::FemOptions& options, double dt_s,
                    int num_steps, const std::function<void(int)>& on_step) {
  fem::TimeStepper stepper(body.model, options, dt_s, body.external_force_N);
  FemRunRecord record;
  record.final_state = fem::MakeRestState(body.model);
  fem::State& state = record.final_state;
  record.steps.reserve(num_steps);
  for (int k = 0; k < num_steps; ++k) {
    record.steps.push_back(stepper.Step(&state));
    if (!state.x_m.allFinite() || !state.v_m_s.allFinite())
      throw std::runtime_error("the simulation diverged at step " + std::to_string(k + 1) +
                               " (t = " + std::to_string((k + 1) * dt_s) +
                               " s): node positions are no longer finite" +
                               (options.integrator == fem::IntegratorKind::kExplicitEuler
                                    ? "; explicit Euler is unstable above dt ≈ 2/ω_max, use the "
                                      "implicit integrator or a smaller dt_s"
                                    : ""));
    Eigen::Matrix3Xd probes_m(3, static_cast<Eigen::Index>(body.probes.size()));
    for (size_t p = 0; p < body.probes.size(); ++p)
      probes_m.col(static_cast<Eigen::Index>(p)) =
          fem::CalcProbeDisplacement(body.model, state, body.probes[p].binding);
    record.probe_displacements_m.push_back(std::move(probes_m));
    if (on_step) on_step(k + 1);
  }
  record.num_factorizations = stepper.solver()->num_factorizations();
  return record;
}

}  // namespace hapsim::apps
