// SPDX-License-Identifier: BSD-3-Clause
#include "Geometry/MeshChecks.h"

#include "Geometry/TriangleIntersection.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>
#include <vector>

namespace md
{
EdgeReport CheckEdges(const Triangles& triangles)
{
  struct EdgeUse
  {
    int forward = 0;  // walked from the smaller to the larger index
    int backward = 0; // walked from the larger to the smaller index
  };
  std::unordered_map<std::uint64_t, EdgeUse> edges;
  edges.reserve(static_cast<size_t>(triangles.rows()) * 2);
  EdgeReport report;
  for (Eigen::Index t = 0; t < triangles.rows(); ++t)
  {
    const auto a = triangles(t, 0), b = triangles(t, 1), c = triangles(t, 2);
    if (a == b || b == c || a == c)
    {
      ++report.degenerateTriangles;
      continue;
    }
    for (int k = 0; k < 3; ++k)
    {
      const std::int64_t from = triangles(t, k);
      const std::int64_t to = triangles(t, (k + 1) % 3);
      const auto lo = static_cast<std::uint64_t>(std::min(from, to));
      const auto hi = static_cast<std::uint64_t>(std::max(from, to));
      EdgeUse& use = edges[(lo << 32) | hi];
      (from < to ? use.forward : use.backward)++;
    }
  }
  for (const auto& entry : edges)
  {
    const int uses = entry.second.forward + entry.second.backward;
    if (uses == 1)
    {
      ++report.boundaryEdges;
    }
    else if (uses > 2)
    {
      ++report.nonManifoldEdges;
    }
    else if (entry.second.forward != 1)
    {
      ++report.inconsistentEdges;
    }
  }
  return report;
}

double SignedVolume(const Points& points, const Triangles& triangles)
{
  if (triangles.rows() == 0)
  {
    return 0.0;
  }
  // Tetrahedra from a point of the surface, not from the coordinates' origin: far from the
  // origin (a scan 1e12 away from it) the products would cancel to noise.
  const Eigen::Vector3d origin = points.row(triangles(0, 0)).transpose();
  double sixTimesVolume = 0;
  for (Eigen::Index t = 0; t < triangles.rows(); ++t)
  {
    const Eigen::Vector3d a = points.row(triangles(t, 0)).transpose() - origin;
    const Eigen::Vector3d b = points.row(triangles(t, 1)).transpose() - origin;
    const Eigen::Vector3d c = points.row(triangles(t, 2)).transpose() - origin;
    sixTimesVolume += a.cross(b).dot(c);
  }
  return sixTimesVolume / 6.0;
}

double WindingNumber(const Points& points, const Triangles& triangles, const Eigen::Vector3d& query)
{
  // Solid angle of each triangle (Van Oosterom & Strackee 1983).
  double total = 0;
  for (Eigen::Index t = 0; t < triangles.rows(); ++t)
  {
    const Eigen::Vector3d a = points.row(triangles(t, 0)).transpose() - query;
    const Eigen::Vector3d b = points.row(triangles(t, 1)).transpose() - query;
    const Eigen::Vector3d c = points.row(triangles(t, 2)).transpose() - query;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2.0 * std::atan2(numerator, denominator);
  }
  return total / (4.0 * M_PI);
}

std::int64_t CountInside(const Points& points, const Triangles& triangles, const Points& queries)
{
  std::int64_t inside = 0;
  for (Eigen::Index i = 0; i < queries.rows(); ++i)
  {
    if (WindingNumber(points, triangles, queries.row(i).transpose()) > 0.5)
    {
      ++inside;
    }
  }
  return inside;
}

Eigen::Vector3d ClosestPointOnTriangle(
  const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c)
{
  // Closest point by regions (Ericson, Real-Time Collision Detection, 5.1.5).
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0)
  {
    return a;
  }
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3)
  {
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0)
  {
    return a + d1 / (d1 - d3) * ab;
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6)
  {
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0)
  {
    return a + d2 / (d2 - d6) * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
  {
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  }
  const double denominator = 1.0 / (va + vb + vc);
  return a + ab * (vb * denominator) + ac * (vc * denominator);
}

Eigen::Vector3d BarycentricCoordinates(const TriangleMesh& mesh, Eigen::Index t, const Eigen::Vector3d& q)
{
  const Eigen::Vector3d a = mesh.points.row(mesh.triangles(t, 0)).transpose();
  const Eigen::Vector3d b = mesh.points.row(mesh.triangles(t, 1)).transpose();
  const Eigen::Vector3d c = mesh.points.row(mesh.triangles(t, 2)).transpose();
  const Eigen::Vector3d normal = (b - a).cross(c - a);
  const double area = normal.squaredNorm();
  if (!(area > 0))
  {
    return Eigen::Vector3d::Constant(1.0 / 3.0);
  }
  const double u = (c - b).cross(q - b).dot(normal) / area;
  const double v = (a - c).cross(q - c).dot(normal) / area;
  return { u, v, 1 - u - v };
}

double PointTriangleDistance(
  const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c)
{
  return (p - ClosestPointOnTriangle(p, a, b, c)).norm();
}

std::int64_t CountOutside(const TriangleMesh& surface, const Points& points, double tolerance)
{
  std::int64_t outside = 0;
  const auto n = static_cast<long>(points.rows());
#pragma omp parallel for schedule(static) reduction(+ : outside)
  for (long i = 0; i < n; ++i)
  {
    const Eigen::Vector3d p = points.row(i).transpose();
    if (WindingNumber(surface.points, surface.triangles, p) > 0.5)
    {
      continue;
    }
    bool near = false;
    for (Eigen::Index t = 0; t < surface.triangles.rows() && !near; ++t)
    {
      near = PointTriangleDistance(p, surface.points.row(surface.triangles(t, 0)).transpose(),
               surface.points.row(surface.triangles(t, 1)).transpose(),
               surface.points.row(surface.triangles(t, 2)).transpose()) <= tolerance;
    }
    outside += near ? 0 : 1;
  }
  return outside;
}

