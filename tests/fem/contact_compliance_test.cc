// The body's contact compliance J A⁻¹ Jᵀ and extra solves with the step's system matrix, against
// a dense factorisation of the same A (a second method). With CG + lagged Cholesky the compliance
// comes from an older factor: the test bounds that approximation after the body has moved.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <random>
#include <string>

#include "fem/cholmod_factor.h"
#include "fem/lattice_mesher.h"
#include "fem/model.h"
#include "fem/time_stepper.h"
#include "fem/warped_compliance.h"

namespace hapsim::fem {
namespace {

// A 4 × 4 × 2 cm block of E = 50 kPa in `cells` lattice cells, its bottom fixed or not.
Model MakeBlock(const Eigen::Vector3i& cells = {4, 4, 2}, bool fix_bottom = true) {
  const TetMesh mesh = MakeBoxTetMesh({0, 0, 0}, {0.04, 0.04, 0.02}, cells);
  Material material;
  material.youngs_modulus_Pa = 5e4;
  return MakeModel(
      mesh, material,
      fix_bottom ? FindNodesInBox(mesh, {-1, -1, -1}, {1, 1, 1e-9}, 0.0) : std::vector<int>{});
}

// A block of quadratic tets (the mid-edge nodes of MakeBlock's lattice added), bottom fixed.
Model MakeQuadraticBlock(const Eigen::Vector3i& cells) {
  const TetMesh mesh =
      MakeQuadraticMesh(MakeBoxTetMesh({0, 0, 0}, {0.04, 0.04, 0.02}, cells));
  Material material;
  material.youngs_modulus_Pa = 5e4;
  return MakeModel(mesh, material, FindNodesInBox(mesh, {-1, -1, -1}, {1, 1, 1e-9}, 0.0));
}

// The implicit step's matrix at rest, A = M + (Δt β + Δt²) K, as a CG step assembles it.
Eigen::SparseMatrix<double> RestSystemMatrix(const Model& model) {
  TimeStepper stepper(model, FemOptions{}, 1.0 / 60.0, Eigen::VectorXd::Zero(model.num_dofs()));
  Eigen::VectorXd dv;
  stepper.CalcFreeVelocityChange(MakeRestState(model), &dv);
  return stepper.system_matrix();
}

// Rows like contact rows: a unit direction spread over three free nodes with barycentric weights.
Eigen::SparseMatrix<double> MakeContactRows(const Model& model, int rows, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> node(0, model.num_nodes() - 1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Eigen::Triplet<double>> entries;
  for (int r = 0; r < rows; ++r) {
    const Eigen::Vector3d n = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized();
    for (int k = 0; k < 3; ++k) {
      const int nd = node(rng);
      for (int a = 0; a < 3; ++a)
        if (!model.dof_is_fixed[3 * nd + a]) entries.emplace_back(r, 3 * nd + a, n[a] / 3.0);
    }
  }
  Eigen::SparseMatrix<double> J(rows, model.num_dofs());
  J.setFromTriplets(entries.begin(), entries.end());
  return J;
}

TEST(ContactCompliance, CholmodMatchesDenseInverse) {
  const Model model = MakeBlock();
  FemOptions options;
  options.solver.kind = SolverKind::kCholmod;
  TimeStepper stepper(model, options, 1.0 / 60.0, CalcGravityForce(model, {0, 0, -9.81}));
  State state = MakeRestState(model);
  for (int k = 0; k < 5; ++k) stepper.Step(&state);
  Eigen::VectorXd dv;
  stepper.CalcFreeVelocityChange(state, &dv);
  const Eigen::SparseMatrix<double> J = MakeContactRows(model, 12, 3);
  const Eigen::MatrixXd W = stepper.CalcCompliance(J);
  const Eigen::MatrixXd A = Eigen::MatrixXd(
      Eigen::SparseMatrix<double>(stepper.system_matrix().selfadjointView<Eigen::Lower>()));
  const Eigen::MatrixXd Jd = Eigen::MatrixXd(J);
  const Eigen::MatrixXd expected = Jd * A.ldlt().solve(Jd.transpose());
  EXPECT_LT((W - expected).norm(), 1e-10 * expected.norm());

  const Eigen::VectorXd rhs = Jd.transpose() * Eigen::VectorXd::Ones(12);
  Eigen::VectorXd x;
  const int factorizations = stepper.solver()->num_factorizations();
  stepper.SolveWithSystemMatrix(rhs, 0.0, &x);
  EXPECT_LT((x - A.ldlt().solve(rhs)).norm(), 1e-10 * x.norm());
  // With the factor the free step made of this A: no second factorisation in the frame.
  EXPECT_EQ(stepper.solver()->num_factorizations(), factorizations);
}

// The reach solve (fem/inverse_quadratic_form.h) against a dense factorisation of the same A: on
// linear and quadratic tets; rows that share dofs, touch a fixed dof (A's identity there), or
// reach the elimination tree's root from a few nodes only; then, with the same factor object, a
// matrix of another pattern (the structure read again).
TEST(ContactCompliance, ReachSolveMatchesDenseInverse) {
  CholmodFactor factor;
  const auto expect_dense = [&factor](const Model& model, const Eigen::SparseMatrix<double>& J,
                                      const std::string& what) {
    const Eigen::SparseMatrix<double> A = RestSystemMatrix(model);
    ASSERT_TRUE(factor.Factorize(A)) << what;
    const Eigen::MatrixXd A_dense =
        Eigen::MatrixXd(Eigen::SparseMatrix<double>(A.selfadjointView<Eigen::Lower>()));
    const Eigen::MatrixXd Jd = Eigen::MatrixXd(J);
    const Eigen::MatrixXd expected = Jd * A_dense.ldlt().solve(Jd.transpose());
    const Eigen::MatrixXd W = factor.CalcInverseQuadraticForm(J);
    EXPECT_LT((W - expected).norm(), 1e-10 * expected.norm()) << what;
  };
  const Model linear = MakeBlock({4, 4, 2});
  expect_dense(linear, MakeContactRows(linear, 30, 5), "linear, 30 rows");
  const Model quadratic = MakeQuadraticBlock({3, 3, 2});
  ASSERT_TRUE(quadratic.is_quadratic());
  expect_dense(quadratic, MakeContactRows(quadratic, 40, 6), "quadratic, 40 rows");
  // Two rows on one node's dofs, and one on a fixed node (its bottom corner) and a free one.
  const int fixed_node = 0, free_node = quadratic.num_nodes() - 1;
  ASSERT_TRUE(quadratic.dof_is_fixed[3 * fixed_node]);
  ASSERT_FALSE(quadratic.dof_is_fixed[3 * free_node]);
  Eigen::SparseMatrix<double> J(3, quadratic.num_dofs());
  J.insert(0, 3 * free_node + 2) = 1.0;
  J.insert(1, 3 * free_node + 2) = -0.5, J.insert(1, 3 * free_node) = 0.5;
  J.insert(2, 3 * fixed_node + 1) = 1.0, J.insert(2, 3 * free_node + 1) = 0.25;
  J.makeCompressed();
  expect_dense(quadratic, J, "quadratic, shared and fixed dofs");
  // No entry at all: zero, as no dof moves.
  EXPECT_EQ(factor.CalcInverseQuadraticForm(Eigen::SparseMatrix<double>(2, quadratic.num_dofs()))
                .norm(),
            0.0);
}

TEST(ContactCompliance, LaggedFactorApproximatesTheCurrentCompliance) {
  const Model model = MakeBlock();
  FemOptions options;  // CG + lagged Cholesky
  TimeStepper stepper(model, options, 1.0 / 60.0, CalcGravityForce(model, {0, 0, -9.81}));
  State state = MakeRestState(model);
  // Bend the block a visible amount so the warped stiffness has moved away from the rest one.
  for (int n = 0; n < model.num_nodes(); ++n) {
    const double z_m = model.mesh.rest_positions_m(2, n);
    state.x_m[3 * n] += 0.05 * z_m * z_m / 0.02;  // top face rotated by atan(0.1) ≈ 6°
  }
  Eigen::VectorXd dv;
  stepper.CalcFreeVelocityChange(MakeRestState(model), &dv);  // factor at rest
  stepper.CalcFreeVelocityChange(state, &dv);                 // A at the bent state
  const Eigen::SparseMatrix<double> J = MakeContactRows(model, 12, 4);
  const Eigen::MatrixXd A = Eigen::MatrixXd(
      Eigen::SparseMatrix<double>(stepper.system_matrix().selfadjointView<Eigen::Lower>()));
  const Eigen::MatrixXd Jd = Eigen::MatrixXd(J);
  const Eigen::MatrixXd exact = Jd * A.ldlt().solve(Jd.transpose());
  const double relative_error = (stepper.CalcCompliance(J) - exact).norm() / exact.norm();
  // Non-zero (the factor is stale) but small: element rotations of up to 6° change K by a few %.
  EXPECT_GT(relative_error, 1e-8);
  EXPECT_LT(relative_error, 0.05);
  // An exact solve with the current A still goes through CG.
  const Eigen::VectorXd rhs = Jd.transpose() * Eigen::VectorXd::Ones(12);
  Eigen::VectorXd x;
  stepper.SolveWithSystemMatrix(rhs, 0.0, &x);
  EXPECT_LT((x - A.ldlt().solve(rhs)).norm(), 1e-5 * x.norm());
}

// Dense J A⁻¹ Jᵀ with the stepper's system matrix at `state` (a second method).
Eigen::MatrixXd CalcDenseCompliance(TimeStepper* stepper, const State& state,
                                    const Eigen::SparseMatrix<double>& J) {
  Eigen::VectorXd dv;
  stepper->CalcFreeVelocityChange(state, &dv);
  const Eigen::MatrixXd A = Eigen::MatrixXd(
      Eigen::SparseMatrix<double>(stepper->system_matrix().selfadjointView<Eigen::Lower>()));
  const Eigen::MatrixXd Jd = Eigen::MatrixXd(J);
  return Jd * A.ldlt().solve(Jd.transpose());
}

// Rows as the friction law makes them: per contact a normal and two tangents with the same
// weights at the same 1–3 nodes (WarpedCompliance rotates such a group's entries at once),
// a normal-only contact between them, a row that touches no node (a contact with a rigid
// object), and two contacts in a row at one node (a group holds at most three rows).
Eigen::SparseMatrix<double> MakeFrictionRows(const Model& model, int contacts, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> node(0, model.num_nodes() - 1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Eigen::Triplet<double>> entries;
  int row = 0;
  std::vector<int> nodes;
  for (int c = 0; c < contacts; ++c) {
    const Eigen::Vector3d n = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized();
    const Eigen::Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
    const bool same_nodes = c % 5 == 4;  // as the contact before
    if (!same_nodes) {
      nodes.assign(1 + c % 3, 0);
      for (int& nd : nodes) nd = node(rng);
      std::sort(nodes.begin(), nodes.end());
      nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    }
    const int num_rows = c % 7 == 3 ? 1 : 3;
    for (int r = 0; r < num_rows; ++r, ++row) {
      const Eigen::Vector3d d = r == 0 ? n : r == 1 ? t1 : t2;
      for (int nd : nodes)
        for (int a = 0; a < 3; ++a)
          entries.emplace_back(row, 3 * nd + a, d[a] / static_cast<double>(nodes.size()));
    }
    if (c == contacts / 2) ++row;  // a row on a rigid object: no body entries
  }
  Eigen::SparseMatrix<double> J(row, model.num_dofs());
  J.setFromTriplets(entries.begin(), entries.end());
  return J;
}

// At rest, and for a free body turned rigidly (A = R A₀ Rᵀ exactly, R the same at every node),
// the warped compliance is exact: to float accuracy, since the columns of A₀⁻¹ come from the float
// copy of its factor (measured 1.8e-7 relative; CHOLMOD's double solve gave < 1e-10).
TEST(WarpedCompliance, ExactAtRestAndUnderRigidRotation) {
  const Model model = MakeBlock({4, 4, 2}, /*fix_bottom=*/false);
  TimeStepper stepper(model, FemOptions{}, 1.0 / 60.0, Eigen::VectorXd::Zero(model.num_dofs()));
  WarpedCompliance warped(model, stepper);
  const Eigen::SparseMatrix<double> J = MakeContactRows(model, 12, 5);
  State state = MakeRestState(model);
  const Eigen::MatrixXd at_rest = CalcDenseCompliance(&stepper, state, J);
  constexpr double kFloatColumns = 1e-6;
  EXPECT_LT((warped.Calc(J, stepper.rotations()) - at_rest).norm(), kFloatColumns * at_rest.norm());

  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  for (int n = 0; n < model.num_nodes(); ++n)
    state.x_m.segment<3>(3 * n) = R * model.mesh.rest_positions_m.col(n);
  const Eigen::MatrixXd turned = CalcDenseCompliance(&stepper, state, J);
  EXPECT_GT((turned - at_rest).norm(), 0.1 * at_rest.norm());  // rotation matters
  EXPECT_LT((warped.Calc(J, stepper.rotations()) - turned).norm(), kFloatColumns * turned.norm());
  EXPECT_EQ(warped.num_cached_nodes(), [&] {  // each node solved once, on first use
    std::vector<int> nodes;
    for (int k = 0; k < J.outerSize(); ++k)
      for (Eigen::SparseMatrix<double>::InnerIterator it(J, k); it; ++it)
        nodes.push_back(it.col() / 3);
    std::sort(nodes.begin(), nodes.end());
    return static_cast<int>(std::unique(nodes.begin(), nodes.end()) - nodes.begin());
  }());
}

// Friction rows, computed a contact's rows at a time, against the exact compliance at rest and
// rigidly turned (no node fixed: the warping is then exact but for the float columns).
TEST(WarpedCompliance, ExactForFrictionRowsAtRestAndUnderRigidRotation) {
  const Model model = MakeBlock({4, 4, 2}, /*fix_bottom=*/false);
  TimeStepper stepper(model, FemOptions{}, 1.0 / 60.0, Eigen::VectorXd::Zero(model.num_dofs()));
  WarpedCompliance warped(model, stepper);
  const Eigen::SparseMatrix<double> J = MakeFrictionRows(model, 20, 8);
  ASSERT_GT(J.rows(), 50);
  State state = MakeRestState(model);
  constexpr double kFloatColumns = 1e-6;
  const Eigen::MatrixXd at_rest = CalcDenseCompliance(&stepper, state, J);
  EXPECT_LT((warped.Calc(J, stepper.rotations()) - at_rest).norm(), kFloatColumns * at_rest.norm());
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(-1.1, Eigen::Vector3d(3, -1, 2).normalized()).toRotationMatrix();
  for (int n = 0; n < model.num_nodes(); ++n)
    state.x_m.segment<3>(3 * n) = R * model.mesh.rest_positions_m.col(n);
  const Eigen::MatrixXd turned = CalcDenseCompliance(&stepper, state, J);
  const Eigen::MatrixXd W = warped.Calc(J, stepper.rotations());
  EXPECT_LT((W - turned).norm(), kFloatColumns * turned.norm());
  EXPECT_EQ(W, W.transpose());
}

// The rows one compliance rotated serve another of the same body with another A₀ (the visual
// frame's and the haptic step's, VisualFrame::SetBodyCompliance): its W is its own exact
// compliance, rigidly turned, and bit for bit what rotating the rows itself gives.
TEST(WarpedCompliance, RowsRotatedByOneServeAnotherOfTheSameBody) {
  const Model model = MakeBlock({4, 4, 2}, /*fix_bottom=*/false);
  const Eigen::VectorXd no_force = Eigen::VectorXd::Zero(model.num_dofs());
  TimeStepper visual_stepper(model, FemOptions{}, 1.0 / 30.0, no_force);
  TimeStepper haptic_stepper(model, FemOptions{}, 1.0 / 1000.0, no_force);
  WarpedCompliance visual(model, visual_stepper), haptic(model, haptic_stepper);
  const Eigen::SparseMatrix<double> J = MakeFrictionRows(model, 20, 3);
  State state = MakeRestState(model);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.9, Eigen::Vector3d(-2, 1, 1).normalized()).toRotationMatrix();
  for (int n = 0; n < model.num_nodes(); ++n)
    state.x_m.segment<3>(3 * n) = R * model.mesh.rest_positions_m.col(n);
  const Eigen::MatrixXd exact = CalcDenseCompliance(&haptic_stepper, state, J);
  Eigen::VectorXd dv;
  visual_stepper.CalcFreeVelocityChange(state, &dv);
  haptic.SetRows(visual.RotateRows(J, visual_stepper.rotations()));
  const Eigen::MatrixXd shared = haptic.CalcAll();
  EXPECT_LT((shared - exact).norm(), 1e-6 * exact.norm());
  EXPECT_GT((CalcDenseCompliance(&visual_stepper, state, J) - exact).norm(), 0.1 * exact.norm());
  EXPECT_EQ(shared, haptic.Calc(J, haptic_stepper.rotations()));
}

// Chosen columns and the diagonal against the whole W of the same rows, rigidly turned (rotated
// entries), with C₀ read in place and then gathered (a frame on few of the held nodes): the
// columns asked for, in two calls (the second copying its rows at the first's columns), agree
// with it to round-off, the diagonal bit for bit; the columns not asked for are left untouched.
TEST(WarpedCompliance, ColumnsAndDiagonalAgreeWithTheWholeMatrix) {
  const Model model = MakeBlock({8, 8, 4}, /*fix_bottom=*/false);
  TimeStepper stepper(model, FemOptions{}, 1.0 / 60.0, Eigen::VectorXd::Zero(model.num_dofs()));
  WarpedCompliance warped(model, stepper);
  State state = MakeRestState(model);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, -2, 1).normalized()).toRotationMatrix();
  for (int n = 0; n < model.num_nodes(); ++n)
    state.x_m.segment<3>(3 * n) = R * model.mesh.rest_positions_m.col(n);
  Eigen::VectorXd dv;
  stepper.CalcFreeVelocityChange(state, &dv);  // the turned block's element rotations
  // Many rows first (the held nodes), then few: the second frame's C₀ is gathered.
  for (const Eigen::SparseMatrix<double>& J :
       {MakeFrictionRows(model, 60, 3), MakeFrictionRows(model, 6, 4)}) {
    const Eigen::MatrixXd whole = warped.Calc(J, stepper.rotations());
    warped.SetRows(J, stepper.rotations());
    const Eigen::Index n = J.rows();
    std::vector<Eigen::Index> columns;
    for (Eigen::Index c = n - 1; c >= 0; c -= 3) columns.push_back(c);  // any order
    Eigen::MatrixXd W = Eigen::MatrixXd::Constant(n, n, -7.0);
    std::vector<std::uint8_t> formed(static_cast<size_t>(n), 0);
    const size_t half = columns.size() / 2;  // in two calls: the second's rows at the first's
    warped.CalcColumns(std::vector<Eigen::Index>(columns.begin(), columns.begin() + half), &W,
                       &formed);  // columns are copied from them
    warped.CalcColumns(std::vector<Eigen::Index>(columns.begin() + half, columns.end()), &W,
                       &formed);
    for (Eigen::Index c = 0; c < n; ++c)
      EXPECT_EQ(formed[static_cast<size_t>(c)] != 0,
                std::find(columns.begin(), columns.end(), c) != columns.end());
    const double scale = whole.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    for (Eigen::Index c = 0; c < n; ++c) {
      const bool asked = std::find(columns.begin(), columns.end(), c) != columns.end();
      for (Eigen::Index r = 0; r < n; ++r) {
        if (!asked)
          EXPECT_EQ(W(r, c), -7.0);
        else
          EXPECT_NEAR(W(r, c), whole(r, c), 1e-12 * scale) << r << ", " << c;
      }
    }
    const Eigen::VectorXd diagonal = warped.CalcDiagonal();
    for (Eigen::Index r = 0; r < n; ++r) EXPECT_EQ(diagonal[r], whole(r, r)) << r;  // bit for bit
  }
}

// Nodes met in a later frame: their columns of A₀⁻¹ are solved only at the rows of the nodes held
// by then (SinglePrecisionFactor::SolveColumnsAt), so W must read each pair from the later of the
// two columns. At rest the warped compliance is exact (to the float columns), frame after frame,
// and stays so as the held blocks outgrow their first capacity (64 nodes) and are copied. A last
// frame back on the first rows alone touches fewer than half the held nodes, so its C₀ is gathered
// from the held blocks rather than read in place (WarpedCompliance::Calc): exact all the same.
TEST(WarpedCompliance, ExactWhenContactsMeetNewNodesFrameByFrame) {
  const Model model = MakeBlock({8, 8, 4}, /*fix_bottom=*/false);
  TimeStepper stepper(model, FemOptions{}, 1.0 / 60.0, Eigen::VectorXd::Zero(model.num_dofs()));
  WarpedCompliance warped(model, stepper);
  const State rest = MakeRestState(model);
  constexpr double kFloatColumns = 1e-6;
  int held = 0;
  for (unsigned frame = 0; frame < 3; ++frame) {
    // Rows of every frame so far (the nodes held), and 30 new ones.
    constexpr int kRowsPerFrame = 30;
    std::vector<Eigen::Triplet<double>> entries;
    for (unsigned f = 0; f <= frame; ++f) {
      const Eigen::SparseMatrix<double> rows = MakeContactRows(model, kRowsPerFrame, 20 + f);
      for (int k = 0; k < rows.outerSize(); ++k)
        for (Eigen::SparseMatrix<double>::InnerIterator it(rows, k); it; ++it)
          entries.emplace_back(kRowsPerFrame * f + it.row(), it.col(), it.value());
    }
    Eigen::SparseMatrix<double> J(kRowsPerFrame * (frame + 1), model.num_dofs());
    J.setFromTriplets(entries.begin(), entries.end());
    const Eigen::MatrixXd exact = CalcDenseCompliance(&stepper, rest, J);
    const Eigen::MatrixXd W = warped.Calc(J, stepper.rotations());
    EXPECT_LT((W - exact).norm(), kFloatColumns * exact.norm()) << "frame " << frame;
    EXPECT_GT(warped.num_cached_nodes(), held) << "frame " << frame << " met no new node";
    held = warped.num_cached_nodes();
  }
  EXPECT_GT(held, 128) << "the held blocks never grew twice";

  const Eigen::SparseMatrix<double> first = MakeContactRows(model, 30, 20);
  const Eigen::MatrixXd exact = CalcDenseCompliance(&stepper, rest, first);
  EXPECT_LT((warped.Calc(first, stepper.rotations()) - exact).norm(), kFloatColumns * exact.norm());
  EXPECT_EQ(warped.num_cached_nodes(), held);
}

// On the bent block of the test above (rotations varying up to 6° across it, bottom fixed) the
// warping is an approximation: bounded here, and measured on block_press in docs/CONTACT.md.
TEST(WarpedCompliance, ApproximatesTheComplianceOfABentBlock) {
  const Model model = MakeBlock();
  TimeStepper stepper(model, FemOptions{}, 1.0 / 60.0, CalcGravityForce(model, {0, 0, -9.81}));
  WarpedCompliance warped(model, stepper);
  State state = MakeRestState(model);
  for (int n = 0; n < model.num_nodes(); ++n) {
    const double z_m = model.mesh.rest_positions_m(2, n);
    state.x_m[3 * n] += 0.05 * z_m * z_m / 0.02;
  }
  const Eigen::SparseMatrix<double> J = MakeContactRows(model, 12, 4);
  const Eigen::MatrixXd exact = CalcDenseCompliance(&stepper, state, J);
  const Eigen::MatrixXd rest = CalcDenseCompliance(&stepper, MakeRestState(model), J);
  CalcDenseCompliance(&stepper, state, J);  // the stepper's rotations at the bent state
  const double warped_error = (warped.Calc(J, stepper.rotations()) - exact).norm() / exact.norm();
  const double rest_error = (rest - exact).norm() / exact.norm();
  RecordProperty("warped_relative_error", std::to_string(warped_error));
  RecordProperty("unwarped_relative_error", std::to_string(rest_error));
  EXPECT_LT(warped_error, 0.05);
  EXPECT_LT(warped_error, rest_error);  // warping does better than the rest compliance alone
}

}  // namespace
}  // namespace hapsim::fem
