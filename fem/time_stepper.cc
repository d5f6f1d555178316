#include "fem/time_stepper.h"

#include <algorithm>
#include <cstdint>
#include <stdexcept>

#include "core/stopwatch.h"
#include "fem/corotational.h"

namespace hapsim::fem {

TimeStepper::TimeStepper(const Model& model, const FemOptions& options, double dt_s,
                         Eigen::VectorXd external_force_N)
    : model_(model),
      options_(options),
      dt_s_(dt_s),
      external_force_N_(std::move(external_force_N)),
      assembler_(model),
      solver_(MakeLinearSolver(options.solver)),
      system_(assembler_.MakeMatrix()) {
  if (!(dt_s > 0.0)) throw std::invalid_argument("time step must be positive");
  if (external_force_N_.size() != model.num_dofs())
    throw std::invalid_argument("external force must have 3N entries");
  for (int i = 0; i < model.num_dofs(); ++i)
    if (model.dof_is_fixed[i]) fixed_dofs_.push_back(i);
  for (Eigen::Index col = 0; col < system_.outerSize(); ++col)
    for (int k = system_.outerIndexPtr()[col]; k < system_.outerIndexPtr()[col + 1]; ++k) {
      const int row = system_.innerIndexPtr()[k];
      if (row != col && (model.dof_is_fixed[row] || model.dof_is_fixed[col]))
        fixed_offdiagonal_value_index_.push_back(k);
    }
  delta_v_m_s_.setZero(model.num_dofs());
  for (int o = 0; o < model.num_objects(); ++o)
    has_free_object_ |= std::none_of(model.dof_is_fixed.begin() + 3 * model.object_first_node(o),
                                     model.dof_is_fixed.begin() + 3 * model.object_end_node(o),
                                     [](std::uint8_t fixed) { return fixed != 0; });
  if (options.integrator == IntegratorKind::kImplicitEuler) solver_->AnalyzePattern(system_);
}

StepStats TimeStepper::Step(State* state) {
  Stopwatch total;
  StepStats stats = CalcFreeVelocityChange(*state, &delta_v_m_s_);
  Advance(delta_v_m_s_, state);
  stats.total_s = total.Elapsed();
  return stats;
}

StepStats TimeStepper::CalcFreeVelocityChange(const State& state, Eigen::VectorXd* dv_m_s) {
  return options_.integrator == IntegratorKind::kImplicitEuler
             ? CalcImplicitVelocityChange(state, dv_m_s)
             : CalcExplicitVelocityChange(state, dv_m_s);
}

SolveReport TimeStepper::SolveWithSystemMatrix(const Eigen::VectorXd& rhs,
                                               double relative_tolerance, Eigen::VectorXd* x) {
  if (options_.integrator != IntegratorKind::kImplicitEuler)
    throw std::logic_error("SolveWithSystemMatrix needs the implicit integrator");
  scratch_rhs_ = rhs;
  for (int i : fixed_dofs_) scratch_rhs_[i] = 0.0;
  // system_ is as the free step's solve left it: a direct solver reuses that factor rather than
  // factoring A a second time in the frame.
  return solver_->SolveAgain(system_, scratch_rhs_,
                             std::max(relative_tolerance, options_.solver.relative_tolerance), x);
}

Eigen::MatrixXd TimeStepper::CalcCompliance(const Eigen::SparseMatrix<double>& J) {
  CholmodFactor* factor = solver_->factor();
  if (options_.integrator != IntegratorKind::kImplicitEuler || factor == nullptr)
    throw std::logic_error(
        "contact compliance needs the implicit integrator and a Cholesky factor (solver cholmod "
        "or cg with the lagged_cholesky preconditioner)");
  return factor->CalcInverseQuadraticForm(J);
}

void TimeStepper::Advance(const Eigen::VectorXd& dv_m_s, State* state) const {
  state->v_m_s += dv_m_s;
  for (int i : fixed_dofs_) state->v_m_s[i] = 0.0;
  state->x_m += dt_s_ * state->v_m_s;
}

void TimeStepper::AddMassAndFixedDofs(Eigen::SparseMatrix<double>* A) const {
  const double alpha = model_.material.rayleigh_alpha_1_s;
  double* values = A->valuePtr();
  for (int i = 0; i < model_.num_dofs(); ++i)
    values[assembler_.diagonal_value_index()[i]] += (1.0 + dt_s_ * alpha) * model_.dof_mass_kg[i];
  for (int k : fixed_offdiagonal_value_index_) values[k] = 0.0;
  for (int i : fixed_dofs_) values[assembler_.diagonal_value_index()[i]] = 1.0;
}

double TimeStepper::StiffnessScale() const {
  return dt_s_ * (model_.material.rayleigh_beta_s + dt_s_);
}

Eigen::SparseMatrix<double> TimeStepper::MakeRestSystemMatrix() const {
  Eigen::SparseMatrix<double> A = assembler_.MakeMatrix();
  assembler_.Assemble(model_,
                      std::vector<Eigen::Matrix3d>(model_.num_tets(), Eigen::Matrix3d::Identity()),
                      StiffnessScale(), &A);
  AddMassAndFixedDofs(&A);
  return A;
}

StepStats TimeStepper::CalcImplicitVelocityChange(const State& state, Eigen::VectorXd* dv_m_s) {
  const double h = dt_s_;
  const double alpha = model_.material.rayleigh_alpha_1_s;
  const double beta = model_.material.rayleigh_beta_s;
  StepStats stats;
  Stopwatch total, stage;

  CalcElementRotations(model_, state.x_m, options_.elasticity, &rotations_);
  stats.rotations_s = stage.Lap();

  // With the rotations held, f_el is affine in x (f_el(x) = −Σ_e R_e K_e (R_eᵀ x_e − X_e)), so
  //   f_el(x) − (β + Δt) K v = f_el(x + (β + Δt) v):
  // one element pass at the shifted positions gives the elastic, damping and implicit terms of
  // Δt F̃ = Δt (f_ext + f_el − αM v − (β + Δt) K v), with no product with K.
  shifted_x_m_ = state.x_m + (beta + h) * state.v_m_s;
  CalcElasticForce(model_, shifted_x_m_, rotations_, &elastic_force_N_);
  rhs_ = h * (external_force_N_ + elastic_force_N_ -
              alpha * model_.dof_mass_kg.cwiseProduct(state.v_m_s));
  // A = (1 + Δt α) M + (Δt β + Δt²) K: K is assembled already scaled.
  assembler_.Assemble(model_, rotations_, StiffnessScale(), &system_);
  AddMassAndFixedDofs(&system_);
  for (int i : fixed_dofs_) rhs_[i] = 0.0;
  stats.assembly_s = stage.Lap();

  if (dv_m_s->size() != rhs_.size()) dv_m_s->setZero(rhs_.size());
  stats.solve = solver_->Solve(system_, rhs_, options_.solver.relative_tolerance,
                               dv_m_s);  // warm start: the caller's previous Δv
  stats.solve_s = stage.Lap();
  stats.total_s = total.Elapsed();
  return stats;
}

StepStats TimeStepper::CalcExplicitVelocityChange(const State& state, Eigen::VectorXd* dv_m_s) {
  const double h = dt_s_;
  const double alpha = model_.material.rayleigh_alpha_1_s;
  const double beta = model_.material.rayleigh_beta_s;
  StepStats stats;
  Stopwatch total, stage;

  CalcElementRotations(model_, state.x_m, options_.elasticity, &rotations_);
  stats.rotations_s = stage.Lap();

  // f_el(x) − β K v = f_el(x + β v) with the rotations held (as in the implicit step).
  shifted_x_m_ = state.x_m + beta * state.v_m_s;
  CalcElasticForce(model_, shifted_x_m_, rotations_, &elastic_force_N_);
  rhs_ =
      external_force_N_ + elastic_force_N_ - alpha * model_.dof_mass_kg.cwiseProduct(state.v_m_s);
  stats.assembly_s = stage.Lap();

  *dv_m_s = h * rhs_.cwiseQuotient(model_.dof_mass_kg);
  stats.solve.converged = true;
  stats.total_s = total.Elapsed();
  return stats;
}

Eigen::VectorXd CalcGravityForce(const Model& model, const Eigen::Vector3d& gravity_m_s2) {
  Eigen::VectorXd force_N(model.num_dofs());
  for (int n = 0; n < model.num_nodes(); ++n)
    force_N.segment<3>(3 * n) = model.node_mass_kg[n] * gravity_m_s2;
  return force_N;
}

double CalcKineticEnergy(const Model& model, const State& state) {
  return 0.5 * state.v_m_s.dot(model.dof_mass_kg.cwiseProduct(state.v_m_s));
}

}  // namespace hapsim::fem
