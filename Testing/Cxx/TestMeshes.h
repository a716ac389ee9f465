// SPDX-License-Identifier: BSD-3-Clause
// Small closed meshes shared by the core tests.
#pragma once

#include "Common/MeshTypes.h"

#include <array>
#include <cmath>
#include <random>
#include <vector>

/// The regular octahedron of points (+-1, 0, 0), (0, +-1, 0), (0, 0, +-1): 8 outward-facing triangles.
inline md::TriangleMesh Octahedron()
{
  md::TriangleMesh octahedron;
  octahedron.points.resize(6, 3);
  octahedron.points << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
  octahedron.triangles.resize(8, 3);
  octahedron.triangles << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
  return octahedron;
}

/// The axis-aligned box from `low` to `high`: 8 points, 12 outward-facing triangles.
inline md::TriangleMesh Box(const Eigen::Vector3d& low, const Eigen::Vector3d& high)
{
  md::TriangleMesh box;
  box.points.resize(8, 3);
  for (int i = 0; i < 8; ++i)
  {
    box.points.row(i) << (i & 1 ? high[0] : low[0]), (i & 2 ? high[1] : low[1]), (i & 4 ? high[2] : low[2]);
  }
  box.triangles.resize(12, 3);
  box.triangles << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3,
    7, 5;
  return box;
}

#include <map>
#include <utility>

/// A sphere: the icosahedron with each triangle split in four `subdivisions`
/// times, points pushed out to the sphere (outward-facing triangles).
inline md::TriangleMesh Sphere(const Eigen::Vector3d& centre, double radius, int subdivisions)
{
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Eigen::Vector3d> points = { { -1, t, 0 }, { 1, t, 0 }, { -1, -t, 0 }, { 1, -t, 0 }, { 0, -1, t },
    { 0, 1, t }, { 0, -1, -t }, { 0, 1, -t }, { t, 0, -1 }, { t, 0, 1 }, { -t, 0, -1 }, { -t, 0, 1 } };
  std::vector<std::array<std::int64_t, 3>> faces = { { 0, 11, 5 }, { 0, 5, 1 }, { 0, 1, 7 }, { 0, 7, 10 },
    { 0, 10, 11 }, { 1, 5, 9 }, { 5, 11, 4 }, { 11, 10, 2 }, { 10, 7, 6 }, { 7, 1, 8 }, { 3, 9, 4 }, { 3, 4, 2 },
    { 3, 2, 6 }, { 3, 6, 8 }, { 3, 8, 9 }, { 4, 9, 5 }, { 2, 4, 11 }, { 6, 2, 10 }, { 8, 6, 7 }, { 9, 8, 1 } };
  for (int s = 0; s < subdivisions; ++s)
  {
    std::map<std::pair<std::int64_t, std::int64_t>, std::int64_t> middle;
    auto mid = [&](std::int64_t a, std::int64_t b) {
      const auto key = std::minmax(a, b);
      auto [entry, added] = middle.try_emplace(key, static_cast<std::int64_t>(points.size()));
      if (added)
      {
        points.push_back((points[a] + points[b]) / 2);
      }
      return entry->second;
    };
    std::vector<std::array<std::int64_t, 3>> next;
    for (const auto& f : faces)
    {
      const std::int64_t ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      next.push_back({ f[0], ab, ca });
      next.push_back({ f[1], bc, ab });
      next.push_back({ f[2], ca, bc });
      next.push_back({ ab, bc, ca });
    }
    faces = std::move(next);
  }
  md::TriangleMesh sphere;
  sphere.points.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i)
  {
    sphere.points.row(static_cast<Eigen::Index>(i)) = (centre + radius * points[i].normalized()).transpose();
  }
  sphere.triangles.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f)
  {
    sphere.triangles.row(static_cast<Eigen::Index>(f)) << faces[f][0], faces[f][1], faces[f][2];
  }
  return sphere;
}

/// `n` points drawn uniformly from the box [-size, size] x [-size, size] x [-3 size, 3 size].
inline md::Points RandomCloud(int n, unsigned seed, double size)
{
  std::mt19937 generator(seed);
  std::uniform_real_distribution<double> coordinate(-size, size);
  md::Points p(n, 3);
  for (int i = 0; i < n; ++i)
  {
    p.row(i) << coordinate(generator), coordinate(generator), 3 * coordinate(generator);
  }
  return p;
}
