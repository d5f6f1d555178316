#include "fem/quarter_point_nodes.h"

#include <stdexcept>

#include "fem/quadratic_tet.h"

namespace hapsim::fem {

int MoveEdgeNodesToQuarterPoints(const std::vector<bool>& singular, double fraction,
                                 TetMesh* mesh) {
  if (!mesh->is_quadratic())
    throw std::invalid_argument("quarter-point edge nodes need a quadratic mesh");
  if (singular.size() != static_cast<size_t>(mesh->num_nodes()))
    throw std::invalid_argument("quarter-point edge nodes: one singular flag per node needed");
  if (!(fraction >= 0.25 && fraction <= 0.5))
    throw std::invalid_argument("quarter-point edge nodes: the fraction must be in [1/4, 1/2]");
  std::vector<bool> moved(static_cast<size_t>(mesh->num_nodes()), false);
  int num_moved = 0;
  for (int t = 0; t < mesh->num_tets(); ++t)
    for (int k = 0; k < 6; ++k) {
      const int a = mesh->tets(kP2EdgeCorners[k][0], t), b = mesh->tets(kP2EdgeCorners[k][1], t);
      if (singular[static_cast<size_t>(a)] == singular[static_cast<size_t>(b)]) continue;
      const int from = singular[static_cast<size_t>(a)] ? a : b, to = from == a ? b : a;
      const int node = mesh->edge_nodes(k, t);
      if (moved[static_cast<size_t>(node)]) continue;  // from another tet around the edge
      mesh->rest_positions_m.col(node) =
          mesh->rest_positions_m.col(from) +
          fraction * (mesh->rest_positions_m.col(to) - mesh->rest_positions_m.col(from));
      moved[static_cast<size_t>(node)] = true;
      ++num_moved;
    }
  return num_moved;
}

}  // namespace hapsim::fem
