#include "fem/supernodal_layout.h"

#include <algorithm>
#include <stdexcept>

namespace hapsim::fem {
namespace {

std::vector<int> CopyInts(const void* data, size_t size) {
  const int* begin = static_cast<const int*>(data);
  return std::vector<int>(begin, begin + size);
}

}  // namespace

void SupernodalLayout::Assign(const cholmod_factor& L) {
  if (!L.is_super || !L.is_ll || L.xtype != CHOLMOD_REAL || L.dtype != CHOLMOD_DOUBLE ||
      L.itype != CHOLMOD_INT)
    throw std::invalid_argument("SupernodalLayout needs a real supernodal LLᵀ factor");
  super = CopyInts(L.super, L.nsuper + 1);
  pi = CopyInts(L.pi, L.nsuper + 1);
  px = CopyInts(L.px, L.nsuper + 1);
  s = CopyInts(L.s, L.ssize);
  perm = CopyInts(L.Perm, L.n);
  max_rows_below = static_cast<int>(L.maxesize);
  max_rows = 0;
  for (size_t sn = 0; sn + 1 < pi.size(); ++sn) max_rows = std::max(max_rows, pi[sn + 1] - pi[sn]);
  supernode_of_column.resize(perm.size());
  for (int sn = 0; sn < num_supernodes(); ++sn)
    for (int k = super[sn]; k < super[sn + 1]; ++k) supernode_of_column[k] = sn;
  // A supernode's parent holds the first row below its diagonal block (the rows are sorted).
  parent.assign(num_supernodes(), -1);
  for (int sn = 0; sn < num_supernodes(); ++sn)
    if (num_rows(sn) > num_columns(sn)) parent[sn] = supernode_of_column[rows_below(sn)[0]];
  permuted_index.resize(perm.size());
  for (int k = 0; k < size(); ++k) permuted_index[perm[k]] = k;
}

}  // namespace hapsim::fem
