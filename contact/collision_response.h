#pragma once
// Stage 5 of the visual frame (DESIGN.md §1, §4): constraint targets, impulses and the
// post-collision velocity changes of tool and body.
//
// Targets b (normal rows; tangent rows target 0): with φ the start-of-frame gap,
//   φ ≥ 0:  b = −φ/Δt   a speculative contact: the bodies may close the gap within the frame but
//                       not cross it, which is what stops a fast tool from tunnelling;
//   φ < 0:  b = −β φ/Δt position stabilisation: a fraction β of the penetration is undone;
// and, with restitution e, for a contact closing at c⁻ < 0 whose gap closes within the frame
// (φ ≤ −c⁻ Δt), b = max(b, −e c⁻): the separating velocity after impact is e times the approach
// velocity (Newton's impact law, the approach of papers/001). A grasp row (Contact::bilateral)
// takes b = −β φ/Δt whatever φ's sign, and no restitution.

#include <Eigen/Core>
#include <vector>

#include "contact/contact.h"
#include "contact/contact_jacobian.h"
#include "contact/contact_solver.h"

namespace hapsim::contact {

struct ResponseOptions {
  ContactSolveOptions solve;
  double stabilization_beta = 0.2;  // fraction of a penetration corrected per frame, [0, 1]
  double restitution = 0.0;         // e in [0, 1]
};

// b for each constraint row. c_pre: separating velocity of each row at the start of the frame.
Eigen::VectorXd CalcConstraintTargets(const std::vector<Contact>& contacts,
                                      const Eigen::VectorXd& c_pre, int rows_per_contact,
                                      double dt_s, const ResponseOptions& options);

// Equality constraints hold the bodies together, so only contacts that collide within the frame
// (predicted gap φ + Δt c_free below `margin_m`) may become constraints, and grasp rows, which
// hold them together by design; unilateral and friction constraints may keep every candidate (an
// inactive one gets λ = 0). Returns the kept indices.
std::vector<int> SelectCollidingContacts(const std::vector<Contact>& contacts,
                                         const Eigen::VectorXd& c_free, int rows_per_contact,
                                         double dt_s, double margin_m);

}  // namespace hapsim::contact
