#include "TriangleIntersection.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace md
{
using Vec3 = Eigen::Vector3d;

bool SegmentHitsTriangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c, double eps)
{
  const Vec3 d = q - p;
  const Vec3 e1 = b - a, e2 = c - a;
  const Vec3 h = d.cross(e2);
  const double det = e1.dot(h);
  const double scale = e1.norm() * e2.norm() * d.norm();
  if (std::abs(det) <= 1e-12 * scale)
  {
    return false; // parallel (coplanar overlaps are not looked for)
  }
  const double inverse = 1.0 / det;
  const Vec3 s = p - a;
  const double u = s.dot(h) * inverse;
  if (u < -eps || u > 1 + eps)
  {
    return false;
  }
  const Vec3 qv = s.cross(e1);
  const double v = d.dot(qv) * inverse;
  if (v < -eps || u + v > 1 + eps)
  {
    return false;
  }
  const double t = e2.dot(qv) * inverse;
  return t >= -eps && t <= 1 + eps;
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
    return SegmentHitsTriangle(xa, xb, y[0], y[1], y[2], -eps) ||
      SegmentHitsTriangle(ya, yb, x[0], x[1], x[2], -eps);
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
  double edgeSum = 0;
  for (int t = 0; t < m; ++t)
  {
    edgeSum += (points.row(triangles(t, 0)) - points.row(triangles(t, 1))).norm();
  }
  const double cell = std::max(2.0 * edgeSum / m, 1e-300);
  auto index = [cell](double x) { return static_cast<long>(std::floor(x / cell)); };
  auto key = [](long i, long j, long k) {
    return (static_cast<std::uint64_t>(i & 0x1fffff) << 42) | (static_cast<std::uint64_t>(j & 0x1fffff) << 21) |
      static_cast<std::uint64_t>(k & 0x1fffff);
  };
  std::unordered_map<std::uint64_t, std::vector<int>> grid;
  std::vector<std::array<Vec3, 3>> corners(static_cast<size_t>(m));
  std::vector<std::array<int, 3>> ids(static_cast<size_t>(m));
  for (int t = 0; t < m; ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      corners[t][k] = points.row(triangles(t, k)).transpose();
      ids[t][k] = static_cast<int>(triangles(t, k));
    }
    const Vec3 low = corners[t][0].cwiseMin(corners[t][1]).cwiseMin(corners[t][2]);
    const Vec3 high = corners[t][0].cwiseMax(corners[t][1]).cwiseMax(corners[t][2]);
    for (long i = index(low[0]); i <= index(high[0]); ++i)
      for (long j = index(low[1]); j <= index(high[1]); ++j)
        for (long k = index(low[2]); k <= index(high[2]); ++k)
          grid[key(i, j, k)].push_back(t);
  }
  for (const auto& entry : grid)
  {
    const std::vector<int>& faces = entry.second;
    for (size_t a = 0; a < faces.size(); ++a)
    {
      for (size_t b = a + 1; b < faces.size(); ++b)
      {
        if (TrianglesIntersect(corners[faces[a]], ids[faces[a]], corners[faces[b]], ids[faces[b]]))
        {
          pairs.emplace_back(std::min(faces[a], faces[b]), std::max(faces[a], faces[b]));
        }
      }
    }
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}
}
