// SPDX-License-Identifier: BSD-3-Clause
// Mesh checks: closedness, orientation, volume, sharp edges and flipped triangles.
#include "Geometry/MeshChecks.h"
#include "Phantom/Phantom.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using md::Points;
using md::Triangles;

namespace
{
md::TriangleMesh Tetrahedron()
{
  md::TriangleMesh mesh;
  mesh.points.resize(4, 3);
  mesh.points << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  mesh.triangles.resize(4, 3);
  mesh.triangles << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  return mesh;
}
}

TEST(MeshChecks, ClosedTetrahedron)
{
  const md::TriangleMesh tet = Tetrahedron();
  EXPECT_TRUE(md::CheckEdges(tet.triangles).IsClosedOrientedManifold());
  EXPECT_NEAR(md::SignedVolume(tet.points, tet.triangles), 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(md::WindingNumber(tet.points, tet.triangles, Eigen::Vector3d(0.1, 0.1, 0.1)), 1.0, 1e-12);
  EXPECT_NEAR(md::WindingNumber(tet.points, tet.triangles, Eigen::Vector3d(2, 2, 2)), 0.0, 1e-12);
}

TEST(MeshChecks, VolumeDoesNotDependOnWhereTheSurfaceSits)
{
  // The phantom's gluteus maximus 1e12 mm from the origin (an offset in the data, not in the
  // anatomy): its volume must stay its volume.
  const md::Phantom phantom = md::BuildPhantom(md::PhantomParameters());
  md::TriangleMesh muscle = phantom.muscles[1].rest;
  const double volume = md::SignedVolume(muscle.points, muscle.triangles);
  muscle.points.rowwise() += Eigen::RowVector3d(1e12, -1e12, 1e12);
  // Coordinates near 1e12 are rounded to about 1e-4 mm: the volume moves by that rounding only.
  EXPECT_NEAR(md::SignedVolume(muscle.points, muscle.triangles) / volume, 1.0, 1e-6);
}

TEST(MeshChecks, DetectsHolesFlipsAndNonManifoldEdges)
{
  md::TriangleMesh tet = Tetrahedron();
  const Triangles open = tet.triangles.topRows(3);
  EXPECT_EQ(md::CheckEdges(open).boundaryEdges, 3);
  Triangles flipped = tet.triangles;
  std::swap(flipped(1, 1), flipped(1, 2));
  EXPECT_EQ(md::CheckEdges(flipped).inconsistentEdges, 3);
  Triangles fin(5, 3);
  fin << tet.triangles, 0, 1, 2; // a third triangle on edge 0-1
  EXPECT_GT(md::CheckEdges(fin).nonManifoldEdges, 0);
  Triangles degenerate(1, 3);
  degenerate << 0, 0, 1;
  EXPECT_EQ(md::CheckEdges(degenerate).degenerateTriangles, 1);
}

TEST(MeshChecks, NewSharpEdgesFoundOnceCountEveryPoseAsPairingTheTrianglesAnew)
{
  // The phantom's gluteus maximus with pits pressed in at random (different ones in each pose):
  // the count built once at rest is, in every pose, that of pairing every two triangles that share
  // an edge by brute force and comparing their normals at rest and in the pose.
  const md::Phantom phantom = md::BuildPhantom(md::PhantomParameters());
  const md::TriangleMesh muscle = phantom.muscles[1].rest;
  const Triangles& triangles = muscle.triangles;
  auto normal = [&](const Points& p, Eigen::Index t) {
    const Eigen::Vector3d a = p.row(triangles(t, 0)), b = p.row(triangles(t, 1)), c = p.row(triangles(t, 2));
    return Eigen::Vector3d((b - a).cross(c - a));
  };
  auto sharp = [&](const Points& p, Eigen::Index s, Eigen::Index t) {
    const Eigen::Vector3d n = normal(p, s), m = normal(p, t);
    return n.dot(m) < 0.5 * n.norm() * m.norm(); // 60 degrees
  };
  auto shared = [&](Eigen::Index s, Eigen::Index t) {
    int common = 0;
    for (int i = 0; i < 3; ++i)
    {
      for (int j = 0; j < 3; ++j)
      {
        common += triangles(s, i) == triangles(t, j) ? 1 : 0;
      }
    }
    return common == 2;
  };
  const md::NewSharpEdges counter(muscle.points, triangles);
  std::mt19937 generator(5);
  std::uniform_int_distribution<Eigen::Index> point(0, muscle.points.rows() - 1);
  const Eigen::RowVector3d centre = muscle.points.colwise().mean();
  for (int pose = 0; pose < 3; ++pose)
  {
    Points pitted = muscle.points;
    for (int pit = 0; pit < 15; ++pit)
    {
      const Eigen::Index i = point(generator);
      pitted.row(i) = centre + 0.6 * (pitted.row(i) - centre);
    }
    std::int64_t expected = 0;
    for (Eigen::Index s = 0; s < triangles.rows(); ++s)
    {
      for (Eigen::Index t = s + 1; t < triangles.rows(); ++t)
      {
        expected += shared(s, t) && sharp(pitted, s, t) && !sharp(muscle.points, s, t) ? 1 : 0;
      }
    }
    EXPECT_GT(expected, 15) << "pose " << pose;
    EXPECT_EQ(counter.Count(pitted), expected) << "pose " << pose;
    EXPECT_EQ(md::CountNewSharpEdges(muscle.points, pitted, triangles), expected) << "pose " << pose;
  }
  EXPECT_EQ(counter.Count(muscle.points), 0);
}
