// SPDX-License-Identifier: BSD-3-Clause
#include "Settle/ActiveSet.h"

#include <Eigen/Cholesky>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

namespace md
{
namespace
{
/// The largest residual of a sparse solve of the dual system, a fraction of its right-hand side,
/// that SolveNudged keeps: over gait2392's first frame the sparse and the dense factorisation
/// both left residuals from 1e-17 to 4e-10 of it, within 4 times of each other.
constexpr double kSparseResidual = 1e-8;
/// The fewest rows SolveNudged factorises sparse: below, the sparse ordering costs more than the
/// dense factorisation saves (the LHDL hip's systems have 10 to 235 rows, 34 at the median;
/// factorised sparse, hip_flexion took 160 ms a frame where dense took 144).
constexpr Eigen::Index kSparseFrom = 256;

/// The multipliers of the dual system `system` y = `rhs` whose first slack.size() rows are
/// contacts (inequalities: a multiplier pushes or is zero) and the rest equalities (the
/// volumes), by a primal-dual active set starting from `active` (and left as the final set): an
/// active contact whose multiplier pulls lets go; an inactive one joins when its residual
/// (a_j . x - target at the new points) is below -slack[j]. One block of SolveActiveSet.
Eigen::VectorXd SolveBlockActiveSet(const Eigen::MatrixXd& system, const Eigen::VectorXd& rhs,
  const std::vector<double>& slack, std::vector<char>& active)
{
  const Eigen::Index size = system.rows(), nc = static_cast<Eigen::Index>(slack.size());
  Eigen::VectorXd multipliers = Eigen::VectorXd::Zero(size);
  for (int round = 0; round < 100; ++round)
  {
    std::vector<Eigen::Index> on;
    for (Eigen::Index k = 0; k < size; ++k)
    {
      if (active[k])
      {
        on.push_back(k);
      }
    }
    multipliers.setZero();
    multipliers(on) = SolveNudged(system(on, on), rhs(on));
    const Eigen::VectorXd residual = system * multipliers - rhs; // a_j . x - target, at the new x
    bool changed = false;
    for (Eigen::Index j = 0; j < nc; ++j)
    {
      const bool want = active[j] ? multipliers(j) > 0 : residual(j) < -slack[static_cast<size_t>(j)];
      if (want != static_cast<bool>(active[j]))
      {
        active[j] = want;
        changed = true;
      }
    }
    if (!changed)
    {
      break;
    }
  }

  return multipliers;
}

}

Eigen::VectorXd SolveNudged(const Eigen::MatrixXd& system, const Eigen::VectorXd& right)
{
  Eigen::MatrixXd nudged = system;
  nudged.diagonal() += 1e-12 * system.diagonal().cwiseAbs();
  // The nudged factor's solution, refined against `matrix` (the system itself, sparse or dense).
  auto refined = [&](const auto& factor, const auto& matrix) {
    Eigen::VectorXd solved = factor.solve(right);
    for (int refine = 0; refine < 3; ++refine)
    {
      solved += factor.solve(right - matrix * solved);
    }
    return solved;
  };
  if (system.rows() >= kSparseFrom)
  {
    const Eigen::SparseMatrix<double> sparse = system.sparseView();
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor(nudged.sparseView());
    if (factor.info() == Eigen::Success)
    {
      Eigen::VectorXd solved = refined(factor, sparse);
      const double residual = (sparse * solved - right).norm();
      if (std::isfinite(residual) && residual <= kSparseResidual * right.norm())
      {
        return solved;
      }
    }
  }
  return refined(Eigen::LDLT<Eigen::MatrixXd>(nudged), system);
}

std::vector<std::vector<Eigen::Index>> UnlinkedBlocks(const Eigen::MatrixXd& system)
{
  const Eigen::Index size = system.rows();
  std::vector<Eigen::Index> root(static_cast<size_t>(size));
  std::iota(root.begin(), root.end(), Eigen::Index(0));
  auto rootOf = [&](Eigen::Index k) {
    while (root[k] != k)
    {
      k = root[k] = root[root[k]];
    }
    return k;
  };
  for (Eigen::Index l = 0; l < size; ++l)
  {
    for (Eigen::Index j = l + 1; j < size; ++j)
    {
      if (system(j, l) != 0)
      {
        const Eigen::Index a = rootOf(j), b = rootOf(l);
        root[std::max(a, b)] = std::min(a, b);
      }
    }
  }
  std::map<Eigen::Index, std::vector<Eigen::Index>> byRoot;
  for (Eigen::Index k = 0; k < size; ++k)
  {
    byRoot[rootOf(k)].push_back(k);
  }
  std::vector<std::vector<Eigen::Index>> blocks;
  for (auto& [first, rows] : byRoot)
  {
    blocks.push_back(std::move(rows));
  }
  std::stable_sort(blocks.begin(), blocks.end(), [](const auto& a, const auto& b) { return a.size() > b.size(); });
  return blocks;
}

Eigen::VectorXd SolveActiveSet(const Eigen::MatrixXd& system, const Eigen::VectorXd& rhs,
  const std::vector<double>& slack, std::vector<char>& active)
{
  const Eigen::Index nc = static_cast<Eigen::Index>(slack.size());
  const std::vector<std::vector<Eigen::Index>> blocks = UnlinkedBlocks(system);
  Eigen::VectorXd multipliers = Eigen::VectorXd::Zero(system.rows());
#pragma omp parallel for schedule(dynamic, 1)
  for (int b = 0; b < static_cast<int>(blocks.size()); ++b)
  {
    const std::vector<Eigen::Index>& rows = blocks[static_cast<size_t>(b)];
    std::vector<double> partSlack;
    std::vector<char> partActive;
    for (const Eigen::Index row : rows)
    {
      partActive.push_back(active[row]);
      if (row < nc)
      {
        partSlack.push_back(slack[row]);
      }
    }
    multipliers(rows) = SolveBlockActiveSet(system(rows, rows), rhs(rows), partSlack, partActive);
    for (size_t r = 0; r < rows.size(); ++r)
    {
      active[rows[r]] = partActive[r];
    }
  }
  return multipliers;
}
}
