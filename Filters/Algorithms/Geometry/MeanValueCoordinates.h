// SPDX-License-Identifier: BSD-3-Clause
// Mean value coordinates with respect to a closed triangle mesh (Ju, Schaefer
// & Warren 2005; computed in the form of Floater, Kos & Reimers 2005).
#pragma once

#include "Common/MeshTypes.h"

namespace md
{
/// Row-major dense weights: row i holds the weights of point i, one column per cage point.
using WeightMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Computes the mean value coordinates of points in one closed, consistently
/// oriented triangle mesh (the cage). They sum to 1 and reproduce every linear
/// function (sum_j w_j cage_j = x); they are smooth and positive inside the
/// cage and defined, possibly negative, outside it.
///
/// Robust near the cage: each triangle's share uses the signed distance of x
/// to the triangle's plane (from the triangle's own normal, so the one small
/// quantity is computed without cancellation); points on a cage point, edge or
/// triangle get the barycentric weights there. A last minimum-norm correction
/// (a few 1e-10 at most for points within 1e-7 of the cage) makes the sum and
/// the linear reproduction exact to rounding.
class MeanValueCoordinateCalculator
{
public:
  explicit MeanValueCoordinateCalculator(const TriangleMesh& cage);

  /// The weights of x, written to `weights` (one per cage point).
  void Compute(const Eigen::Vector3d& x, Eigen::Ref<Eigen::RowVectorXd> weights) const;

  /// Weights of every point (one row each), computed in parallel.
  WeightMatrix Compute(const Points& points) const;

private:
  const TriangleMesh& Cage;
  Eigen::Vector3d Centre;
  Points Centred;                        // cage points minus Centre
  Eigen::Matrix4d ConstraintGramInverse; // (A A^T)^-1, A = [centred^T; 1^T]
  double Size = 0;
  Eigen::Matrix<std::int64_t, Eigen::Dynamic, 2, Eigen::RowMajor> Edges; // each cage edge once: its two points
  Triangles TriangleEdges; // per triangle, the edge opposite each corner (an index into Edges)
};

/// Convenience: the weights of every point in `cage`.
WeightMatrix MeanValueCoordinates(const TriangleMesh& cage, const Points& points);
}
