// SPDX-License-Identifier: BSD-3-Clause
#include "Hull/ProgressiveHull.h"

#include "Geometry/ConvexProjection.h"
#include "Geometry/LocalFrame.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/TriangleGrid.h"
#include "Geometry/TriangleIntersection.h"
#include "Geometry/TriangleTree.h"
#include "Hull/HullBuilder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <queue>
#include <unordered_map>

namespace md
{

HullResult BuildProgressiveHull(const TriangleMesh& surface, const HullParameters& parameters, const Points* enclose)
{
  if (surface.points.rows() < 4 || surface.triangles.rows() < 4)
  {
    throw InputError("the surface is empty or has fewer than 4 points");
  }
  if (parameters.targetNumberOfPoints < 4)
  {
    throw InputError("the target number of hull points must be at least 4");
  }
  if (parameters.targetNumberOfPoints > surface.points.rows())
  {
    throw InputError("the target of " + std::to_string(parameters.targetNumberOfPoints) +
      " hull points is larger than the surface's " + std::to_string(surface.points.rows()) + " points");
  }
  hull::HullBuilder builder(surface, parameters);
  return builder.Run(enclose);
}

MuscleHull BuildMuscleHull(const TriangleMesh& muscle, const HullParameters& parameters)
{
  // In the muscle's local frame: the repair's merging, the placement's margins and the checks'
  // tolerances then mean the same wherever the muscle sits and whatever its units.
  const LocalFrame frame = LocalFrame::Around({ &muscle.points });
  TriangleMesh local = muscle;
  frame.ToLocal(local.points);
  MuscleHull built;
  built.clean = RepairClosedSurface(local, built.report);
  built.result = BuildProgressiveHull(built.clean, parameters, &built.report.pointsToEnclose);
  // A hull that is no closed manifold, or leaves muscle points outside, would map the muscle
  // wrongly (mean value coordinates extrapolate): refuse it rather than hand it on.
  const TriangleMesh& hull = built.result.hull;
  const EdgeReport edges = CheckEdges(hull.triangles);
  if (!edges.IsClosedOrientedManifold() || !(SignedVolume(hull.points, hull.triangles) > 0))
  {
    throw InputError("its hull came out as no closed, outward-oriented manifold surface (" +
      std::to_string(edges.boundaryEdges) + " open, " + std::to_string(edges.nonManifoldEdges) + " non-manifold and " +
      std::to_string(edges.inconsistentEdges) +
      " inconsistently oriented edges): the surface is too noisy or too thin for a hull; smooth or remesh it");
  }
  const std::int64_t outside = CountPointsOutsideHull(hull, local);
  if (outside > 0)
  {
    throw InputError("its hull leaves " + std::to_string(outside) +
      " of its points outside: the surface is too noisy for a hull; smooth or remesh it");
  }
  built.hullVolume = frame.VolumeToWorld(SignedVolume(hull.points, hull.triangles));
  built.cleanVolume = frame.VolumeToWorld(SignedVolume(built.clean.points, built.clean.triangles));
  frame.ToWorld(built.clean.points);
  frame.ToWorld(built.result.hull.points);
  frame.ToWorld(built.report.pointsToEnclose);
  return built;
}

std::int64_t CountPointsOutsideHull(const TriangleMesh& hull, const TriangleMesh& muscle, double slack)
{
  const Points used = UsedPoints(muscle);
  const double size = (used.colwise().maxCoeff() - used.colwise().minCoeff()).norm();
  // Ray parity through a tree sorts out the points well inside fast; the others (on or near the
  // hull, where it touches the muscle, or outside) are settled exactly by the winding number and
  // the distance to the hull, O(triangles) each.
  const TriangleTree tree(hull);
  const auto n = static_cast<long>(used.rows());
  std::vector<char> suspect(static_cast<size_t>(n), 0);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i)
  {
    suspect[static_cast<size_t>(i)] = tree.Inside(used.row(i).transpose()) ? 0 : 1;
  }
  Points suspects(std::count(suspect.begin(), suspect.end(), 1), 3);
  Eigen::Index k = 0;
  for (long i = 0; i < n; ++i)
  {
    if (suspect[static_cast<size_t>(i)])
    {
      suspects.row(k++) = used.row(i);
    }
  }
  return CountOutside(hull, suspects, kOnSurfaceShare * size + slack);
}

void CheckGivenHull(const TriangleMesh& hull, const std::string& hullName, const TriangleMesh& muscle,
  const std::string& muscleName, double slack)
{
  if (!CheckEdges(hull.triangles).IsClosedOrientedManifold() || SignedVolume(hull.points, hull.triangles) <= 0)
  {
    throw InputError(hullName + " is not a closed, outward-oriented manifold surface: build it with HullDecimation");
  }
  const std::int64_t outside = CountPointsOutsideHull(hull, muscle, slack);
  if (outside > 0)
  {
    throw InputError(hullName + " does not enclose " + muscleName + ": " + std::to_string(outside) + " of " +
      std::to_string(UsedPoints(muscle).rows()) +
      " muscle points are outside it, where mean value coordinates extrapolate; build the hull with HullDecimation "
      "or leave Hull empty");
  }
}
}
