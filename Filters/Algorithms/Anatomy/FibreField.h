// SPDX-License-Identifier: BSD-3-Clause
// The fibres' harmonic field and its streamlines (docs/DESIGN.md section 11, "Fibres"): the field
// solved on a grid of the rest muscle's inside, the seeds, the streamlines from the origin to the
// insertion and their ends on the attachment areas. The Anatomy stage's own; MuscleFibres.cxx
// builds on it.
#pragma once

#include "Anatomy/MuscleFibres.h"

#include <array>
#include <functional>
#include <vector>

namespace md
{
/// A point of an end's surface: its triangle's corners and its barycentric coordinates there.
struct Anchor
{
  std::array<Eigen::Index, 3> ids{};
  Eigen::Vector3d weights;
  Eigen::Vector3d point;
};

/// How a fibre's end is carried: `share` of the way from its area's point to the next fibre point.
struct FibreEnd
{
  Anchor anchor;
  double share = 0.5;
};

/// Fibres traced through the field on a grid of about `gridNodes` nodes inside the muscle (see
/// MuscleFibres::MuscleFibres), each with how its ends are carried; `free` says whether a point
/// is inside the muscle and out of the obstacles. Throws InputError where SolveField does.
struct TracedFibres
{
  int gridNodes = 0;
  double spacing = 0; ///< the grid's
  std::vector<Points> fibres;
  std::vector<std::array<FibreEnd, 2>> ends; ///< per fibre, how each end is carried
};
TracedFibres TraceFibres(const TriangleMesh& rest, const FibreEnds& given, const FibreParameters& parameters,
  int gridNodes, const std::vector<const TriangleMesh*>& obstacles,
  const std::function<bool(const Eigen::Vector3d&)>& free);
}
