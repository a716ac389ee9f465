// SPDX-License-Identifier: BSD-3-Clause
// Intersection tests between triangles of one mesh (shared corners allowed).
#pragma once

#include "Common/MeshTypes.h"

#include <array>

namespace md
{
/// Whether the line p + t d passes through triangle abc, within `eps` of
/// its edges in barycentric terms (u, v >= -eps, u + v <= 1 + eps); if so, the
/// line parameter t and the barycentric coordinates of the meeting point
/// (a + u (b - a) + v (c - a)). False, early, as soon as one test fails, and
/// when the line is parallel to the plane.
bool IntersectLineTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
  const Eigen::Vector3d& b, const Eigen::Vector3d& c, double eps, double& t, double& u, double& v);

/// Does the segment pq cross triangle abc? eps > 0 counts touching (within
/// eps of the barycentric range) as crossing, eps < 0 requires a clear crossing.
bool SegmentHitsTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& a,
  const Eigen::Vector3d& b, const Eigen::Vector3d& c, double eps);

/// Do two triangles of one mesh (corner indices fx, fy; positions x, y)
/// intersect anywhere but at what they share? Triangles sharing an edge are
/// not tested (that is a matter of folding); coplanar overlaps are not found.
bool TrianglesIntersect(const std::array<Eigen::Vector3d, 3>& x, const std::array<int, 3>& fx,
  const std::array<Eigen::Vector3d, 3>& y, const std::array<int, 3>& fy);
}

#include <type_traits>
#include <utility>
#include <vector>

namespace md
{
/// Key of cell (i, j, k) of a uniform grid, 21 bits a coordinate (wrapping).
inline std::uint64_t GridCellKey(long i, long j, long k)
{
  return (static_cast<std::uint64_t>(i & 0x1fffff) << 42) | (static_cast<std::uint64_t>(j & 0x1fffff) << 21) |
    static_cast<std::uint64_t>(k & 0x1fffff);
}

/// Visits GridCellKey(i, j, k) of every cell from `low` to `high` (inclusive), i slowest. A
/// visitor that returns bool stops the walk by returning false; the walk then returns false.
template<typename Visit>
bool ForEachGridCell(const std::array<long, 3>& low, const std::array<long, 3>& high, Visit&& visit)
{
  for (long i = low[0]; i <= high[0]; ++i)
  {
    for (long j = low[1]; j <= high[1]; ++j)
    {
      for (long k = low[2]; k <= high[2]; ++k)
      {
        if constexpr (std::is_same_v<decltype(visit(std::uint64_t{})), bool>)
        {
          if (!visit(GridCellKey(i, j, k)))
          {
            return false;
          }
        }
        else
        {
          visit(GridCellKey(i, j, k));
        }
      }
    }
  }
  return true;
}

/// Every pair (s < t) of triangles of the mesh that intersect other than at
/// what they share, found through a uniform grid of triangle bounds.
std::vector<std::pair<int, int>> FindSelfIntersections(const Points& points, const Triangles& triangles);
}
