#pragma once
// The structure of a supernodal CHOLMOD factor A = Pᵀ L Lᵀ P, copied out of it, for the
// reduced-precision copies of L (fem/single_precision_factor.h, fem/half_precision_factor.h) and
// the exact compliance's sweeps on CHOLMOD's own values (fem/inverse_quadratic_form.h).
//
// Layout (CHOLMOD's supernodal factor, read as documented in cholmod_core.h): supernode s holds
// columns super[s] .. super[s+1]−1 of L as a dense column-major block of nsrow = pi[s+1] − pi[s]
// rows at x[px[s]]; its first nscol rows are the diagonal block (lower triangular), the rest are
// the rows s[pi[s] + nscol ..], below it.

#include <cholmod.h>

#include <vector>

namespace hapsim::fem {

struct SupernodalLayout {
  std::vector<int> super, pi, px, s, perm;
  std::vector<int> parent;               // the supernodal elimination tree: −1 at a root
  std::vector<int> supernode_of_column;  // by permuted index
  std::vector<int> permuted_index;       // of each original index: perm[permuted_index[i]] = i
  int max_rows_below = 0;  // the most rows below any diagonal block (CHOLMOD's maxesize)
  int max_rows = 0;        // the most rows of any supernode, its diagonal block's and those below

  // Copies the structure of L (supernodal, LLᵀ, real, double, int indices). Throws
  // std::invalid_argument for any other kind of factor.
  void Assign(const cholmod_factor& L);

  bool empty() const { return super.empty(); }
  int num_supernodes() const { return static_cast<int>(super.size()) - 1; }
  int size() const { return static_cast<int>(perm.size()); }
  // Supernode sn: its first column, its columns, its rows (the diagonal block's and those below),
  // and the rows below as indices into the permuted vector.
  int first_column(int sn) const { return super[sn]; }
  int num_columns(int sn) const { return super[sn + 1] - super[sn]; }
  int num_rows(int sn) const { return pi[sn + 1] - pi[sn]; }
  const int* rows_below(int sn) const { return s.data() + pi[sn] + num_columns(sn); }
};

}  // namespace hapsim::fem
