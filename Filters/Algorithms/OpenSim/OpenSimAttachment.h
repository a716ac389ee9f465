// SPDX-License-Identifier: BSD-3-Clause
// Tying the user's own surfaces to an OpenSim model: which body a scanned bone moves with,
// and which muscle paths are the action lines of which muscle surface.
#pragma once

#include "Common/MeshTypes.h"
#include "Common/Names.h"

#include <string>
#include <utility>
#include <vector>

namespace md::osim
{
/// "a=x; b=y,z" (separators between items: ';' or newlines; between values: ',' or spaces) as
/// (name, values) pairs. Throws InputError for an item without '='.
std::vector<std::pair<std::string, std::vector<std::string>>> ParseAssignments(const std::string& text);

using md::WithoutExtension; // "femur_r.vtk" -> "femur_r" (Common/Names.h)

/// The body a surface named `surfaceName` moves with: the one `assignments` gives it (by its
/// name with or without extension), else the body named as the surface (without extension), else
/// the body with the longest name that the surface's name starts with followed by a non-letter.
/// -1 when none.
int BodyOfSurface(const std::string& surfaceName, const std::vector<std::string>& bodyNames,
  const std::vector<std::pair<std::string, std::vector<std::string>>>& assignments);

struct PathGrouping
{
  std::vector<int> muscleOfPath;      ///< per path: index of its muscle, -1 when none
  std::vector<double> insideFraction; ///< per path: share of its length inside that muscle
  std::vector<bool> assignedByUser;   ///< per path: named in the assignments
};

/// Assigns each path (a polyline) to the closed muscle surface that holds the largest share of
/// its length (at least `minimumShare`), unless `assignments` (muscle=path,path) names it.
/// Throws InputError for an assignment naming an unknown muscle or path.
PathGrouping GroupPaths(const std::vector<TriangleMesh>& muscles, const std::vector<std::string>& muscleNames,
  const std::vector<Points>& paths, const std::vector<std::string>& pathNames,
  const std::vector<std::pair<std::string, std::vector<std::string>>>& assignments, double minimumShare = 0.05);
}
