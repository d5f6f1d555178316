#include "contact/god_object.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "contact/tool_distance.h"

namespace hapsim::contact {

using Eigen::Vector3d;

namespace {

// Active normals count as dependent when the Gram determinant det(NᵀN) is below this (for two
// planes 1 − cos²φ = sin²φ: φ < 1e-5 rad); the Lagrange system is then (nearly) singular.
constexpr double kDependentGram = 1e-10;
// Path searches per step: three additions and a few replacements of dependent planes; then the
// god-object stops at the next crossing.
constexpr int kMaxSearches = 6;

using Constraint = GodObject::Constraint;

// argmin |x − hip|² subject to n_i·x = c_i + ε, i < k (header: thesis eq. 3.4–3.7). False if the
// normals are (nearly) dependent.
bool SolveGoal(const std::array<Constraint, 3>& planes, int k, double epsilon_m,
               const Vector3d& hip, Vector3d* x) {
  if (k == 0) {
    *x = hip;
    return true;
  }
  const Vector3d& n1 = planes[0].normal_W;
  const double c1 = planes[0].offset_m + epsilon_m;
  if (k == 1) {
    *x = hip + (c1 - n1.dot(hip)) * n1;
    return true;
  }
  const Vector3d& n2 = planes[1].normal_W;
  const double c2 = planes[1].offset_m + epsilon_m;
  if (k == 2) {
    // (NᵀN) l = Nᵀ hip − c with NᵀN = [1 g; g 1]; x = hip − N l.
    const double g = n1.dot(n2);
    const double det = 1.0 - g * g;
    if (det < kDependentGram) return false;
    const double b1 = n1.dot(hip) - c1;
    const double b2 = n2.dot(hip) - c2;
    const double l1 = (b1 - g * b2) / det;
    const double l2 = (b2 - g * b1) / det;
    *x = hip - l1 * n1 - l2 * n2;
    return true;
  }
  // Three planes: the constraints alone fix x = N⁻ᵀ c (Cramer's rule), whatever the HIP.
  const Vector3d& n3 = planes[2].normal_W;
  const double c3 = planes[2].offset_m + epsilon_m;
  const double det = n1.dot(n2.cross(n3));
  if (det * det < kDependentGram) return false;
  *x = (c1 * n2.cross(n3) + c2 * n3.cross(n1) + c3 * n1.cross(n2)) / det;
  return true;
}

}  // namespace

void ValidateGodObjectParams(const GodObjectParams& p) {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("GodObjectParams: " + what);
  };
  if (!(p.stiffness_N_m > 0.0) || !std::isfinite(p.stiffness_N_m))
    fail("stiffness_N_m must be positive and finite");
  if (!(p.proxy_radius_m >= 0.0) || !std::isfinite(p.proxy_radius_m))
    fail("proxy_radius_m must be >= 0 and finite");
  if (!(p.surface_epsilon_m > 0.0) || !std::isfinite(p.surface_epsilon_m))
    fail("surface_epsilon_m must be positive and finite");
  if (!(p.static_friction >= 0.0) || !(p.dynamic_friction >= 0.0))
    fail("friction coefficients must be >= 0");
  if (p.dynamic_friction > p.static_friction)
    fail("dynamic_friction must not exceed static_friction");
  if (!(p.texture_amplitude_m >= 0.0)) fail("texture_amplitude_m must be >= 0");
  if (p.texture_amplitude_m > 0.0 &&
      (!(p.texture_wavelength_m > 0.0) || !(p.texture_direction_O.norm() > 0.0)))
    fail("a texture needs a positive wavelength and a non-zero direction");
}

GodObject::GodObject(const GodObjectParams& params) : params_(params) {
  ValidateGodObjectParams(params_);
  if (params_.texture_amplitude_m > 0.0) params_.texture_direction_O.normalize();
}

