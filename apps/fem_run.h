#pragma once
// A headless FEM-only run of a scene's deformable body: the stepping loop and what it records.
// Used by `hapsim fem` (outputs) and `hapsim fem --bench` (timings against a second solver).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "config/body_builder.h"
#include "config/scene.h"
#include "fem/state.h"
#include "fem/time_stepper.h"

namespace hapsim::apps {

struct FemRunRecord {
  std::vector<fem::StepStats> steps;
  std::vector<Eigen::Matrix3Xd> probe_displacements_m;  // per step: (3 x num_probes)
  fem::State final_state;
  int num_factorizations = 0;  // CG with lagged Cholesky: numeric factorisations done
};

// Runs scene.num_steps steps from rest. `on_step(k)` is called after step k (progress).
// Throws std::runtime_error naming the step if the state stops being finite (e.g. explicit
// Euler above its stability limit).
FemRunRecord RunFem(const config::Body& body, const fem::FemOptions& options, double dt_s,
                    int num_steps, const std::function<void(int)>& on_step = {});

}  // namespace hapsim::apps
