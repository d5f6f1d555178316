// Google Benchmark: the stages of one implicit FEM step on the reference blocks (DESIGN.md §7).
// Not a test: run `build/tests/fem_step_benchmark` from the repository root (it reads scenes/).
// The state is first advanced 30 steps from rest so rotations and CG warm starts are realistic.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

#include "config/body_builder.h"
#include "config/scene.h"
#include "fem/corotational.h"
#include "fem/stiffness_assembly.h"
#include "fem/time_stepper.h"
#include "fem/warped_compliance.h"

namespace hapsim {
namespace {

// Fixtures 0-2: the scenes as they are (linear tets). 3-4: quadratic tets (issue 27) on
// block_tiny's box, 5 x 5 x 2 cells (250 tets, the size of the cheapest P2 frames of the graded
// Hertz and punch meshes in docs/RESULTS.md) and its own 8 x 8 x 3 (960 tets).
struct FixtureSpec {
  const char* scene;
  bool quadratic;
  Eigen::Vector3i cells;  // zero: the scene's
};
const FixtureSpec kFixtures[] = {
    {"scenes/block_tiny.yaml", false, Eigen::Vector3i::Zero()},
    {"scenes/block_small.yaml", false, Eigen::Vector3i::Zero()},
    {"scenes/block_large.yaml", false, Eigen::Vector3i::Zero()},
    {"scenes/block_tiny.yaml", true, Eigen::Vector3i(5, 5, 2)},
    {"scenes/block_tiny.yaml", true, Eigen::Vector3i::Zero()}};
constexpr int kNumFixtures = sizeof(kFixtures) / sizeof(kFixtures[0]);
constexpr int kWarmUpSteps = 30;

struct Fixture {
  config::Scene scene;
  config::Body body;
  fem::State state;
};

// Built once per scene and kept: meshing the large block is not what is measured.
const Fixture& GetFixture(int index) {
  static Fixture* fixtures[kNumFixtures] = {};
  if (!fixtures[index]) {
    const FixtureSpec& spec = kFixtures[index];
    auto* f = new Fixture{config::LoadScene(spec.scene), {}, {}};
    f->scene.body->quadratic = spec.quadratic;
    if (spec.cells != Eigen::Vector3i::Zero()) f->scene.body->mesh.cells = spec.cells;
    f->body = config::MakeBody(*f->scene.body, f->scene.gravity_m_s2);
    f->state = fem::MakeRestState(f->body.model);
    fem::TimeStepper stepper(f->body.model, f->scene.body->options, f->scene.dt_s,
                             f->body.external_force_N);
    for (int k = 0; k < kWarmUpSteps; ++k) stepper.Step(&f->state);
    fixtures[index] = f;
  }
  return *fixtures[index];
}

void SetCounters(benchmark::State& bench, const Fixture& f) {
  bench.counters["tets"] = f.body.model.num_tets();
  bench.counters["dofs"] = f.body.model.num_dofs();
}

void BM_Rotations(benchmark::State& bench) {
  const Fixture& f = GetFixture(static_cast<int>(bench.range(0)));
  std::vector<Eigen::Matrix3d> rotations;
  for (auto _ : bench) {
    fem::CalcElementRotations(f.body.model, f.state.x_m, fem::ElasticityKind::kCorotational,
                              &rotations);
    benchmark::DoNotOptimize(rotations.data());
  }
  SetCounters(bench, f);
}

void BM_ForcesAndStiffness(benchmark::State& bench) {
  const Fixture& f = GetFixture(static_cast<int>(bench.range(0)));
  std::vector<Eigen::Matrix3d> rotations;
  fem::CalcElementRotations(f.body.model, f.state.x_m, fem::ElasticityKind::kCorotational,
                            &rotations);
  const fem::StiffnessAssembler assembler(f.body.model);
  Eigen::SparseMatrix<double> K = assembler.MakeMatrix();
  Eigen::VectorXd force_N;
  for (auto _ : bench) {
    assembler.Assemble(f.body.model, rotations, /*scale=*/1.0, &K);
    fem::CalcElasticForce(f.body.model, f.state.x_m, rotations, &force_N);
    benchmark::DoNotOptimize(K.valuePtr());
    benchmark::DoNotOptimize(force_N.data());
  }
  SetCounters(bench, f);
}

// A whole implicit step, continuing the motion (the state keeps evolving across iterations).
void BM_ImplicitStep(benchmark::State& bench) {
  const Fixture& f = GetFixture(static_cast<int>(bench.range(0)));
  fem::FemOptions options = f.scene.body->options;
  options.solver.kind =
      bench.range(1) == 0 ? fem::SolverKind::kConjugateGradient : fem::SolverKind::kCholmod;
  fem::TimeStepper stepper(f.body.model, options, f.scene.dt_s, f.body.external_force_N);
  fem::State state = f.state;
  stepper.Step(&state);  // first step: first factorisation (the ordering is the constructor's)
  double iterations = 0.0;
  for (auto _ : bench) iterations += stepper.Step(&state).solve.iterations;
  SetCounters(bench, f);
  bench.counters["iterations"] = benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
}

// The top face's nodes, nearest the vertical axis first.
std::vector<int> TopNodesFromTheCentre(const fem::Model& model) {
  const double top_m = model.mesh.rest_positions_m.row(2).maxCoeff();
  std::vector<std::pair<double, int>> top;
  for (int n = 0; n < model.num_nodes(); ++n)
    if (model.mesh.rest_positions_m(2, n) > top_m - 1e-9)
      top.emplace_back(model.mesh.rest_positions_m.col(n).head<2>().norm(), n);
  std::sort(top.begin(), top.end());
  std::vector<int> nodes;
  for (const auto& [distance_m, node] : top) nodes.push_back(node);
  return nodes;
}

// Rows of contacts on the top nodes nearest the centre, 1 a contact (normal −z) or 3 (and the
// tangents x, y): a flat tool pressing down, with friction for 3.
// Contact rows on the top face, from its centre out: rows_per_contact 1 (the normal) or 3 (with two
// tangents); nodes_per_contact 1 (a body node against the tool) or 3 (a tool point on a face, each
// contact sharing nodes with its neighbours: contact i touches top nodes i/2 to i/2 + 2, as
// block_press's face contacts do, 1.6 nodes a row over 118 nodes at 212 rows).
Eigen::SparseMatrix<double> MakeTopContactRows(const fem::Model& model, int num_contacts,
                                               int rows_per_contact, int nodes_per_contact = 1) {
  const std::vector<int> top = TopNodesFromTheCentre(model);
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < num_contacts; ++i)
    for (int n = 0; n < nodes_per_contact; ++n) {
      const int node = nodes_per_contact == 1 ? top[i] : top[i / 2 + n];
      const double weight = 1.0 / nodes_per_contact;
      for (int k = 0; k < rows_per_contact; ++k)
        entries.emplace_back(rows_per_contact * i + k, 3 * node + (k == 0 ? 2 : k - 1),
                             k == 0 ? -weight : weight);
    }
  Eigen::SparseMatrix<double> J(rows_per_contact * num_contacts, model.num_dofs());
  J.setFromTriplets(entries.begin(), entries.end());
  return J;
}

// Body compliance J A⁻¹ Jᵀ for 125 contacts (docs/CONTACT.md): arg 1 = 0 the chosen method (the
// solve on the contact dofs' reach, fem/inverse_quadratic_form.h), 1 one dense solve per contact
// with the same factor.
void BM_ContactCompliance(benchmark::State& bench) {
  const Fixture& f = GetFixture(static_cast<int>(bench.range(0)));
  fem::TimeStepper stepper(f.body.model, f.scene.body->options, f.scene.dt_s,
                           f.body.external_force_N);
  Eigen::VectorXd dv;
  stepper.CalcFreeVelocityChange(f.state, &dv);  // assembles A and holds its factor
  const Eigen::SparseMatrix<double> J = MakeTopContactRows(f.body.model, 125, 1);
  const Eigen::MatrixXd Jt = Eigen::MatrixXd(J.transpose());
  fem::CholmodFactor* factor = const_cast<fem::LinearSolver*>(stepper.solver())->factor();
  Eigen::MatrixXd W(125, 125);
  Eigen::VectorXd x;
  for (auto _ : bench) {
    if (bench.range(1) == 0) {
      W = stepper.CalcCompliance(J);
    } else {
      for (int i = 0; i < 125; ++i) {
        factor->Solve(Jt.col(i), &x);
        W.col(i) = J * x;
      }
    }
    benchmark::DoNotOptimize(W.data());
  }
  SetCounters(bench, f);
}

// The warped compliance (fem/warped_compliance.h) of a frame whose contact nodes are all held:
// arg 1 contacts on the top face (the small block has 169 top nodes), arg 2 rows a contact (1
// frictionless, 3 with friction), arg 3 nodes a contact (MakeTopContactRows).
void BM_WarpedCompliance(benchmark::State& bench) {
  const Fixture& f = GetFixture(static_cast<int>(bench.range(0)));
  fem::TimeStepper stepper(f.body.model, f.scene.body->options, f.scene.dt_s,
                           f.body.external_force_N);
  Eigen::VectorXd dv;
  stepper.CalcFreeVelocityChange(f.state, &dv);  // the element rotations of the settled block
  fem::WarpedCompliance compliance(f.body.model, stepper);
  const Eigen::SparseMatrix<double> J =
      MakeTopContactRows(f.body.model, static_cast<int>(bench.range(1)),
                         static_cast<int>(bench.range(2)), static_cast<int>(bench.range(3)));
  Eigen::MatrixXd W = compliance.Calc(J, stepper.rotations());  // solves the nodes' columns
  for (auto _ : bench) {
    W = compliance.Calc(J, stepper.rotations());
    benchmark::DoNotOptimize(W.data());
  }
  SetCounters(bench, f);
}

// The system matrix A of the settled block (its lower triangle), as the next step assembles it.
Eigen::SparseMatrix<double> MakeSettledSystemMatrix(const Fixture& f) {
  fem::TimeStepper stepper(f.body.model, f.scene.body->options, f.scene.dt_s,
                           f.body.external_force_N);
  Eigen::VectorXd dv;
  stepper.CalcFreeVelocityChange(f.state, &dv);  // assembles A
  return stepper.system_matrix();
}

// One preconditioner application A⁻¹ r with the factor of the settled block's system matrix:
// arg 1 (bits) = 64 CHOLMOD's double-precision supernodal solve, 32 the float copy, 16 the
// binary16 one.
void BM_FactorSolve(benchmark::State& bench) {
  const Fixture& f = GetFixture(static_cast<int>(bench.range(0)));
  const Eigen::SparseMatrix<double> A = MakeSettledSystemMatrix(f);
  fem::CholmodFactor factor;
  factor.KeepCopy(bench.range(1) == 32   ? fem::FactorPrecision::kSingle
                  : bench.range(1) == 16 ? fem::FactorPrecision::kHalf
                                         : fem::FactorPrecision::kDouble);
  factor.Factorize(A);
  const Eigen::VectorXd r = Eigen::VectorXd::Random(A.rows());
  Eigen::VectorXd z;
  for (auto _ : bench) {
    if (bench.range(1) == 64)
      factor.Solve(r, &z);
    else
      factor.SolveWithCopy(r, &z);
    benchmark::DoNotOptimize(z.data());
  }
  SetCounters(bench, f);
  bench.counters["factor_nonzeros"] = factor.num_factor_nonzeros();
}

// One numeric factorisation of the settled block's system matrix (the ordering and symbolic
// analysis are done once before): what a refactorisation of the lagged preconditioner costs.
void BM_Factorize(benchmark::State& bench) {
  const Fixture& f = GetFixture(static_cast<int>(bench.range(0)));
  const Eigen::SparseMatrix<double> A = MakeSettledSystemMatrix(f);
  fem::CholmodFactor factor;
  factor.Analyze(A);
  for (auto _ : bench) benchmark::DoNotOptimize(factor.Factorize(A));
  SetCounters(bench, f);
  bench.counters["factor_nonzeros"] = factor.num_factor_nonzeros();
  bench.counters["flops"] = factor.factorization_flops();
  bench.counters["flop_rate"] = benchmark::Counter(factor.factorization_flops(),
                                                   benchmark::Counter::kIsIterationInvariantRate);
}

// New contact nodes' columns of A⁻¹ (the warped compliance's, fem/warped_compliance.h): arg 1
// nodes of the top face's centre, 3 columns each; arg 2 (bits) = 64 CHOLMOD's dense multi-column
// solve, 32 the float copy's (its forward sweep only on the nodes' elimination-tree paths); arg 3
// (at) = 0 every row, else the rows of only that many top nodes nearest the centre (the backward
// sweep only on their paths; block_press_large touches ~450, fem/warped_compliance.h).
void BM_SolveColumns(benchmark::State& bench) {
  const Fixture& f = GetFixture(static_cast<int>(bench.range(0)));
  const Eigen::SparseMatrix<double> A = MakeSettledSystemMatrix(f);
  fem::CholmodFactor factor;
  factor.KeepCopy(fem::FactorPrecision::kSingle);
  factor.Factorize(A);
  const std::vector<int> top = TopNodesFromTheCentre(f.body.model);
  const int num_nodes = static_cast<int>(bench.range(1));
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(A.rows(), 3 * num_nodes);
  for (int k = 0; k < num_nodes; ++k)
    for (int d = 0; d < 3; ++d) E(3 * top[k] + d, 3 * k + d) = 1.0;
  std::vector<int> wanted_rows;
  for (int k = 0; k < bench.range(3); ++k)
    for (int d = 0; d < 3; ++d) wanted_rows.push_back(3 * top[k] + d);
  for (auto _ : bench) {
    const Eigen::MatrixXd X = bench.range(2) == 64  ? factor.SolveColumns(E)
                              : wanted_rows.empty() ? factor.SolveColumnsWithCopy(E)
                                                    : factor.SolveColumnsWithCopyAt(E, wanted_rows);
    benchmark::DoNotOptimize(X.data());
  }
  SetCounters(bench, f);
}

BENCHMARK(BM_Rotations)->DenseRange(0, 4)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ForcesAndStiffness)->DenseRange(0, 4)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ImplicitStep)
    ->ArgsProduct({{0, 1, 2, 3, 4}, {0, 1}})
    ->ArgNames({"block", "cholmod"})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FactorSolve)
    ->ArgsProduct({{1, 2}, {64, 32, 16}})
    ->ArgNames({"block", "bits"})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Factorize)->DenseRange(1, 2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SolveColumns)
    ->ArgsProduct({{2}, {2, 8}, {64, 32}, {0}})
    ->ArgsProduct({{2}, {2, 8}, {32}, {150, 450}})
    ->ArgNames({"block", "nodes", "bits", "at"})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WarpedCompliance)
    ->ArgsProduct({{1}, {125}, {1, 3}, {1}})
    ->ArgsProduct({{1}, {200}, {1, 3}, {3}})
    ->ArgsProduct({{2}, {200}, {1, 3}, {1, 3}})
    ->ArgNames({"block", "contacts", "rows", "nodes"})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ContactCompliance)
    ->ArgsProduct({{1, 2, 4}, {0, 1}})
    ->ArgNames({"block", "per_contact"})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace hapsim

BENCHMARK_MAIN();
