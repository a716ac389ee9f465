// Small closed meshes shared by the core tests.
#pragma once

#include "MeshTypes.h"

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
  box.triangles << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5,
    3, 7, 5;
  return box;
}
