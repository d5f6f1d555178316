#pragma once
// Contacts on the boundary of a body of quadratic tets (issue 27 item 2). The detector finds them
// on the boundary's sub-triangles, four a face (fem::ExtractBoundarySurface), with the linear
// weights of the sub-triangle's corners. Re-weighted here by the quadratic face's own shape
// functions at the same point of the face, the contact's Jacobian row moves the point as the
// quadratic displacement field does:
//
//   face nodes  o0, o1, o2 (corners), m01, m12, m20 (edge nodes), at face coordinates
//               (0,0) (1,0) (0,1) (½,0) (½,½) (0,½);
//   the point   (s, t) = Σ_k w_k (s_k, t_k) over the sub-triangle nodes it was found with;
//   its weights N = L_i (2 L_i − 1) at the corners, 4 L_i L_j at the edge nodes,
//               L = (1 − s − t, s, t).
//
// On an undeformed (flat-faced) body the point Σ N_a x_a is the sub-triangle's point itself (the
// quadratic functions reproduce linear geometry); on a deformed one it is the curved face's point
// at the same face coordinates, a distance O(h² curvature) from the flat sub-triangle the gap was
// measured on. A contact at a node keeps it (the functions are 1 there and 0 at the others).

#include <vector>

#include "contact/contact.h"
#include "core/eigen_types.h"

namespace hapsim::contact {

class QuadraticSurface {
 public:
  // sub_triangles: a quadratic mesh's boundary as ExtractBoundarySurface gives it, face by face
  // (o0 m01 m20) (m01 o1 m12) (m20 m12 o2) (m01 m12 m20). Throws std::invalid_argument if the
  // triangles are not in that layout.
  QuadraticSurface(const Matrix3Xi& sub_triangles, int num_nodes);

  // Re-weights a contact whose 2 or 3 nodes lie on one face; one of 1 node (or of another
  // surface) is left as it is. Keeps surface_points (what names the contact).
  void Reweight(Contact* contact) const;

 private:
  Matrix6Xi face_nodes_;  // per face: o0 o1 o2 m01 m12 m20
  // The faces around each node (CSR): node_faces_[node_face_begin_[n] .. node_face_begin_[n+1]).
  std::vector<int> node_face_begin_, node_faces_;
};

}  // namespace hapsim::contact
