#include "contact/quadratic_surface.h"

#include <stdexcept>

namespace hapsim::contact {
namespace {

// Face coordinates (s, t) of the face nodes o0 o1 o2 m01 m12 m20.
constexpr double kFaceS[6] = {0.0, 1.0, 0.0, 0.5, 0.5, 0.0};
constexpr double kFaceT[6] = {0.0, 0.0, 1.0, 0.0, 0.5, 0.5};

}  // namespace

QuadraticSurface::QuadraticSurface(const Matrix3Xi& sub_triangles, int num_nodes) {
  if (sub_triangles.cols() % 4 != 0)
    throw std::invalid_argument("QuadraticSurface: sub-triangles must come four a face");
  const Eigen::Index num_faces = sub_triangles.cols() / 4;
  face_nodes_.resize(6, num_faces);
  for (Eigen::Index f = 0; f < num_faces; ++f) {
    const auto T = [&](int row, int sub) { return sub_triangles(row, 4 * f + sub); };
    face_nodes_.col(f) << T(0, 0), T(1, 1), T(2, 2), T(1, 0), T(2, 1), T(2, 0);
    // The four must agree on the shared nodes, and the middle one be (m01 m12 m20).
    const bool consistent = T(0, 1) == T(1, 0) && T(0, 2) == T(2, 0) && T(1, 2) == T(2, 1) &&
                            T(0, 3) == T(1, 0) && T(1, 3) == T(2, 1) && T(2, 3) == T(2, 0);
    if (!consistent)
      throw std::invalid_argument("QuadraticSurface: face " + std::to_string(f) +
                                  "'s sub-triangles are not a quadratic face's four");
  }
  node_face_begin_.assign(num_nodes + 1, 0);
  for (Eigen::Index f = 0; f < num_faces; ++f)
    for (int k = 0; k < 6; ++k) ++node_face_begin_[face_nodes_(k, f) + 1];
  for (int n = 0; n < num_nodes; ++n) node_face_begin_[n + 1] += node_face_begin_[n];
  node_faces_.resize(node_face_begin_[num_nodes]);
  std::vector<int> next(node_face_begin_.begin(), node_face_begin_.end() - 1);
  for (Eigen::Index f = 0; f < num_faces; ++f)
    for (int k = 0; k < 6; ++k) node_faces_[next[face_nodes_(k, f)]++] = static_cast<int>(f);
}

void QuadraticSurface::Reweight(Contact* contact) const {
  int count = 0;
  while (count < kMaxContactNodes && contact->nodes[count] >= 0) ++count;
  if (count < 2 || count > 3) return;
  // A face holding every node of the contact, and each node's place in it.
  const int first = contact->nodes[0];
  for (int i = node_face_begin_[first]; i < node_face_begin_[first + 1]; ++i) {
    const int f = node_faces_[i];
    int place[3] = {-1, -1, -1};
    for (int j = 0; j < count; ++j)
      for (int k = 0; k < 6; ++k)
        if (face_nodes_(k, f) == contact->nodes[j]) place[j] = k;
    if (place[0] < 0 || place[1] < 0 || (count == 3 && place[2] < 0)) continue;
    double s = 0.0, t = 0.0;
    for (int j = 0; j < count; ++j) {
      s += contact->weights[j] * kFaceS[place[j]];
      t += contact->weights[j] * kFaceT[place[j]];
    }
    const double L[3] = {1.0 - s - t, s, t};
    const double N[6] = {L[0] * (2.0 * L[0] - 1.0), L[1] * (2.0 * L[1] - 1.0),
                         L[2] * (2.0 * L[2] - 1.0), 4.0 * L[0] * L[1],
                         4.0 * L[1] * L[2],         4.0 * L[2] * L[0]};
    contact->nodes.fill(-1);
    contact->weights.fill(0.0);
    int slot = 0;
    for (int k = 0; k < 6; ++k) {
      if (N[k] == 0.0) continue;  // exactly zero along the face's edges: no row entry
      contact->nodes[slot] = face_nodes_(k, f);
      contact->weights[slot++] = N[k];
    }
    return;
  }
}

}  // namespace hapsim::contact