std::vector<char> UsedMask(const TriangleMesh& mesh)
{
  std::vector<char> used(static_cast<size_t>(mesh.points.rows()), 0);
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      used[static_cast<size_t>(mesh.triangles(t, k))] = 1;
    }
  }
  return used;
}

Points UsedPoints(const TriangleMesh& mesh)
{
  const std::vector<char> used = UsedMask(mesh);
  Points out(std::count(used.begin(), used.end(), 1), 3);
  for (Eigen::Index i = 0, next = 0; i < mesh.points.rows(); ++i)
  {
    if (used[i])
    {
      out.row(next++) = mesh.points.row(i);
    }
  }
  return out;
}

std::int64_t CountSelfIntersections(const TriangleMesh& surface)
{
  return static_cast<std::int64_t>(FindSelfIntersections(surface.points, surface.triangles).size());
}
}

namespace md
{
std::vector<std::vector<std::int64_t>> PointNeighbours(const Triangles& triangles, Eigen::Index points)
{
  std::vector<std::vector<std::int64_t>> neighbours(static_cast<size_t>(points));
  for (Eigen::Index t = 0; t < triangles.rows(); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      neighbours[triangles(t, k)].push_back(triangles(t, (k + 1) % 3));
      neighbours[triangles(t, (k + 1) % 3)].push_back(triangles(t, k));
    }
  }
  for (auto& list : neighbours)
  {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return neighbours;
}

std::vector<int> Components(
  const Triangles& triangles, Eigen::Index points, int& count, const std::vector<char>* member)
{
  auto isMember = [&](std::int64_t i) {
    return !member || (*member)[static_cast<size_t>(i)];
  };
  std::vector<int> parent(static_cast<size_t>(points));
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int x) {
    while (parent[x] != x)
    {
      x = parent[x] = parent[parent[x]];
    }
    return x;
  };
  for (Eigen::Index t = 0; t < triangles.rows(); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      const std::int64_t a = triangles(t, k), b = triangles(t, (k + 1) % 3);
      if (isMember(a) && isMember(b))
      {
        parent[root(static_cast<int>(b))] = root(static_cast<int>(a));
      }
    }
  }
  std::vector<int> label(static_cast<size_t>(points), -1), component(static_cast<size_t>(points), -1);
  count = 0;
  for (Eigen::Index i = 0; i < points; ++i)
  {
    if (!isMember(i))
    {
      continue;
    }
    int& l = label[root(static_cast<int>(i))];
    if (l < 0)
    {
      l = count++;
    }
    component[i] = l;
  }
  return component;
}

namespace
{
/// Twice the area times the unit normal of every triangle.
Points TriangleNormals(const Points& points, const Triangles& triangles)
{
  Points normals(triangles.rows(), 3);
  for (Eigen::Index t = 0; t < triangles.rows(); ++t)
  {
    const Eigen::Vector3d a = points.row(triangles(t, 0)), b = points.row(triangles(t, 1)),
                          c = points.row(triangles(t, 2));
    normals.row(t) = (b - a).cross(c - a).transpose();
  }
  return normals;
}

/// Whether the normals of triangles s and t meet at an angle whose cosine is below `limit`.
bool Sharp(const Points& normals, Eigen::Index s, Eigen::Index t, double limit)
{
  const double norms = normals.row(s).norm() * normals.row(t).norm();
  return norms > 0 && normals.row(s).dot(normals.row(t)) < limit * norms;
}
}

NewSharpEdges::NewSharpEdges(const Points& rest, const Triangles& triangles, double angleDegrees)
  : TrianglesAtRest(triangles)
  , Limit(std::cos(angleDegrees * 3.14159265358979323846 / 180.0))
{
  // The two triangles of each edge, keyed by its ordered point pair.
  std::unordered_map<std::uint64_t, std::pair<Eigen::Index, Eigen::Index>> edges;
  edges.reserve(static_cast<size_t>(triangles.rows()) * 2);
  for (Eigen::Index t = 0; t < triangles.rows(); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      const auto a = static_cast<std::uint64_t>(triangles(t, k)),
                 b = static_cast<std::uint64_t>(triangles(t, (k + 1) % 3));
      auto [entry, added] = edges.try_emplace((std::min(a, b) << 32) | std::max(a, b), t, -1);
      if (!added)
      {
        entry->second.second = entry->second.second < 0 ? t : -2; // -2: more than two triangles
      }
    }
  }
  const Points normals = TriangleNormals(rest, triangles);
  for (const auto& entry : edges)
  {
    const auto [s, t] = entry.second;
    if (t >= 0 && !Sharp(normals, s, t, this->Limit))
    {
      this->NotSharpAtRest.emplace_back(s, t);
    }
  }
  std::sort(this->NotSharpAtRest.begin(), this->NotSharpAtRest.end()); // the triangles' order: fewer cache misses
}

std::int64_t NewSharpEdges::Count(const Points& current) const
{
  const Points normals = TriangleNormals(current, this->TrianglesAtRest);
  std::int64_t count = 0;
  for (const auto& [s, t] : this->NotSharpAtRest)
  {
    count += Sharp(normals, s, t, this->Limit) ? 1 : 0;
  }
  return count;
}

std::int64_t CountNewSharpEdges(
  const Points& rest, const Points& current, const Triangles& triangles, double angleDegrees)
{
  return NewSharpEdges(rest, triangles, angleDegrees).Count(current);
}
}
