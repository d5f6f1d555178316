// FrameCompliance (contact/frame_compliance.h): W formed by columns against the same W formed
// whole, the body's warped compliance plus a dynamic object's rigid-body part, and above it the
// tool's part.
#include "contact/frame_compliance.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <random>
#include <stdexcept>
#include <vector>

#include "fem/lattice_mesher.h"
#include "fem/model.h"
#include "fem/time_stepper.h"

namespace hapsim::contact {
namespace {

// Rows as contacts make them: a unit direction on 1–3 nodes of a 4 × 4 × 2 cm block (bottom
// fixed), and random tool and object rows.
struct Rows {
  ContactJacobian tool;    // J_v, J_ω, J_u
  ContactJacobian object;  // a dynamic object's J_v,o, J_ω,o (zero on the rows that miss it)
};

Rows MakeRows(const fem::Model& model, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> node(0, model.num_nodes() - 1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Rows rows;
  rows.tool.rows_per_contact = rows.object.rows_per_contact = 1;
  rows.tool.J_v.resize(n, 3);
  rows.tool.J_w.resize(n, 3);
  rows.object.J_v = Eigen::MatrixXd::Zero(n, 3);
  rows.object.J_w = Eigen::MatrixXd::Zero(n, 3);
  std::vector<Eigen::Triplet<double>> entries;
  for (int r = 0; r < n; ++r) {
    const Eigen::Vector3d d = Eigen::Vector3d(unit(rng), unit(rng), -2.0).normalized();
    const Eigen::Vector3d arm(0.01 * unit(rng), 0.01 * unit(rng), 0.02);
    rows.tool.J_v.row(r) = -d.transpose();
    rows.tool.J_w.row(r) = -arm.cross(d).transpose();
    const int num_nodes = 1 + r % 3;
    for (int k = 0; k < num_nodes; ++k) {
      const int nd = node(rng);
      for (int a = 0; a < 3; ++a)
        if (!model.dof_is_fixed[3 * nd + a]) entries.emplace_back(r, 3 * nd + a, d[a] / num_nodes);
    }
    if (r % 4 == 1) {  // a row that also touches the object
      rows.object.J_v.row(r) = d.transpose();
      rows.object.J_w.row(r) = Eigen::Vector3d(0.003, -0.002, 0.001).cross(d).transpose();
    }
  }
  rows.tool.J_u.resize(n, model.num_dofs());
  rows.tool.J_u.setFromTriplets(entries.begin(), entries.end());
  return rows;
}

// The tool's step system: a coupling torque makes A_L, and so its part of W, unsymmetric.
ToolStepSystem MakeToolSystem() {
  ToolStepSystem tool;
  tool.dt_s = 0.03;
  tool.A_v =
      0.05 * Eigen::Matrix3d::Identity() + 0.03 * 0.03 * 1000.0 * Eigen::Matrix3d::Identity();
  tool.M_inv_W = Eigen::Vector3d(5e4, 4e4, 6e4).asDiagonal();
  Eigen::Matrix3d C;
  C << 1e-3, 2e-4, 0, -1e-4, 1e-3, 0, 0, 3e-4, 1e-3;
  tool.A_L = Eigen::Matrix3d::Identity() + 1e-3 * C * tool.M_inv_W;
  return tool;
}

ToolStepSystem MakeObjectSystem() {  // a 15 g body under gravity alone
  ToolStepSystem object;
  object.dt_s = 0.03;
  object.A_v = 0.015 * Eigen::Matrix3d::Identity();
  object.M_inv_W = Eigen::Vector3d(3e5, 3e5, 2e5).asDiagonal();
  return object;
}

// Columns formed in three batches, the second naming columns of the first again, with the
// object's part added to the body's columns (whose rows at earlier columns are copied from them,
// not computed: the part must not be counted twice there) and the tool's to the frame's. Every
// formed column equals the whole W's to round-off, the diagonals agree, unformed columns are
// counted out, and WriteDiagonalOfUnformedColumns puts each row's own entry in place.
TEST(FrameCompliance, ColumnsFormedInBatchesEqualTheWholeMatrix) {
  const fem::TetMesh mesh = fem::MakeBoxTetMesh({0, 0, 0}, {0.04, 0.04, 0.02}, {4, 4, 2});
  fem::Material material;
  material.youngs_modulus_Pa = 5e4;
  const fem::Model model =
      fem::MakeModel(mesh, material, fem::FindNodesInBox(mesh, {-1, -1, -1}, {1, 1, 1e-9}, 0.0));
  fem::TimeStepper stepper(model, fem::FemOptions{}, 0.03, Eigen::VectorXd::Zero(model.num_dofs()));
  Eigen::VectorXd dv;
  stepper.CalcFreeVelocityChange(fem::MakeRestState(model), &dv);  // the element rotations
  fem::WarpedCompliance warped(model, stepper);
  const int n = 30;
  const Rows rows = MakeRows(model, n, 11);
  const ToolStepSystem tool = MakeToolSystem(), object = MakeObjectSystem();

  Eigen::MatrixXd body_whole = warped.Calc(rows.tool.J_u, stepper.rotations());
  AddToolDelassus(rows.object, object, &body_whole);
  Eigen::MatrixXd frame_whole = body_whole;
  AddToolDelassus(rows.tool, tool, &frame_whole);
  ASSERT_GT((frame_whole - frame_whole.transpose()).norm(), 1e-6 * frame_whole.norm());

  warped.SetRows(rows.tool.J_u, stepper.rotations());
  FrameCompliance body, frame;
  body.SetByColumns(&warped, n);
  body.AddRigidPart(rows.object, object);
  frame.SetAbove(&body);
  frame.AddRigidPart(rows.tool, tool);
  const double scale = frame_whole.cwiseAbs().maxCoeff();
  EXPECT_LT((body.diagonal() - body_whole.diagonal()).cwiseAbs().maxCoeff(), 1e-12 * scale);
  EXPECT_LT((frame.diagonal() - frame_whole.diagonal()).cwiseAbs().maxCoeff(), 1e-12 * scale);

  frame.Fill({3, 1, 7, 1});
  body.Fill({20, 3, 5, 9});  // the model's own reads, beside the solve's
  frame.Fill({9, 0, 29, 7});
  const std::vector<Eigen::Index> in_frame = {0, 1, 3, 7, 9, 29};
  const std::vector<Eigen::Index> in_body = {0, 1, 3, 5, 7, 9, 20, 29};
  EXPECT_EQ(frame.num_formed(), static_cast<Eigen::Index>(in_frame.size()));
  EXPECT_EQ(body.num_formed(), static_cast<Eigen::Index>(in_body.size()));
  for (Eigen::Index c = 0; c < n; ++c) {
    const bool framed = std::count(in_frame.begin(), in_frame.end(), c) != 0;
    const bool bodied = std::count(in_body.begin(), in_body.end(), c) != 0;
    EXPECT_EQ(frame.has_column(c), framed) << c;
    EXPECT_EQ(body.has_column(c), bodied) << c;
    if (framed) {
      EXPECT_LT((frame.W().col(c) - frame_whole.col(c)).cwiseAbs().maxCoeff(), 1e-12 * scale) << c;
    }
    if (bodied) {
      EXPECT_LT((body.W().col(c) - body_whole.col(c)).cwiseAbs().maxCoeff(), 1e-12 * scale) << c;
    }
  }
  // The tool's part is unsymmetric: the body's columns, copied by symmetry, refuse it.
  FrameCompliance refuses;
  refuses.SetByColumns(&warped, n);
  EXPECT_THROW(refuses.AddRigidPart(rows.tool, tool), std::invalid_argument);
  body.WriteDiagonalOfUnformedColumns();
  for (Eigen::Index c = 0; c < n; ++c)
    EXPECT_NEAR(body.W()(c, c), body_whole(c, c), 1e-12 * scale) << c;
}

// Given whole, W is held as given, its parts added at once; Fill has nothing to do.
TEST(FrameCompliance, WholeHoldsTheMatrixWithItsParts) {
  const Eigen::MatrixXd W_body = Eigen::MatrixXd::Identity(4, 4) * 2.0;
  ContactJacobian J;
  J.rows_per_contact = 1;
  J.J_v = Eigen::MatrixXd::Random(4, 3);
  J.J_w = Eigen::MatrixXd::Random(4, 3);
  const ToolStepSystem tool = MakeToolSystem();
  FrameCompliance body, frame;
  body.SetWhole(W_body);
  frame.SetAbove(&body);
  frame.AddRigidPart(J, tool);
  frame.Fill({2});
  Eigen::MatrixXd expected = W_body;
  AddToolDelassus(J, tool, &expected);
  EXPECT_TRUE(frame.is_whole());
  EXPECT_EQ(frame.num_formed(), 4);
  EXPECT_LT((frame.W() - expected).norm(), 1e-14 * expected.norm());
  EXPECT_LT((frame.diagonal() - expected.diagonal()).norm(), 1e-14 * expected.norm());
}

}  // namespace
}  // namespace hapsim::contact
