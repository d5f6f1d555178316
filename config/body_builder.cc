#include "config/body_builder.h"

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <stdexcept>

#include "config/surface_mesh_cache.h"
#include "contact/body_body_contacts.h"
#include "contact/rigid_objects.h"
#include "core/error.h"
#include "core/triangle_mesh_io.h"
#include "fem/curved_boundary.h"
#include "fem/lattice_mesher.h"
#include "fem/mesh_io.h"
#include "fem/time_stepper.h"

namespace hapsim::config {
namespace {

// Rest positions within this distance of a box face count as inside (round-off in lattices).
constexpr double kBoxTolerance_m = 1e-9;

[[noreturn]] void Fail(const SourceLocation& where, const std::string& message) {
  throw InputError(where.file, where.line, where.key, message);
}

fem::SurfaceMeshOptions MakeSurfaceMeshOptions(const MeshSource& source) {
  fem::SurfaceMeshOptions options;
  options.cell_size_m = source.cell_size_m;
  if (source.refine_cell_size_m > 0.0) {
    options.refine_near_m = {source.refine_near_m};
    options.refine_cell_size_m = source.refine_cell_size_m;
    options.refine_radius_m = source.refine_radius_m;
  }
  return options;
}

fem::TetMesh MakeMesh(const MeshSource& source) {
  try {
    switch (source.kind) {
      case MeshSource::Kind::kBox:
        // The uniform lattice, bit for bit as before grading.
        if (source.grading_ratio == 1.0 && source.grading_circle_radius_m == 0.0)
          return fem::MakeBoxTetMesh(source.box.min_m, source.box.max_m, source.cells);
        return fem::MakeGradedBoxTetMesh(source.box.min_m, source.box.max_m, source.cells,
                                         source.grading_focus_m, source.grading_ratio,
                                         source.grading_circle_radius_m);
      case MeshSource::Kind::kEllipsoid: {
        // A lattice of an even number of cells centred on the ellipsoid, with a margin: the
        // five-tet cut is then mirror-symmetric about the centre, so is the mesh.
        const Eigen::Vector3d half_m =
            (1.05 * source.radii_m / source.cell_size_m).array().ceil() * source.cell_size_m;
        return fem::MakeImplicitTetMesh(fem::MakeEllipsoidFunction(source.center_m, source.radii_m),
                                        source.center_m - half_m, source.center_m + half_m,
                                        source.cell_size_m);
      }
      case MeshSource::Kind::kFile: {
        fem::TetMesh mesh = fem::ReadTetMesh(source.file);  // its errors name the file and line
        source.transform.Apply(&mesh.rest_positions_m);
        return mesh;
      }
      case MeshSource::Kind::kSurface:         // its errors name the surface file
        return MeshSurfaceFile(source.file, MakeSurfaceMeshOptions(source), source.transform).mesh;
    }
  } catch (const std::invalid_argument& error) {
    Fail(source.location, error.what());
  }
  Fail(source.location, "unknown mesh source");
}

// A surface file bound to the tets of `mesh`; errors name the scene key and the surface file.
fem::EmbeddedSurface EmbedSurfaceFile(const EmbeddedSurfaceSource& source,
                                      const fem::TetMesh& mesh) {
  TriangleMesh surface = ReadTriangleMesh(source.file);  // its errors name the file and line
  source.transform.Apply(&surface.vertices_m);
  try {
    return fem::EmbedSurface(mesh, surface.vertices_m, surface.triangles,
                             fem::CalcDefaultMaxOutsideDistance(mesh));
  } catch (const std::invalid_argument& error) {
    Fail(source.location, source.file + ": " + error.what());
  }
}

// Quadratic tets cut from a `surface:` file: their boundary edge nodes onto that surface
// (fem/curved_boundary.h), so the body is as round as the surface, not its linear facets.
void CurveOntoSurfaceFile(const MeshSource& source, fem::TetMesh* mesh) {
  TriangleMesh surface = ReadTriangleMesh(source.file);
  source.transform.Apply(&surface.vertices_m);
  const fem::CurvedBoundaryReport report =
      fem::MoveBoundaryEdgeNodesOntoSurface(surface.vertices_m, surface.triangles, mesh);
  if (report.num_kept > 0)
    std::cerr << source.location.file << ':' << source.location.line
              << ": warning: " << report.num_kept << " of " << report.num_boundary_edge_nodes
              << " boundary edge nodes stay on their straight edges: moving them onto "
              << source.file
              << " would fold or nearly fold a tet, or move them more than a quarter of their "
              << "edge; a smaller cell_size_m curves them too\n";
}

}  // namespace

Body MakeBody(const BodyScene& scene, const Eigen::Vector3d& gravity_m_s2) {
  fem::TetMesh mesh = MakeMesh(scene.mesh);
  if (scene.quadratic) {
    mesh = fem::MakeQuadraticMesh(mesh);
    if (scene.mesh.kind == MeshSource::Kind::kSurface) CurveOntoSurfaceFile(scene.mesh, &mesh);
  }
  std::vector<int> fixed_nodes;
  if (scene.fixed) {
    fixed_nodes =
        fem::FindNodesInBox(mesh, scene.fixed->min_m, scene.fixed->max_m, kBoxTolerance_m);
    if (fixed_nodes.empty())
      Fail(scene.fixed_location, "the fixed box holds no node of the mesh (" +
                                     std::to_string(mesh.num_nodes()) + " nodes)");
  }
  Body body;
  body.model = fem::MakeModel(std::move(mesh), scene.material, fixed_nodes);
  if (scene.collision_surface)
    body.model.collision_surface = EmbedSurfaceFile(*scene.collision_surface, body.model.mesh);
  if (scene.visual_surface)
    body.visual_surface = EmbedSurfaceFile(*scene.visual_surface, body.model.mesh);
  body.parts = {{0, body.model.num_nodes(), 0, body.model.num_tets()}};
  body.external_force_N = fem::CalcGravityForce(body.model, gravity_m_s2);
  for (const NodalLoad& load : scene.loads) {
    const std::vector<int> nodes =
        fem::FindNodesInBox(body.model.mesh, load.region.min_m, load.region.max_m, kBoxTolerance_m);
    if (nodes.empty()) Fail(load.location, "the load box holds no node of the mesh");
    for (int n : nodes)
      body.external_force_N.segment<3>(3 * n) += load.total_force_N / nodes.size();
  }
  for (const Probe& probe : scene.probes) {
    const std::optional<fem::ProbeBinding> binding = fem::BindProbe(body.model, probe.position_m);
    if (!binding) Fail(probe.location, "probe '" + probe.name + "' lies outside the body");
    body.probes.push_back({probe.name, *binding});
  }
  return body;
}

namespace {

// Deformable objects that start overlapping would be thrust apart by their contact rows in the
// first frames (β of the overlap a frame, at the stiffness of both): a scene error, named with
// both objects, at the later one's entry. Overlaps under 0.1 mm (a mesh's facets against
// another's curved surface) are let be.
void CheckObjectsStartApart(const Scene& scene, const Body& body) {
  constexpr double kTolerance_m = 1e-4;
  const contact::BodyBodyContacts objects(body.model, scene.contact.margin_m);
  const std::optional<contact::BodyBodyContacts::Overlap> overlap =
      objects.FindDeepestOverlap(body.model.rest_positions_m, kTolerance_m);
  if (!overlap) return;
  // The objects are the merged models, in scene order (fem::Model::object_first_nodes).
  const auto name_of = [&](int object) {
    return object == 0 ? scene.body_name : scene.more_bodies[object - 1].name;
  };
  const int inside = overlap->node_object, around = overlap->face_object;
  const DeformableObjectScene& later = scene.more_bodies[std::max(inside, around) - 1];
  char depth[32];
  std::snprintf(depth, sizeof(depth), "%.2f mm", 1e3 * overlap->depth_m);
  throw InputError(later.location.file, later.location.line, later.location.key,
                   "deformable objects '" + name_of(inside) + "' and '" + name_of(around) +
                       "' start interpenetrating: a node of '" + name_of(inside) + "' lies " +
                       depth + " inside '" + name_of(around) +
                       "' (move one apart; they touch through contact)");
}

// A dynamic object that starts inside another object or the tissue would be pushed out by the
// stabilisation from its first frame, as if shot: a scene error at its entry naming both (over
// 0.1 mm deep). Fixed and scripted objects may overlap each other: they never move apart.
void CheckDynamicObjectsStartFree(const Scene& scene, const Body* body) {
  constexpr double kTolerance_m = 1e-4;
  std::vector<contact::RigidObject> objects;
  bool any_dynamic = false;
  for (const RigidObjectScene& rigid : scene.rigid_objects) {
    objects.push_back(rigid.object);
    any_dynamic = any_dynamic || rigid.object.dynamic;
  }
  if (!any_dynamic || !scene.tool) return;  // rigid objects without a tool: refused elsewhere
  const contact::RigidObjectContacts placed(objects, scene.tool->model.shape, 0.0);
  std::vector<contact::Contact> found;
  placed.AddObjectContacts(&found);
  if (body != nullptr) {
    const Eigen::Isometry3d still = Eigen::Isometry3d::Identity();  // no tool motion, no sweep
    placed.AddBodyContacts(fem::FindFreeSurfaceNodes(body->model), body->model.rest_positions_m,
                           body->model.rest_positions_m, still, still, &found);
  }
  const contact::Contact* deepest = nullptr;
  for (const contact::Contact& contact : found)
    if (objects[contact.rigid_object].dynamic && contact.gap_m < -kTolerance_m &&
        (deepest == nullptr || contact.gap_m < deepest->gap_m))
      deepest = &contact;
  if (deepest == nullptr) return;
  std::string other = "the tissue";
  if (deepest->other_object >= 0) {
    other = "'" + objects[deepest->other_object].name + "'";
  } else if (body != nullptr) {  // the deformable object of the node
    const std::vector<int>& first = body->model.object_first_nodes;
    const int object = static_cast<int>(
        std::upper_bound(first.begin(), first.end(), deepest->nodes[0]) - first.begin() - 1);
    other = "'" + (object <= 0 ? scene.body_name : scene.more_bodies[object - 1].name) + "'";
  }
  const SourceLocation& where = scene.rigid_objects[deepest->rigid_object].location;
  char depth[32];
  std::snprintf(depth, sizeof(depth), "%.2f mm", -1e3 * deepest->gap_m);
  Fail(where, "the dynamic object '" + objects[deepest->rigid_object].name + "' and " + other +
                  " start interpenetrating, " + depth +
                  " deep (move it apart: it would be pushed out at its first frame)");
}

// The deformable objects as one body (several: one system of them).
std::optional<Body> MakeDeformableBody(const Scene& scene) {
  if (!scene.body) return std::nullopt;
  Body first = MakeBody(*scene.body, scene.gravity_m_s2);
  if (scene.more_bodies.empty()) return first;
  // One system of all the deformable objects: models side by side, forces stacked, probes moved
  // to their tets' new indices.
  std::vector<Body> bodies;
  bodies.push_back(std::move(first));
  for (const DeformableObjectScene& more : scene.more_bodies)
    bodies.push_back(MakeBody(more.body, scene.gravity_m_s2));
  std::vector<fem::Model> models;
  for (const Body& body : bodies) models.push_back(body.model);
  Body merged;
  merged.model = fem::MergeModels(models);  // damping checked equal when the scene was read
  merged.external_force_N.resize(merged.model.num_dofs());
  std::vector<fem::EmbeddedSurface> visual_surfaces;
  std::vector<Matrix3Xi> boundaries;
  std::vector<int> first_nodes;
  int node = 0, tet = 0;
  for (const Body& body : bodies) {
    visual_surfaces.push_back(body.visual_surface);
    boundaries.push_back(body.model.surface_triangles);
    first_nodes.push_back(node);
    merged.external_force_N.segment(3 * node, body.model.num_dofs()) = body.external_force_N;
    for (BoundProbe probe : body.probes) {
      probe.binding.tet += tet;
      merged.probes.push_back(probe);
    }
    merged.parts.push_back({node, body.model.num_nodes(), tet, body.model.num_tets()});
    node += body.model.num_nodes();
    tet += body.model.num_tets();
  }
  merged.visual_surface = fem::MergeEmbeddedSurfaces(visual_surfaces, boundaries, first_nodes);
  CheckObjectsStartApart(scene, merged);
  return merged;
}

}  // namespace

std::optional<Body> MakeSceneBody(const Scene& scene) {
  std::optional<Body> body = MakeDeformableBody(scene);
  CheckDynamicObjectsStartFree(scene, body ? &*body : nullptr);
  return body;
}

}  // namespace hapsim::config
