#include "view/scene_painter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "contact/rigid_objects.h"
#include "contact/tool_distance.h"
#include "core/shape_mesh.h"
#include "view/depth_cue.h"
#include "view/shape_widget.h"

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
const cv::viz::Color kDropLine(40, 220, 250);  // the tool's drop line and shadow ring

// A camera looking at the middle of the scene's bounding box from the front, above and to the
// side (or, for the side view, level from the front along +y), far enough to hold the whole box.
cv::Affine3d MakeCameraPose(const Eigen::AlignedBox3d& box, bool side) {
  const Eigen::Vector3d centre = box.center();
  const double size = std::max(box.diagonal().norm(), 0.02);
  const Eigen::Vector3d eye =
      centre + size * (side ? Eigen::Vector3d(0.0, -1.2, 0.0) : Eigen::Vector3d(0.6, -1.5, 0.9));
  // viz cameras follow OpenCV's convention, y pointing down the image: world z up is −y.
  return cv::viz::makeCameraPose(ToVec(eye), ToVec(centre), cv::Vec3d(0, 0, -1));
}

}  // namespace

ScenePainter::ScenePainter(cv::viz::Viz3d* window, const config::Scene& scene,
                           Matrix3Xd rest_positions_m, fem::EmbeddedSurface visual_surface,
                           const PainterOptions& options)
    : window_(window),
      scene_(scene),
      rest_positions_m_(std::move(rest_positions_m)),
      visual_(std::move(visual_surface)),
      num_scene_nodes_(static_cast<int>(rest_positions_m_.cols())),
      options_(options) {
  // A visual surface that does not fit the body drawn (another scene's) is not used.
  if (!visual_.empty() && visual_.nodes.maxCoeff() >= rest_positions_m_.cols())
    visual_ = fem::EmbeddedSurface();
  if (!visual_.empty())
    fem::CalcEmbeddedPositions(visual_, rest_positions_m_.reshaped(), &visual_rest_m_);
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
    object_meshes_.push_back(MakeShapeMesh(object.shape));
    box.extend(contact::CalcWorldBox(object));
  }
  if (scene.tool) {
    const double radius_m = contact::ToolDistanceField(scene.tool->model.shape).bounding_radius_m();
    box.extend(scene.tool->initial_state.x_W_m + Eigen::Vector3d::Constant(radius_m));
    box.extend(scene.tool->initial_state.x_W_m - Eigen::Vector3d::Constant(radius_m));
  }
  window_->setViewerPose(MakeCameraPose(box, options_.side_camera));
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
    tool_mesh_ = MakeShapeMesh(scene.tool->model.shape);
    ghost_widget_ = MakeShapeWidget(InflateShape(scene.tool->model.shape, 0.03), kGhost, true);
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
  if (!visual_.empty() && frame.num_nodes == num_scene_nodes_)
    fem::CalcEmbeddedPositions(visual_, rest_positions_m_.reshaped(), &visual_rest_m_);
}

void ScenePainter::DrawBody(const hapsim_lcm::sim_frame_t& frame) {
  const int num_nodes = frame.num_nodes;
  if (num_nodes == 0 || frame.num_triangles == 0) return;
  Eigen::VectorXd x_nodes_m(3 * num_nodes);
  for (int n = 0; n < num_nodes; ++n)
    for (int d = 0; d < 3; ++d) x_nodes_m[3 * n + d] = frame.positions_W_m[n][d];
  // The points drawn and where they were at the displacement reference (empty: unknown).
  Eigen::VectorXd x_points_m, rest_points_m;
  if (!visual_.empty() && num_nodes == num_scene_nodes_) {  // not another scene's frame
    fem::CalcEmbeddedPositions(visual_, x_nodes_m, &x_points_m);
    rest_points_m = visual_rest_m_;
    body_triangles_ = visual_.triangles;
  } else {
    x_points_m = x_nodes_m;
    if (rest_positions_m_.cols() == num_nodes) rest_points_m = rest_positions_m_.reshaped();
    body_triangles_.resize(3, frame.num_triangles);
    for (int f = 0; f < frame.num_triangles; ++f)
      for (int k = 0; k < 3; ++k) body_triangles_(k, f) = frame.triangles[f][k];
  }
  const int num_points = static_cast<int>(x_points_m.size() / 3);
  body_points_W_m_ = x_points_m.reshaped(3, num_points);
  const bool has_rest = rest_points_m.size() == x_points_m.size();

  cv::viz::Mesh mesh;
  mesh.cloud.create(1, num_points, CV_32FC3);
  mesh.colors.create(1, num_points, CV_8UC3);
  for (int p = 0; p < num_points; ++p) {
    const Eigen::Vector3d x_m = x_points_m.segment<3>(3 * p);
    mesh.cloud.at<cv::Vec3f>(0, p) = cv::Vec3f(x_m.x(), x_m.y(), x_m.z());
    // Colour: the tissue tone at rest, blending linearly into a deep red at displacement_scale_m.
    const double u_m = has_rest ? (x_m - rest_points_m.segment<3>(3 * p)).norm() : 0.0;
    const double a = std::clamp(u_m / options_.displacement_scale_m, 0.0, 1.0);
    cv::Vec3b c;
    for (int k = 0; k < 3; ++k) c[k] = static_cast<uchar>((1.0 - a) * kTissue[k] + a * kDeepRed[k]);
    mesh.colors.at<cv::Vec3b>(0, p) = c;
  }
  // Area-weighted vertex normals: smooth (Phong) shading instead of a facet per triangle.
  const int num_triangles = static_cast<int>(body_triangles_.cols());
  mesh.polygons.create(1, 4 * num_triangles, CV_32SC1);
  mesh.normals = cv::Mat::zeros(1, num_points, CV_32FC3);
  for (int f = 0; f < num_triangles; ++f) {
    mesh.polygons.at<int>(0, 4 * f) = 3;
    const Eigen::Vector3i t = body_triangles_.col(f);
    for (int k = 0; k < 3; ++k) mesh.polygons.at<int>(0, 4 * f + 1 + k) = t[k];
    const cv::Vec3f a = mesh.cloud.at<cv::Vec3f>(0, t[0]), b = mesh.cloud.at<cv::Vec3f>(0, t[1]),
                    c = mesh.cloud.at<cv::Vec3f>(0, t[2]);
    const cv::Vec3f area_normal = (b - a).cross(c - a);  // twice the area, outward
    for (int k = 0; k < 3; ++k) mesh.normals.at<cv::Vec3f>(0, t[k]) += area_normal;
  }
  for (int p = 0; p < num_points; ++p) {
    cv::Vec3f& normal = mesh.normals.at<cv::Vec3f>(0, p);
    const float length = static_cast<float>(cv::norm(normal));
    if (length > 0.0f) normal /= length;
  }
  cv::viz::WMesh widget(mesh);
  widget.setRenderingProperty(cv::viz::SHADING, cv::viz::SHADING_PHONG);
  Show("body", widget);
}

