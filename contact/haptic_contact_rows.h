#pragma once
// The rows the visual frame hands over for the `lcp` mode (DESIGN.md §4: "with unilateral
// contacts the haptic process can instead receive the per-contact rows and solve the small LCP
// at 1 kHz"): per normal contact row, frozen at the frame. HapticLcpSolver
// (haptic_lcp_solver.h) solves the LCP on them at every haptic step.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "contact/contact_jacobian.h"
#include "core/tool_integrator.h"

namespace hapsim::contact {

// What the visual frame hands to the haptic step for the lcp mode: per contact row (a normal row
// per contact, or with friction three), frozen at the frame.
struct ContactRows {
  Eigen::MatrixX3d J_v;      // (n x 3) −n_iᵀ, world
  Eigen::MatrixX3d J_w;      // (n x 3) −(r_i × n_i)ᵀ, world, m (lever from the tool's COM)
  Eigen::MatrixXd W_body;    // (n x n) J_u A_u⁻¹ J_uᵀ at the visual step, 1/kg; symmetric
  Eigen::VectorXd body_rhs;  // (n) b − J_u u̇: target minus the body's normal velocity, m/s
  // (n, or empty) the visual frame's impulse per row, N. Its rows with λ > 0, the frame's active
  // set, are the solver's first guess when the rows change: far closer than "every row that asks
  // for a push", which on block_press holds twice the ~70 active rows and cost 1.1 ms to shrink.
  Eigen::VectorXd lambda_frame_N;
  // (n each, or all three empty) What the hybrid mode needs to follow a row the frame did not find
  // active between frames (device/haptic_step.h), read on normal rows (gap and gap target are 0 on
  // tangential ones, the surface velocity is the tangential one there):
  //   gap_m                φ_i, the row's gap at the tool pose the rows are linearised at, m
  //   gap_target_m_s       the part of body_rhs_i that closes that gap over the visual frame,
  //                        −φ_i/Δt_visual (−β φ_i/Δt_visual when penetrating), m/s
  //   surface_velocity_m_s how fast the surface's own motion opens the gap, frozen for the frame:
  //                        the body's normal velocity after the frame, J_u,i u̇, plus a moving rigid
  //                        object's, m/s (dφ_i/dt = J_v,i v + J_ω,i ω + this)
  Eigen::VectorXd gap_m;
  Eigen::VectorXd gap_target_m_s;
  Eigen::VectorXd surface_velocity_m_s;
  // Friction (issue 13): with rows_per_contact 3 the rows come in threes per contact (normal,
  // t1, t2, as CalcContactJacobian orders them) and friction_coefficient holds one μ ≥ 0 per
  // contact; HapticFrictionSolver solves them. With 1 (normal rows only) it is empty.
  int rows_per_contact = 1;
  Eigen::VectorXd friction_coefficient;
  // The last num_uncoupled_rows rows, whole contacts, couple through the body only within their
  // own contact: W_body is zero between one of them and any row of another contact, and the
  // solvers do not read those entries (they hold zeros all the same, for dense readers). The
  // visual frame sends the candidate contacts the tool is not expected to reach within the frame
  // this way (issue 13 item 5): every contact travels, but its coupling costs O(n) instead of
  // O(n²) on the wire and in each haptic step. 0: every row may couple.
  int num_uncoupled_rows = 0;
  // The first num_bilateral_rows rows (coupled ones; normal rows only) are a grasp's
  // (contact/tissue_grasp.h): bilateral, held as equalities in every mode, their λ of either
  // sign (lambda_frame_N too), never released. 0: every row is a unilateral contact.
  int num_bilateral_rows = 0;
  // Identity for the solvers' caches. 0 (the default) promises nothing: a solver compares the
  // rows it is given with its copy bitwise, O(n²) (~65 µs at 600 rows, about half of a
  // one-sweep friction step there). Rows stamped by StampNewContactRows promise that rows with
  // equal stamps are equal, so a solver compares the stamp alone; the two producers that feed the
  // haptic loop (the visual frame's export and the LCM decode) stamp what they fill, and rows
  // changed in place must be stamped again.
  std::uint64_t stamp = 0;
  int num_rows() const { return static_cast<int>(J_v.rows()); }
  int num_coupled_rows() const { return num_rows() - num_uncoupled_rows; }
};

// The first row of the W_body block that `row` lies in, for rows whose first `num_coupled` couple
// and whose others come in uncoupled contacts of `per` rows (ContactRows::num_uncoupled_rows):
// 0 for a coupled row, else the first row of its contact.
inline int FirstRowOfBlock(int row, int num_coupled, int per) {
  return row < num_coupled ? 0 : row - (row - num_coupled) % per;
}

// Gives `rows` a stamp no other rows in this process have had (an atomic counter from 1).
void StampNewContactRows(ContactRows* rows);

// A haptic solver's copy of the last rows it was handed (HapticLcpSolver, HapticFrictionSolver:
// both keep per-row work across the steps of a frame, so they must know when the rows change).
// Preallocated for max_rows; allocates nothing after.
struct ContactRowCache {
  explicit ContactRowCache(int max_rows);

