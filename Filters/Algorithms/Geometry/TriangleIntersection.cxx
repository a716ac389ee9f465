// SPDX-License-Identifier: BSD-3-Clause
#include "Geometry/TriangleIntersection.h"

#include "Geometry/TriangleGrid.h"

#include <algorithm>
#include <cmath>

namespace md
{
using Vec3 = Eigen::Vector3d;

bool IntersectLineTriangle(const Vec3& p, const Vec3& d, const Vec3& a, const Vec3& b, const Vec3& c, double eps,
  double& t, double& u, double& v)
{
  // Moller & Trumbore 1997, leaving as early as it can (this is a hot path).
  const Vec3 e1 = b - a, e2 = c - a;
  const Vec3 h = d.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) <= kDegenerateShare * e1.norm() * e2.norm() * d.norm())
  {
    return false;
  }
  const double inverse = 1.0 / det;
  const Vec3 s = p - a;
  u = s.dot(h) * inverse;
  if (u < -eps || u > 1 + eps)
  {
    return false;
  }
  const Vec3 q = s.cross(e1);
  v = d.dot(q) * inverse;
  if (v < -eps || u + v > 1 + eps)
  {
    return false;
  }
  t = e2.dot(q) * inverse;
  return true;
}

bool SegmentHitsTriangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c, double eps)
{
  double t, u, v;
  // Coplanar overlaps (a parallel segment) are not looked for.
  return IntersectLineTriangle(p, q - p, a, b, c, eps, t, u, v) && t >= -eps && t <= 1 + eps;
}

bool TrianglesIntersect(const std::array<Vec3, 3>& x, const std::array<int, 3>& fx, const std::array<Vec3, 3>& y,
  const std::array<int, 3>& fy)
{
  int shared = 0;
  int sharedX = -1, sharedY = -1;
  for (int i = 0; i < 3; ++i)
  {
    for (int j = 0; j < 3; ++j)
    {
      if (fx[i] == fy[j])
      {
        ++shared;
        sharedX = i;
        sharedY = j;
      }
    }
  }
  constexpr double eps = 1e-9;
  if (shared >= 2)
  {
    return false; // neighbours: the fold checks look after them
  }
  if (shared == 1)
  {
    // Only the edges opposite the shared corner can cut the other triangle.
    const Vec3& xa = x[(sharedX + 1) % 3];
    const Vec3& xb = x[(sharedX + 2) % 3];
    const Vec3& ya = y[(sharedY + 1) % 3];
    const Vec3& yb = y[(sharedY + 2) % 3];
    return SegmentHitsTriangle(xa, xb, y[0], y[1], y[2], -eps) || SegmentHitsTriangle(ya, yb, x[0], x[1], x[2], -eps);
  }
  for (int i = 0; i < 3; ++i)
  {
    if (SegmentHitsTriangle(x[i], x[(i + 1) % 3], y[0], y[1], y[2], eps) ||
      SegmentHitsTriangle(y[i], y[(i + 1) % 3], x[0], x[1], x[2], eps))
    {
      return true;
    }
  }
  return false;
}

std::vector<std::pair<int, int>> FindSelfIntersections(const Points& points, const Triangles& triangles)
{
  std::vector<std::pair<int, int>> pairs;
  const auto m = static_cast<int>(triangles.rows());
  if (m == 0)
  {
    return pairs;
  }
  TriangleGrid grid(TriangleGrid::CellSizeFor(points, triangles));
  std::vector<std::array<Vec3, 3>> corners(static_cast<size_t>(m));
  std::vector<std::array<int, 3>> ids(static_cast<size_t>(m));
  std::vector<Vec3> low(static_cast<size_t>(m)), high(static_cast<size_t>(m));
  for (int t = 0; t < m; ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      corners[t][k] = points.row(triangles(t, k)).transpose();
      ids[t][k] = static_cast<int>(triangles(t, k));
    }
    low[t] = corners[t][0].cwiseMin(corners[t][1]).cwiseMin(corners[t][2]);
    high[t] = corners[t][0].cwiseMax(corners[t][1]).cwiseMax(corners[t][2]);
    grid.Insert(t, low[t], high[t]);
  }
  // Cells in parallel, each thread collecting its own pairs; sorted after, so
  // the result does not depend on the threads.
  const std::vector<const std::vector<int>*> cells = grid.CrowdedCells();
  const auto cellCount = static_cast<long>(cells.size());
#pragma omp parallel
  {
    std::vector<std::pair<int, int>> found;
#pragma omp for schedule(dynamic, 64)
    for (long c = 0; c < cellCount; ++c)
    {
      const std::vector<int>& faces = *cells[c];
      for (size_t a = 0; a < faces.size(); ++a)
      {
        for (size_t b = a + 1; b < faces.size(); ++b)
        {
          const int s = faces[a], t = faces[b];
          if ((low[s].array() > high[t].array()).any() || (high[s].array() < low[t].array()).any())
          {
            continue; // bounding boxes apart
          }
          if (TrianglesIntersect(corners[s], ids[s], corners[t], ids[t]))
          {
            found.emplace_back(std::min(s, t), std::max(s, t));
          }
        }
      }
    }
#pragma omp critical
    pairs.insert(pairs.end(), found.begin(), found.end());
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}
}
