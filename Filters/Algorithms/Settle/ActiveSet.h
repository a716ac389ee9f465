// SPDX-License-Identifier: BSD-3-Clause
// The dual system of a settle's iteration (SurfaceSettle.cxx) solved: S y = rhs, S_jl =
// a_j . K^-1 a_l over the contacts' rows (inequalities: a contact pushes or lets go), then the
// samples let go and the volumes (equalities), by a primal-dual active set. The muscles that no
// contact joins are independent blocks, solved apart; each block's factorisation is sparse.
#pragma once

#include <Eigen/Core>

#include <vector>

namespace md
{
/// The multipliers y of `system` y = `rhs`, whose first slack.size() rows are contacts and the
/// rest equalities, by a primal-dual active set started from `active` and left as the final set:
/// an active contact whose multiplier pulls (y_j <= 0) lets go, an inactive one joins when its
/// residual ((system y - rhs)_j, the gap at the new points) is below -slack[j]; 100 rounds at
/// most. Block by block (UnlinkedBlocks), in parallel, each block's rows in their order: a
/// system of one block is solved as a whole.
Eigen::VectorXd SolveActiveSet(const Eigen::MatrixXd& system, const Eigen::VectorXd& rhs,
  const std::vector<double>& slack, std::vector<char>& active);

/// The blocks of the symmetric `system` that no nonzero entry links, each its rows in increasing
/// order, the largest first (of equal sizes, the one with the lowest first row first).
std::vector<std::vector<Eigen::Index>> UnlinkedBlocks(const Eigen::MatrixXd& system);

/// The solution y of the symmetric `system` y = `right`, singular where two contacts push a
/// point the same way: a nudge of 1e-12 of each diagonal entry picks the smallest multipliers,
/// and three rounds of refinement take the nudge's error out of the rest. A system of 256 rows or
/// more is factorised sparse (simplicial LDL^T, no pivoting: a contact links only the rows of its
/// muscles, and gait2392's block of about 950 rows is 5 % full, its factor as sparse, 5 ms where the
/// dense one took 50); a smaller one, or one whose sparse factorisation meets a zero pivot or
/// leaves a residual beyond 1e-8 of the right-hand side, by a dense LDL^T with pivoting.
Eigen::VectorXd SolveNudged(const Eigen::MatrixXd& system, const Eigen::VectorXd& right);
}
