// SPDX-License-Identifier: BSD-3-Clause
// The numerical core of the muscle deformation (Kellnhofer & Kohout, after
// Huang et al. 2006): least squares |L X - b|^2 on the hull points X with the
// enclosed volume held, by Gauss-Newton steps with a Lagrange multiplier.
#pragma once

#include "Common/MeshTypes.h"

#include <Eigen/Cholesky>
#include <Eigen/SparseCore>

#include <optional>

namespace md
{
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

/// Cotangent Laplacian of a closed triangle mesh: row i has -1 on the
/// diagonal and c_ij / sum_k c_ik for each neighbour j, c_ij = cot(alpha) +
/// cot(beta) of the two angles facing edge ij. Where a point's cotangent sum is
/// not positive (degenerate triangles) its row falls back to uniform weights.
///
/// With `largestCotangent`, each angle's cotangent is taken within [0, largestCotangent]
/// (angles over 90 degrees count as right angles, angles under acot(largestCotangent) as that
/// angle), for a scanned surface's badly shaped triangles: an obtuse angle's negative weight
/// lets a point cross its neighbours, and a sliver's tiny angle gives its short edge a weight
/// that ties the edge's two points to each other and hardly to anything else, so that the pair
/// turns its triangles over (the LHDL gluteus medius, docs/DESIGN.md section 7). Clamping is
/// continuous in the points, so the weights still move continuously with the input.
SparseMatrix CotangentLaplacian(const TriangleMesh& mesh, std::optional<double> largestCotangent = std::nullopt);

/// V = 1/6 sum over triangles (x_a x x_b) . x_c, and dV/dx_i (one row per point).
double EnclosedVolume(const Points& points, const Triangles& triangles, Points* gradient = nullptr);

/// Solves min |L X - b|^2 subject to V(X) = V0 step by step. A = (L^T L)^-1 is
/// factored once (L must have full column rank: the Laplacian rows alone do
/// not, a translation costs them nothing; rows fixing positions, such as
/// action-line rows, give it). L^T L is factored dense: the action-line rows
/// are mean value coordinates, which weigh every hull point, so it is dense
/// anyway.
class VolumeConstrainedSolver
{
public:
  VolumeConstrainedSolver(const SparseMatrix& rows, const Triangles& triangles);
  /// The system of `base` with `extraRows` (dense, one column per hull point)
  /// appended: its normal matrix is updated, not rebuilt from all the rows.
  VolumeConstrainedSolver(const VolumeConstrainedSolver& base, const Eigen::MatrixXd& extraRows);

  /// One step of length alpha in (0, 1] from X, with r = L X - b, J = dV/dX,
  /// c = V(X) - V0:
  ///   lambda = (J A J^T)^-1 (c / alpha - J A L^T r),  h = -alpha A (L^T r + J^T lambda),
  /// so that the linearised volume after the step is exactly V0. (The original
  /// implementation had the sign of the J A L^T r term wrong; its volume then
  /// settles at an error proportional to alpha.)
  Points Step(const Points& x, const Points& targets, double targetVolume, double alpha) const;

  /// The step with the volume measured by the caller (the fine phase measures
  /// it on the full mesh): c = V - V0 and J = dV/dX. An empty J means no
  /// volume constraint (lambda = 0).
  Points Step(
    const Points& x, const Points& targets, double volumeError, const Points& volumeGradient, double alpha) const;

  SparseMatrix Rows;
  Triangles Faces;
  Eigen::MatrixXd NormalMatrix; ///< L^T L, undamped
  Eigen::LDLT<Eigen::MatrixXd> Normal;

private:
  void AddToNormal(const Eigen::MatrixXd& rows); ///< NormalMatrix += rows^T rows, then Factor
  void Factor();                                 ///< Normal from NormalMatrix; throws InputError when singular
};
}