  // Whether `rows` are the cached ones: by stamp when they carry one (ContactRows::stamp), else
  // bitwise (memcmp, ~4× faster than Eigen's ==). Precondition: HasConsistentShape(rows).
  bool Holds(const ContactRows& rows) const;
  // Copies `rows` (at most max_rows) and checks them once: every entry finite, W_body symmetric
  // to 1e-9 of its largest entry. False, with nothing cached, if they fail.
  bool Take(const ContactRows& rows);

  // W_body(i, j) for i ≥ j: the cached lower triangle where rows couple, 0 between an uncoupled
  // contact and any other (ContactRows::num_uncoupled_rows).
  double BodyLower(int i, int j) const {
    return FirstRowOfBlock(i, coupled, per) <= j ? W(i, j) : 0.0;
  }
  // y = W_body x over the n rows (x, y: n entries), reading only what may be non-zero, both
  // triangles as stored (as AddContactColumns reads them): O(coupled² + uncoupled · per).
  void MultiplyBody(const Eigen::Ref<const Eigen::VectorXd>& x,
                    Eigen::Ref<Eigen::VectorXd> y) const;
  // y += W_body[:, a..a+3) δ for the three rows of friction contact a/3 (rows_per_contact 3).
  void AddContactColumns(int a, const Eigen::Vector3d& delta, Eigen::Ref<Eigen::VectorXd> y) const;

  int n = -1;               // rows cached; −1 before the first, or after a failed Take
  int coupled = 0;          // of them, the leading rows that may couple to others
  int per = 1;              // rows per contact
  int bilateral = 0;        // leading bilateral rows (ContactRows::num_bilateral_rows)
  std::uint64_t stamp = 0;  // their ContactRows::stamp
  // (max × max) W_body: its rows × rows block where they couple, each uncoupled contact's own
  // block, both full (upper entries too); the rest is not written (BodyLower).
  Eigen::MatrixXd W;
  Eigen::Matrix<double, Eigen::Dynamic, 6> U;  // (max × 6) [J_v J_ω]
  Eigen::VectorXd body_rhs;                    // (max)
  Eigen::VectorXd mu;                          // (max / 3 + 1) μ per contact, friction rows only
  int num_mu = 0;                              // entries of mu cached
};

// The checks both haptic solvers make of rows they are handed: W_body square of num_rows,
// body_rhs, J_w and lambda_frame_N and the three gap vectors (if given) of num_rows rows,
// friction_coefficient one finite μ ≥ 0 per contact with rows_per_contact 3 (a whole number of
// contacts) and empty with 1, num_uncoupled_rows whole contacts of num_rows, num_bilateral_rows
// within the coupled rows (and 0 with friction rows). (The other entries'
// finiteness and W_body's symmetry are checked where a solver copies them.)
bool HasConsistentShape(const ContactRows& rows);

// The tool's side of both haptic solves at one step: its compliance S = blockdiag(A_v⁻¹,
// M⁻¹A_L⁻¹) and free velocities s_free = S Δt [F̂; T̂] (world; m/s and rad/s). Returns whether
// both are finite. Fixed-size: no allocation.
bool CalcToolCompliance(const ToolStepSystem& tool, const Eigen::Vector3d& F_hat_N,
                        const Eigen::Vector3d& T_hat_N_m, Eigen::Matrix<double, 6, 6>* S,
                        Eigen::Matrix<double, 6, 1>* s_free);

// Builds the rows from the visual frame's data, the same inputs as MakeLinearContactModel: the
// Jacobian of the chosen contacts (rows_per_contact must be 1), the body's Delassus part over
// those rows and body_rhs = b − J_u u̇. W_body is symmetrised (½(W + Wᵀ)) so that the solver,
// which reads its lower triangle, sees exactly what was given up to round-off. Throws
// std::invalid_argument on a friction Jacobian or inconsistent sizes.
ContactRows MakeContactRows(const ContactJacobian& J, const Eigen::MatrixXd& W_body,
                            const Eigen::VectorXd& body_rhs);

// Same with W_body over all the frame's rows and `rows` the indices of the chosen ones (J and
// body_rhs hold only the chosen rows, in that order), as VisualFrame::BuildLinearModel selects
// the rows that travel. With a friction Jacobian (3 rows per contact, whole contacts chosen)
// friction_coefficient gives the chosen contacts' μ, as MakeFrictionContactRows. Rows from
// num_coupled_rows on (a whole number of contacts; default all coupled) travel uncoupled
// (ContactRows::num_uncoupled_rows): W_body keeps only their own contact's block.
ContactRows MakeContactRows(const ContactJacobian& J, const Eigen::MatrixXd& W_body_all,
                            const std::vector<int>& rows, const Eigen::VectorXd& body_rhs,
                            const Eigen::VectorXd& friction_coefficient = Eigen::VectorXd(),
                            int num_coupled_rows = -1);

// The rows of a friction Jacobian (rows_per_contact 3), every contact, with one μ per contact:
// for HapticFrictionSolver. W_body (over the same rows) is symmetrised as above. Throws
// std::invalid_argument on a normal-only Jacobian, inconsistent sizes or a μ < 0.
ContactRows MakeFrictionContactRows(const ContactJacobian& J, const Eigen::MatrixXd& W_body,
                                    const Eigen::VectorXd& body_rhs,
                                    const Eigen::VectorXd& friction_coefficient);

}  // namespace hapsim::contact
