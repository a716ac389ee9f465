// SPDX-License-Identifier: BSD-3-Clause
// Euclidean projection of a point onto a convex polyhedron given by half-spaces.
#pragma once

#include "Common/MeshTypes.h"

#include <optional>
#include <vector>

namespace md
{
/// The half-space normal . x >= offset.
struct HalfSpace
{
  Eigen::Vector3d normal;
  double offset;
};

/// argmin |x - target| subject to every half-space, by a primal active-set
/// method (at most three constraints are active in 3D) started from
/// `feasibleStart`, which must satisfy every half-space. Returns nothing when
/// the iteration does not settle (degenerate input).
std::optional<Eigen::Vector3d> ProjectOntoPolyhedron(
  const Eigen::Vector3d& target, const std::vector<HalfSpace>& halfSpaces, const Eigen::Vector3d& feasibleStart);

/// A point satisfying every half-space, searched along `direction` from
/// `origin` (the first point of that ray inside all of them), or nothing.
std::optional<Eigen::Vector3d> FeasiblePointAlongRay(
  const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, const std::vector<HalfSpace>& halfSpaces);
}