void GodObject::Reset(const Vector3d& p_W_m) {
  initialised_ = true;
  god_object_W_m_ = proxy_W_m_ = p_W_m;
  force_W_N_.setZero();
  normal_force_N_ = 0.0;
  num_active_ = 0;
  stuck_ = false;
  for (Mesh& mesh : meshes_) mesh.X_WO_last = mesh.X_WO;
}

Constraint GodObject::FindFirstCrossing(const Vector3d& goal_W, Vector3d* point_W,
                                        double* t_out) const {
  Constraint best;
  *t_out = 2.0;
  for (int id = 0; id < num_meshes(); ++id) {
    const Mesh& mesh = meshes_[id];
    // From the last god-object, carried along with the mesh, to the goal, in O.
    const Vector3d p0 = mesh.X_WO_last.inverse(Eigen::Isometry) * god_object_W_m_;
    const Vector3d p1 = mesh.X_WO.inverse(Eigen::Isometry) * goal_W;
    // The goal is ε in front of the active planes, but round-off in a nearly singular solve can
    // put it a hair behind one: their triangles are skipped, all of them, so that such a plane
    // does not hide a real crossing further along.
    Exclusions exclude = {-1, -1, -1};
    for (int i = 0; i < num_active_; ++i) {
      if (active_[i].mesh == id) exclude[i] = active_[i].triangle;
    }
    const Crossing crossing = CalcFirstCrossing(id, p0, p1, exclude);
    if (crossing.triangle < 0 || crossing.t >= *t_out) continue;
    *t_out = crossing.t;
    best.mesh = id;
    best.triangle = crossing.triangle;
    best.normal_W = mesh.X_WO.linear() * mesh.face_normals_O.col(crossing.triangle);
    // n_O·x_O = c_O with x_O = X_WO⁻¹ x_W  ⇔  n_W·x_W = c_O + n_W·t_WO.
    best.offset_m = mesh.offsets_m(crossing.triangle) + best.normal_W.dot(mesh.X_WO.translation());
    *point_W =
        mesh.X_WO * (p0 + crossing.t * (p1 - p0)) + params_.surface_epsilon_m * best.normal_W;
  }
  return best;
}

Vector3d GodObject::CalcShadingNormal(const Constraint& c) const {
  const Mesh& mesh = meshes_[c.mesh];
  const Vector3d g_O = mesh.X_WO.inverse(Eigen::Isometry) * god_object_W_m_;
  const auto& T = mesh.triangles;
  const TrianglePoint closest = CalcClosestPointOnTriangle(
      g_O, mesh.vertices_O_m.col(T(0, c.triangle)), mesh.vertices_O_m.col(T(1, c.triangle)),
      mesh.vertices_O_m.col(T(2, c.triangle)));
  Vector3d n_O = Vector3d::Zero();
  for (int k = 0; k < 3; ++k)
    n_O += closest.weights(k) * mesh.vertex_normals_O.col(T(k, c.triangle));
  if (n_O.norm() < 1e-9) return c.normal_W;
  return mesh.X_WO.linear() * n_O.normalized();
}

void GodObject::Step(const Vector3d& hip_W_m) {
  if (!initialised_) Reset(hip_W_m);
  // A stiction point resting on a mesh moves with it.
  if (num_active_ > 0) {
    const Mesh& mesh = meshes_[active_[0].mesh];
    proxy_W_m_ = mesh.X_WO * (mesh.X_WO_last.inverse(Eigen::Isometry) * proxy_W_m_);
  }
  const bool was_in_contact = num_active_ > 0;
  const Vector3d first_point_W = PlaceGodObject(hip_W_m);  // 1. the constrained god-object
  ApplyFriction(hip_W_m, was_in_contact, first_point_W);   // 2. the stiction point, the force
  ApplyTextureAndShading();                                // 3. one plane only
}

