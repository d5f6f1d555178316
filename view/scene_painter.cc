#include "view/scene_painter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "contact/rigid_objects.h"
#include "contact/tool_distance.h"

namespace hapsim::view {
namespace {

const cv::viz::Color kTissue(170, 170, 235);  // BGR: a pale flesh tone at zero displacement
const cv::viz::Color kDeepRed(30, 30, 190);   // at the displacement scale and beyond
const cv::viz::Color kRigid(150, 150, 150);
const cv::viz::Color kSelected(120, 220, 240);  // a grabbable object the tool touches
const cv::viz::Color kGrabbed(90, 200, 90);     // the object the tool holds
const cv::viz::Color kTool(230, 200, 120);
const cv::viz::Color kGhost(255, 255, 255);
const cv::viz::Color kContact(0, 230, 255);
const cv::viz::Color kForce(60, 60, 255);
const cv::viz::Color kTargetOpen(0, 140, 255);
const cv::viz::Color kTargetReached(60, 200, 60);

cv::Vec3d ToVec(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

// A camera looking at the middle of the scene's bounding box from the front, above and to the
// side, far enough to hold the whole box.
cv::Affine3d MakeCameraPose(const Eigen::AlignedBox3d& box) {
  const Eigen::Vector3d centre = box.center();
  const double size = std::max(box.diagonal().norm(), 0.02);
  const Eigen::Vector3d eye = centre + size * Eigen::Vector3d(0.6, -1.5, 0.9);
  // viz cameras follow OpenCV's convention, y pointing down the image: world z up is −y.
  return cv::viz::makeCameraPose(ToVec(eye), ToVec(centre), cv::Vec3d(0, 0, -1));
}

// A flat disc of `radius_m` at height z, normal ±z, as a triangle fan.
cv::viz::WMesh MakeDisc(double radius_m, double z_m, int sides, const cv::viz::Color& color) {
  cv::viz::Mesh mesh;
  mesh.cloud.create(1, sides + 1, CV_64FC3);
  mesh.cloud.at<cv::Vec3d>(0, 0) = cv::Vec3d(0, 0, z_m);
  for (int k = 0; k < sides; ++k) {
    const double angle = 2.0 * M_PI * k / sides;
    mesh.cloud.at<cv::Vec3d>(0, k + 1) =
        cv::Vec3d(radius_m * std::cos(angle), radius_m * std::sin(angle), z_m);
  }
  mesh.polygons.create(1, 4 * sides, CV_32SC1);
  for (int k = 0; k < sides; ++k) {
    int* triangle = mesh.polygons.ptr<int>(0) + 4 * k;
    triangle[0] = 3;
    triangle[1] = 0;
    triangle[2] = k + 1;
    triangle[3] = (k + 1) % sides + 1;
  }
  cv::viz::WMesh disc(mesh);
  disc.setColor(color);
  return disc;
}

// `shape` grown by `fraction` of its bounding radius on every side (a mesh: scaled), so that the
// device's ghost, drawn as lines, does not lie on the tool's surface where the two coincide: there
// the depth test would pick between them by rounding, differently from one window to the next.
ToolShape Inflate(ToolShape shape, double fraction) {
  const double grow_m = fraction * contact::ToolDistanceField(shape).bounding_radius_m();
  shape.radius_m += grow_m;
  shape.length_m += shape.kind == ToolShape::Kind::kCylinder ? 2.0 * grow_m : 0.0;
  shape.edge_radius_m = 0.0;
  shape.half_extents_m.array() += grow_m;
  shape.mesh.vertices_m *= 1.0 + fraction;
  return shape;
}

}  // namespace

cv::Affine3d ToAffine(const double x_W_m[3], const double q[4]) {
  const Eigen::Matrix3d R =
      Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  cv::Matx33d rotation;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) rotation(i, j) = R(i, j);
  return cv::Affine3d(rotation, cv::Vec3d(x_W_m[0], x_W_m[1], x_W_m[2]));
}

cv::viz::Widget3D MakeShapeWidget(const ToolShape& shape, const cv::viz::Color& color,
                                  bool wireframe) {
  cv::viz::WWidgetMerger merged;
  const double half_length = 0.5 * shape.length_m;
  switch (shape.kind) {
    case ToolShape::Kind::kSphere:
      merged.addWidget(cv::viz::WSphere(cv::Point3d(0, 0, 0), shape.radius_m, 24, color));
      break;
    case ToolShape::Kind::kCapsule:
      merged.addWidget(cv::viz::WCylinder(cv::Point3d(0, 0, -half_length),
                                          cv::Point3d(0, 0, half_length), shape.radius_m, 32,
                                          color));
      for (const double z : {-half_length, half_length})
        merged.addWidget(cv::viz::WSphere(cv::Point3d(0, 0, z), shape.radius_m, 24, color));
      break;
    case ToolShape::Kind::kCylinder:
      merged.addWidget(cv::viz::WCylinder(cv::Point3d(0, 0, -half_length),
                                          cv::Point3d(0, 0, half_length), shape.radius_m, 48,
                                          color));
      // WCylinder is an open tube (and viz circles are rings): close it with two discs.
      for (const double z : {-half_length, half_length})
        merged.addWidget(MakeDisc(shape.radius_m, z, 48, color));
      break;
    case ToolShape::Kind::kBox: {
      const Eigen::Vector3d& h = shape.half_extents_m;
      merged.addWidget(cv::viz::WCube(cv::Point3d(-h.x(), -h.y(), -h.z()),
                                      cv::Point3d(h.x(), h.y(), h.z()), false, color));
      break;
    }
    case ToolShape::Kind::kMesh: {
      cv::viz::Mesh mesh;
      mesh.cloud.create(1, static_cast<int>(shape.mesh.vertices_m.cols()), CV_64FC3);
      for (int v = 0; v < mesh.cloud.cols; ++v)
        mesh.cloud.at<cv::Vec3d>(0, v) = ToVec(shape.mesh.vertices_m.col(v));
      mesh.polygons.create(1, 4 * static_cast<int>(shape.mesh.triangles.cols()), CV_32SC1);
      for (int f = 0; f < shape.mesh.triangles.cols(); ++f) {
        mesh.polygons.at<int>(0, 4 * f) = 3;
        for (int k = 0; k < 3; ++k)
          mesh.polygons.at<int>(0, 4 * f + 1 + k) = shape.mesh.triangles(k, f);
      }
      cv::viz::WMesh widget(mesh);
      widget.setColor(color);
      merged.addWidget(widget);
      break;
    }
  }
  merged.finalize();
  merged.setColor(color);  // the parts' colours do not all survive the merge
  merged.setRenderingProperty(cv::viz::SHADING, cv::viz::SHADING_PHONG);
  if (wireframe)
    merged.setRenderingProperty(cv::viz::REPRESENTATION, cv::viz::REPRESENTATION_WIREFRAME);
  return merged;
}

ScenePainter::ScenePainter(cv::viz::Viz3d* window, const config::Scene& scene,
                           Matrix3Xd rest_positions_m, const PainterOptions& options)
    : window_(window),
      scene_(scene),
      rest_positions_m_(std::move(rest_positions_m)),
      options_(options) {
  window_->setBackgroundColor(cv::viz::Color(60, 45, 40));  // a gradient cost 7 ms a picture
  Eigen::AlignedBox3d box;
  for (Eigen::Index n = 0; n < rest_positions_m_.cols(); ++n) box.extend(rest_positions_m_.col(n));
  for (const config::RigidObjectScene& rigid : scene.rigid_objects) {
    const contact::RigidObject& object = rigid.object;
    const Eigen::Quaterniond q(object.X_WO.linear());
    const double x[3] = {object.X_WO.translation().x(), object.X_WO.translation().y(),
                         object.X_WO.translation().z()};
    const double q_wxyz[4] = {q.w(), q.x(), q.y(), q.z()};
    window_->showWidget("rigid_" + object.name, MakeShapeWidget(object.shape, kRigid, false),
                        ToAffine(x, q_wxyz));
    box.extend(contact::CalcWorldBox(object));
  }
  if (scene.tool) {
    const double radius_m = contact::ToolDistanceField(scene.tool->model.shape).bounding_radius_m();
    box.extend(scene.tool->initial_state.x_W_m + Eigen::Vector3d::Constant(radius_m));
    box.extend(scene.tool->initial_state.x_W_m - Eigen::Vector3d::Constant(radius_m));
  }
  window_->setViewerPose(MakeCameraPose(box));
  if (!(options_.displacement_scale_m > 0.0)) {
    options_.displacement_scale_m = 0.005;
    if (rest_positions_m_.cols() > 0) {
      const Eigen::Vector3d extent_m =
          rest_positions_m_.rowwise().maxCoeff() - rest_positions_m_.rowwise().minCoeff();
      options_.displacement_scale_m = std::min(0.005, 0.25 * extent_m.minCoeff());
    }
  }
  if (!(options_.force_gauge_N > 0.0))
    options_.force_gauge_N =
        scene.task ? 1.5 * scene.task->force_limit_N : scene.haptic.safety.max_force_N;
  if (!(options_.force_scale_m_N > 0.0))
    options_.force_scale_m_N = 0.25 * box.diagonal().norm() / options_.force_gauge_N;
  // The widgets that only move are made once (a merged cylinder costs milliseconds) and placed
  // by Place() when first seen.
  if (scene.tool) {
    tool_widget_ = MakeShapeWidget(scene.tool->model.shape, kTool, false);
    ghost_widget_ = MakeShapeWidget(Inflate(scene.tool->model.shape, 0.03), kGhost, true);
  }
  if (scene.task) {
    for (const config::PalpationTarget& target : scene.task->targets) {
      // As lines: a translucent sphere made VTK peel depth layers, a third of the picture's
      // cost with software OpenGL.
      cv::viz::WSphere sphere(cv::Point3d(0, 0, 0), target.radius_m, 12, kTargetOpen);
      sphere.setRenderingProperty(cv::viz::REPRESENTATION, cv::viz::REPRESENTATION_WIREFRAME);
      sphere.setRenderingProperty(cv::viz::LINE_WIDTH, 2.0);
      Show("target_" + target.name, sphere,
           cv::Affine3d(cv::Matx33d::eye(), ToVec(target.position_m)));
    }
  }
}

void ScenePainter::Place(const std::string& name, const cv::Affine3d& pose) {
  if (shown_.count(name) == 0) {
    Show(name, name == "tool" ? tool_widget_ : ghost_widget_, pose);
  } else {
    window_->setWidgetPose(name, pose);
  }
}

void ScenePainter::SetDisplacementReference(const hapsim_lcm::sim_frame_t& frame) {
  rest_positions_m_.resize(3, frame.num_nodes);
  for (int n = 0; n < frame.num_nodes; ++n)
    for (int d = 0; d < 3; ++d) rest_positions_m_(d, n) = frame.positions_W_m[n][d];
}

void ScenePainter::DrawBody(const hapsim_lcm::sim_frame_t& frame) {
  const int num_nodes = frame.num_nodes;
  if (num_nodes == 0 || frame.num_triangles == 0) return;
  cv::viz::Mesh mesh;
  mesh.cloud.create(1, num_nodes, CV_32FC3);
  cv::Mat level(1, num_nodes, CV_8UC1);
  const bool has_rest = rest_positions_m_.cols() == num_nodes;
  for (int n = 0; n < num_nodes; ++n) {
    const std::vector<float>& p = frame.positions_W_m[n];
    mesh.cloud.at<cv::Vec3f>(0, n) = cv::Vec3f(p[0], p[1], p[2]);
    const double u_m =
        has_rest ? (Eigen::Vector3d(p[0], p[1], p[2]) - rest_positions_m_.col(n)).norm() : 0.0;
    level.at<uchar>(0, n) = static_cast<uchar>(
        std::lround(255.0 * std::clamp(u_m / options_.displacement_scale_m, 0.0, 1.0)));
  }
  // Colour: the tissue tone at rest, blending linearly into a deep red at displacement_scale_m.
  mesh.colors.create(1, num_nodes, CV_8UC3);
  for (int n = 0; n < num_nodes; ++n) {
    const double a = level.at<uchar>(0, n) / 255.0;
    cv::Vec3b c;
    for (int k = 0; k < 3; ++k) c[k] = static_cast<uchar>((1.0 - a) * kTissue[k] + a * kDeepRed[k]);
    mesh.colors.at<cv::Vec3b>(0, n) = c;
  }
  // Area-weighted vertex normals, for smooth shading of the faceted surface.
  mesh.polygons.create(1, 4 * frame.num_triangles, CV_32SC1);
  mesh.normals = cv::Mat::zeros(1, num_nodes, CV_32FC3);
  for (int f = 0; f < frame.num_triangles; ++f) {
    mesh.polygons.at<int>(0, 4 * f) = 3;
    const std::vector<int32_t>& t = frame.triangles[f];
    for (int k = 0; k < 3; ++k) mesh.polygons.at<int>(0, 4 * f + 1 + k) = t[k];
    const cv::Vec3f a = mesh.cloud.at<cv::Vec3f>(0, t[0]), b = mesh.cloud.at<cv::Vec3f>(0, t[1]),
                    c = mesh.cloud.at<cv::Vec3f>(0, t[2]);
    const cv::Vec3f area_normal = (b - a).cross(c - a);  // twice the area, outward
    for (int k = 0; k < 3; ++k) mesh.normals.at<cv::Vec3f>(0, t[k]) += area_normal;
  }
  for (int n = 0; n < num_nodes; ++n) {
    cv::Vec3f& normal = mesh.normals.at<cv::Vec3f>(0, n);
    const float length = static_cast<float>(cv::norm(normal));
    if (length > 0.0f) normal /= length;
  }
  Show("body", cv::viz::WMesh(mesh));
}

void ScenePainter::DrawGauge(const ViewState& state) {
  char line[256];
  const double force_N =
      state.has_haptic ? Eigen::Map<const Eigen::Vector3d>(state.haptic.force_device_W_N).norm()
                       : 0.0;
  const int bars =
      static_cast<int>(std::lround(20.0 * std::clamp(force_N / options_.force_gauge_N, 0.0, 1.0)));
  std::string gauge = "[" + std::string(bars, '|') + std::string(20 - bars, '.') + "]";
  std::snprintf(line, sizeof(line), "t %6.2f s   force %5.2f N %s %.0f N",
                state.has_frame ? state.frame.t_s : 0.0, force_N, gauge.c_str(),
                options_.force_gauge_N);
  std::string text = line;
  if (state.has_haptic) {
    const hapsim_lcm::haptic_state_t& h = state.haptic;
    std::snprintf(line, sizeof(line),
                  "\nloop: %s | step %lld | p99 %.0f us | overruns %lld | model %.0f ms old | "
                  "passivity %.4f J",
                  h.zeroed ? ("ZERO FORCE: " + h.reason).c_str() : "rendering",
                  static_cast<long long>(h.step), 1e6 * h.period_error_p99_s,
                  static_cast<long long>(h.overruns), 1e3 * h.model_age_s, h.passivity_energy_J);
    text += line;
  } else {
    text += "\nloop: no state yet";
  }
  if (!state.status.empty()) text += "\n" + state.status;
  Show("gauge", cv::viz::WText(text, cv::Point(10, 12), 14, cv::viz::Color::white()));
}

void ScenePainter::Show(const std::string& name, const cv::viz::Widget& widget,
                        const cv::Affine3d& pose) {
  window_->showWidget(name, widget, pose);
  shown_.insert(name);
}

void ScenePainter::Hide(const std::string& name) {
  if (shown_.erase(name) > 0) window_->removeWidget(name);  // viz asserts on an unknown name
}

void ScenePainter::DrawObjects(const hapsim_lcm::sim_frame_t& frame) {
  // A frame of another scene (or of an older run without objects) leaves them where they are.
  if (frame.num_objects != static_cast<int>(scene_.rigid_objects.size())) return;
  for (int i = 0; i < frame.num_objects; ++i) {
    const std::string name = "rigid_" + scene_.rigid_objects[i].object.name;
    window_->setWidgetPose(name,
                           ToAffine(frame.object_x_W_m[i].data(), frame.object_q_WO[i].data()));
    const cv::viz::Color color = i == frame.grabbed_object    ? kGrabbed
                                 : i == frame.selected_object ? kSelected
                                                              : kRigid;
    window_->getWidget(name).cast<cv::viz::Widget3D>().setColor(color);
  }
}

void ScenePainter::Draw(const ViewState& state) {
  if (state.has_frame) {
    const hapsim_lcm::sim_frame_t& frame = state.frame;
    DrawBody(frame);
    DrawObjects(frame);
    if (scene_.tool) Place("tool", ToAffine(frame.x_W_m, frame.q_WT));
    if (frame.num_contacts > 0) {
      cv::Mat points(1, frame.num_contacts, CV_64FC3);
      for (int i = 0; i < frame.num_contacts; ++i)
        points.at<cv::Vec3d>(0, i) =
            cv::Vec3d(frame.p_W_m[i][0], frame.p_W_m[i][1], frame.p_W_m[i][2]);
      cv::viz::WCloud cloud(points, kContact);
      cloud.setRenderingProperty(cv::viz::POINT_SIZE, 5.0);
      Show("contacts", cloud);
    } else {
      Hide("contacts");
    }
  }
  for (size_t i = 0; i < state.targets_reached.size() && scene_.task; ++i) {
    const config::PalpationTarget& target = scene_.task->targets[i];
    window_->getWidget("target_" + target.name)
        .cast<cv::viz::WSphere>()
        .setColor(state.targets_reached[i] ? kTargetReached : kTargetOpen);
  }
  if (state.has_device && scene_.tool)
    Place("ghost", ToAffine(state.device.x_W_m, state.device.q_WD));
  if (state.has_haptic && state.has_frame) {
    const Eigen::Vector3d from(state.frame.x_W_m[0], state.frame.x_W_m[1], state.frame.x_W_m[2]);
    const Eigen::Vector3d force(state.haptic.force_device_W_N[0], state.haptic.force_device_W_N[1],
                                state.haptic.force_device_W_N[2]);
    if (force.norm() > 1e-3) {
      // WArrow rolls its cone by a vector drawn from OpenCV's RNG: a fixed seed draws the same
      // arrow for the same force in every window (a log's picture equals the live one).
      cv::theRNG().state = 0x5eed;
      Show("force", cv::viz::WArrow(ToVec(from), ToVec(from + options_.force_scale_m_N * force),
                                    0.03, kForce));
    } else {
      Hide("force");
    }
  }
  DrawGauge(state);
}

}  // namespace hapsim::view