std::string ScenePainter::DrawDepthCue(const hapsim_lcm::sim_frame_t& frame) {
  if (!scene_.tool || tool_mesh_.vertices_m.cols() == 0) return "";
  // The line starts under the tool's centre, on the tool's own lower surface (a probe's tip, the
  // middle of a lying scope's underside).
  const Eigen::Isometry3d X_WT = ToIsometry(frame.x_W_m, frame.q_WT);
  const Matrix3Xd tool_W_m = X_WT * tool_mesh_.vertices_m;
  const Eigen::Vector3d down_W(0.0, 0.0, -1.0);
  const double inside_m = CastRay(X_WT.translation(), down_W, tool_W_m, tool_mesh_.triangles);
  const Eigen::Vector3d start_W_m =
      X_WT.translation() + (std::isfinite(inside_m) ? inside_m : 0.0) * down_W;
  std::vector<DropSurface> surfaces;
  if (body_points_W_m_.cols() > 0)
    surfaces.push_back({scene_.more_bodies.empty() ? scene_.body_name : "tissue", &body_points_W_m_,
                        &body_triangles_, Eigen::Isometry3d::Identity()});
  const bool objects_posed = frame.num_objects == static_cast<int>(scene_.rigid_objects.size());
  for (size_t i = 0; i < scene_.rigid_objects.size(); ++i) {
    if (objects_posed && static_cast<int>(i) == frame.grabbed_object) continue;  // the tool's
    const Eigen::Isometry3d X_WO =
        objects_posed ? ToIsometry(frame.object_x_W_m[i].data(), frame.object_q_WO[i].data())
                      : scene_.rigid_objects[i].object.X_WO;
    surfaces.push_back({scene_.rigid_objects[i].object.name, &object_meshes_[i].vertices_m,
                        &object_meshes_[i].triangles, X_WO});
  }
  const DropHit hit = CastDropLine(start_W_m, surfaces);
  if (!std::isfinite(hit.distance_m)) {
    Hide("drop_line");
    Hide("drop_ring");
    return "depth: nothing below the tool";
  }
  Show("drop_line", cv::viz::WLine(ToVec(hit.from_W_m), ToVec(hit.to_W_m), kDropLine));
  // A ring a little above the surface hit, the size of the tool's footprint, as its shadow.
  const double radius_m =
      0.5 * (tool_W_m.rowwise().maxCoeff() - tool_W_m.rowwise().minCoeff()).head<2>().maxCoeff();
  cv::viz::WCircle ring(std::max(radius_m, 1e-4), 0.1 * std::max(radius_m, 1e-4), kDropLine);
  Show("drop_ring", ring,
       cv::Affine3d(cv::Matx33d::eye(), ToVec(hit.to_W_m + Eigen::Vector3d(0.0, 0.0, 1e-4))));
  char line[160];
  std::snprintf(line, sizeof(line), "depth: %.1f mm above the %s", 1e3 * hit.distance_m,
                hit.name.c_str());
  return line;
}

void ScenePainter::DrawGauge(const ViewState& state, const std::string& depth_line) {
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
  if (!depth_line.empty()) text += "\n" + depth_line;
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
    // The points the grasper's jaws hold, larger and in the grabbed colour.
    if (frame.num_grasped > 0 && frame.num_grasped <= frame.num_nodes) {
      cv::Mat held(1, frame.num_grasped, CV_64FC3);
      for (int i = 0; i < frame.num_grasped; ++i) {
        const std::vector<float>& p = frame.positions_W_m[frame.grasped_nodes[i]];
        held.at<cv::Vec3d>(0, i) = cv::Vec3d(p[0], p[1], p[2]);
      }
      cv::viz::WCloud cloud(held, kGrabbed);
      cloud.setRenderingProperty(cv::viz::POINT_SIZE, 9.0);
      Show("grasped", cloud);
    } else {
      Hide("grasped");
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
  const std::string depth_line = state.has_frame ? DrawDepthCue(state.frame) : "";
  if (!options_.side_camera) DrawGauge(state, depth_line);  // the side view is an inset
}

}  // namespace hapsim::view