// 1. Constraints found one at a time along the path (thesis §3.2.2); returns where the path
// first met a surface (the hip if it met none).
Vector3d GodObject::PlaceGodObject(const Vector3d& hip_W_m) {
  const double epsilon = params_.surface_epsilon_m;
  num_active_ = 0;
  Vector3d goal = hip_W_m;
  Vector3d first_point_W = hip_W_m;
  for (int search = 0;; ++search) {
    Vector3d point_W;
    double t;
    const Constraint found = FindFirstCrossing(goal, &point_W, &t);
    if (found.mesh < 0) break;
    if (num_active_ == 0) first_point_W = point_W;
    Vector3d x;
    if (search < kMaxSearches && num_active_ < 3) {
      active_[num_active_] = found;
      if (SolveGoal(active_, num_active_ + 1, epsilon, hip_W_m, &x)) {
        ++num_active_;
        goal = x;
        continue;
      }
    }
    // Dependent on the active planes: take the place of one of them if that leaves the goal in
    // front of the plane it replaces (hidden surface removal, thesis §3.3.3).
    bool replaced = false;
    for (int i = 0; i < num_active_ && !replaced && search < kMaxSearches; ++i) {
      std::array<Constraint, 3> trial = active_;
      trial[i] = found;
      if (SolveGoal(trial, num_active_, epsilon, hip_W_m, &x) &&
          active_[i].normal_W.dot(x) - active_[i].offset_m >= 0.0) {
        active_ = trial;
        goal = x;
        replaced = true;
      }
    }
    if (replaced) continue;
    // Unresolved (a fourth plane, nearly dependent planes on a finely curved saddle, or too many
    // searches): stop where the path met this plane. That point lies on the path from the last
    // god-object, before its first crossing, so in front of every plane: never through.
    goal = point_W;
    break;
  }
  god_object_W_m_ = goal;
  for (Mesh& mesh : meshes_) mesh.X_WO_last = mesh.X_WO;
  return first_point_W;
}

// 2. The stiction point follows the god-object (thesis §4.1.1); the spring force to it.
void GodObject::ApplyFriction(const Vector3d& hip_W_m, bool was_in_contact,
                              const Vector3d& first_point_W) {
  const double k = params_.stiffness_N_m;
  stuck_ = false;
  normal_force_N_ = 0.0;
  if (num_active_ == 0) {
    proxy_W_m_ = god_object_W_m_;
  } else {
    if (!was_in_contact) proxy_W_m_ = first_point_W;
    const double depth_m = (god_object_W_m_ - hip_W_m).norm();
    const Vector3d slip = proxy_W_m_ - god_object_W_m_;
    const double slip_m = slip.norm();
    normal_force_N_ = k * depth_m;
    if (params_.static_friction > 0.0 && slip_m <= params_.static_friction * depth_m) {
      stuck_ = true;
    } else if (slip_m > 0.0) {
      proxy_W_m_ = god_object_W_m_ + (params_.dynamic_friction * depth_m / slip_m) * slip;
    }
  }
  force_W_N_ = k * (proxy_W_m_ - hip_W_m);
}

// 3. Texture and shading on the output, with one active plane only (header comment).
void GodObject::ApplyTextureAndShading() {
  if (num_active_ != 1) return;
  const Constraint& c = active_[0];
  if (params_.texture_amplitude_m > 0.0) {
    const Mesh& mesh = meshes_[c.mesh];
    const double s_m =
        params_.texture_direction_O.dot(mesh.X_WO.inverse(Eigen::Isometry) * proxy_W_m_);
    const double h_m =
        params_.texture_amplitude_m * std::sin(2.0 * M_PI * s_m / params_.texture_wavelength_m);
    force_W_N_ += params_.stiffness_N_m * h_m * c.normal_W;
    normal_force_N_ += params_.stiffness_N_m * h_m;
  }
  if (params_.shading) {
    force_W_N_ = Eigen::Quaterniond::FromTwoVectors(c.normal_W, CalcShadingNormal(c)) * force_W_N_;
  }
}

}  // namespace hapsim::contact
