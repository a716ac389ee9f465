// SPDX-License-Identifier: BSD-3-Clause
// Folds of the one pass's full mesh (docs/DESIGN.md section 4): triangles the mapping turned over,
// found and undone as-rigid-as-possible around them.
#include "Deformation/DeformerState.h"

#include "Geometry/MeshChecks.h"
#include "Geometry/RigidMotion.h"

#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>

namespace md
{
namespace
{
/// The rings of neighbours of every point and the triangles at every point of `s`'s muscle,
/// found once.
void EnsureRings(MuscleState& s)
{
  if (!s.neighbours.empty())
  {
    return;
  }
  const Triangles& triangles = s.input->muscle->triangles;
  const Eigen::Index n = s.points.rows();
  s.neighbours = PointNeighbours(triangles, n);
  s.trianglesOf.assign(static_cast<size_t>(n), {});
  for (Eigen::Index t = 0; t < triangles.rows(); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      s.trianglesOf[triangles(t, k)].push_back(t);
    }
  }
}

/// `region` grown by the corners of the `flipped` triangles and then by two rings (so that an
/// attempt that left the same triangles flipped works on a wider region).
void GrowRegion(const std::vector<Eigen::Index>& flipped, const Triangles& triangles,
  const std::vector<std::vector<std::int64_t>>& ring, std::vector<char>& region)
{
  for (Eigen::Index t : flipped)
  {
    for (int k = 0; k < 3; ++k)
    {
      region[triangles(t, k)] = 1;
    }
  }
  std::vector<Eigen::Index> frontier;
  for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(region.size()); ++i)
  {
    if (region[i])
    {
      frontier.push_back(i);
    }
  }
  for (int grow = 0; grow < 2; ++grow)
  {
    std::vector<Eigen::Index> next;
    for (Eigen::Index i : frontier)
    {
      for (std::int64_t j : ring[i])
      {
        if (!region[j])
        {
          region[j] = 1;
          next.push_back(j);
        }
      }
    }
    frontier = std::move(next);
  }
}

/// The points `members` (their places among the unknowns in `slot`, -1 for the others, which
/// stay) given back the rest shape of their neighbourhoods (`s.reference`) as far as the fixed
/// border allows: five rounds of local rotations (fitted to each point's ring) and a global
/// solve of the uniform Laplacian. With `onBones` a point carried into a bone slides on it.
void ReshapeRegion(MuscleState& s, const std::vector<Eigen::Index>& members, const std::vector<Eigen::Index>& slot,
  const std::vector<Obstacle>& bones, bool onBones)
{
  const std::vector<std::vector<std::int64_t>>& ring = s.neighbours;
  const Points& reference = *s.reference;
  const Eigen::Index k = static_cast<Eigen::Index>(members.size());
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index a = 0; a < k; ++a)
  {
    const Eigen::Index i = members[a];
    entries.emplace_back(a, a, static_cast<double>(ring[i].size()));
    for (std::int64_t j : ring[i])
    {
      if (slot[j] >= 0)
      {
        entries.emplace_back(a, slot[j], -1.0);
      }
    }
  }
  Eigen::SparseMatrix<double> system(k, k);
  system.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(system);
  Points& shape = s.points; // the region reshaped, the rest unchanged
  std::vector<Eigen::Matrix3d> rotation(static_cast<size_t>(shape.rows()));
  Eigen::MatrixXd rhs(k, 3);
  for (int local = 0; local < 5 && solver.info() == Eigen::Success; ++local)
  {
#pragma omp parallel for schedule(static)
    for (Eigen::Index a = 0; a < k; ++a)
    {
      const Eigen::Index i = members[a];
      Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
      for (std::int64_t j : ring[i])
      {
        covariance += (shape.row(j) - shape.row(i)).transpose() * (reference.row(j) - reference.row(i));
      }
      rotation[i] = BestRotation(covariance);
    }
#pragma omp parallel for schedule(static)
    for (Eigen::Index a = 0; a < k; ++a)
    {
      const Eigen::Index i = members[a];
      Eigen::RowVector3d row = Eigen::RowVector3d::Zero();
      for (std::int64_t j : ring[i])
      {
        const Eigen::Matrix3d r = slot[j] >= 0 ? Eigen::Matrix3d(0.5 * (rotation[i] + rotation[j])) : rotation[i];
        row += (r * (reference.row(i) - reference.row(j)).transpose()).transpose();
        if (slot[j] < 0)
        {
          row += shape.row(j);
        }
      }
      rhs.row(a) = row;
    }
    const Eigen::MatrixXd solved = solver.solve(rhs);
    for (Eigen::Index a = 0; a < k; ++a)
    {
      shape.row(members[a]) = solved.row(a);
    }
    if (onBones)
    {
      SlideOnBones(s, bones, members);
    }
  }
}

/// The triangles that can have changed when `members` moved: those with a corner among them or
/// next to them.
std::vector<Eigen::Index> TrianglesNear(const MuscleState& s, const std::vector<Eigen::Index>& members)
{
  std::vector<char> candidate(static_cast<size_t>(s.input->muscle->triangles.rows()), 0);
  for (Eigen::Index i : members)
  {
    for (Eigen::Index t : s.trianglesOf[i])
    {
      candidate[t] = 1;
    }
    for (std::int64_t j : s.neighbours[i])
    {
      for (Eigen::Index t : s.trianglesOf[j])
      {
        candidate[t] = 1;
      }
    }
  }
  std::vector<Eigen::Index> candidates;
  for (Eigen::Index t = 0; t < static_cast<Eigen::Index>(candidate.size()); ++t)
  {
    if (candidate[t])
    {
      candidates.push_back(t);
    }
  }
  return candidates;
}
}

bool UnfoldFlippedTriangles(MuscleState& s, const std::vector<Obstacle>& bones, bool dynamicIntersections, bool onBones)
{
  const Triangles& triangles = s.input->muscle->triangles;
  std::vector<Eigen::Index> flipped = FlippedTriangles(*s.reference, s.points, triangles);
  if (flipped.empty())
  {
    return false;
  }
  const Eigen::Index n = s.points.rows();
  EnsureRings(s);
  std::vector<char> region(static_cast<size_t>(n), 0);
  std::vector<Eigen::Index> members;
  std::vector<char> pinned(static_cast<size_t>(n), 0); // held where they were (onBones)
  const Points before = s.points;
  for (int attempt = 0; attempt < 8 && !flipped.empty(); ++attempt)
  {
    // The region: the region of the attempts before and the corners of the flipped triangles,
    // grown by two rings.
    GrowRegion(flipped, triangles, s.neighbours, region);
    members.clear();
    std::vector<Eigen::Index> slot(static_cast<size_t>(n), -1);
    for (Eigen::Index i = 0; i < n; ++i)
    {
      if (region[i] && !s.neighbours[i].empty() && !pinned[i])
      {
        slot[i] = static_cast<Eigen::Index>(members.size());
        members.push_back(i);
      }
    }
    ReshapeRegion(s, members, slot, bones, onBones);
    if (onBones && attempt + 1 < 8 && PinDeeperInBones(s, bones, members, before, pinned) > 0)
    {
      continue; // the same folds, the region reshaped again around the held points
    }
    // Only triangles with a corner in the region or next to it can have changed.
    const std::vector<Eigen::Index> candidates = TrianglesNear(s, members);
    flipped = FlippedTriangles(*s.reference, s.points, triangles, &candidates);
  }
  // Held at the bones, a fold may stay: unfolding again would not undo it.
  s.unfoldingBlocked = onBones && !flipped.empty();
  // Without `onBones` unfolding is not held by obstacles (a fold is the worse
  // defect): a point it moved into a bone is frozen there like any point
  // found inside a bone, for the static resolution to settle.
  if (dynamicIntersections)
  {
#pragma omp parallel for schedule(dynamic, 16)
    for (Eigen::Index a = 0; a < static_cast<Eigen::Index>(members.size()); ++a)
    {
      const Eigen::Index i = members[a];
      const Eigen::Vector3d p = s.points.row(i).transpose();
      for (const Obstacle& bone : bones)
      {
        if (!s.frozen[i] && bone.tree->InBounds(p) && bone.tree->Inside(p))
        {
          s.frozen[i] = 1;
        }
      }
    }
  }
  return true;
}

std::vector<Eigen::Index> FlippedTriangles(
  const Points& rest, const Points& deformed, const Triangles& triangles, const std::vector<Eigen::Index>* candidates)
{
  // Each point's local motion: the covariance of its edges, rest against
  // deformed (only at the corners of the triangles to check).
  const Eigen::Index n = rest.rows(), m = triangles.rows();
  std::vector<char> needed(static_cast<size_t>(n), candidates ? 0 : 1);
  if (candidates)
  {
    for (Eigen::Index t : *candidates)
    {
      for (int k = 0; k < 3; ++k)
      {
        needed[triangles(t, k)] = 1;
      }
    }
  }
  std::vector<Eigen::Matrix3d> covariance(static_cast<size_t>(n), Eigen::Matrix3d::Zero());
  for (Eigen::Index t = 0; t < m; ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      const std::int64_t a = triangles(t, k), b = triangles(t, (k + 1) % 3);
      if (!needed[a] && !needed[b])
      {
        continue;
      }
      const Eigen::Vector3d e0 = (rest.row(b) - rest.row(a)).transpose();
      const Eigen::Vector3d e1 = (deformed.row(b) - deformed.row(a)).transpose();
      const Eigen::Matrix3d product = e1 * e0.transpose();
      covariance[a] += product;
      covariance[b] += product;
    }
  }
  std::vector<char> flipped(static_cast<size_t>(m), 0);
  const Eigen::Index count = candidates ? static_cast<Eigen::Index>(candidates->size()) : m;
#pragma omp parallel for schedule(static)
  for (Eigen::Index c = 0; c < count; ++c)
  {
    const Eigen::Index t = candidates ? (*candidates)[c] : c;
    const Eigen::Vector3d a0 = rest.row(triangles(t, 0)).transpose(), a1 = deformed.row(triangles(t, 0)).transpose();
    const Eigen::Vector3d n0 =
      (rest.row(triangles(t, 1)).transpose() - a0).cross(rest.row(triangles(t, 2)).transpose() - a0);
    const Eigen::Vector3d n1 =
      (deformed.row(triangles(t, 1)).transpose() - a1).cross(deformed.row(triangles(t, 2)).transpose() - a1);
    if (n0.squaredNorm() == 0 || n1.squaredNorm() == 0)
    {
      continue; // degenerate: no orientation to compare
    }
    const Eigen::Matrix3d local =
      covariance[triangles(t, 0)] + covariance[triangles(t, 1)] + covariance[triangles(t, 2)];
    const int sign = SignUnderBestRotation(local, n0, n1);
    flipped[t] = sign != 0 ? sign < 0 : n1.dot(BestRotationDirect(local) * n0) < 0;
  }
  std::vector<Eigen::Index> list;
  for (Eigen::Index t = 0; t < m; ++t)
  {
    if (flipped[t])
    {
      list.push_back(t);
    }
  }
  return list;
}

std::int64_t CountFlippedTriangles(const Points& rest, const Points& deformed, const Triangles& triangles)
{
  return static_cast<std::int64_t>(FlippedTriangles(rest, deformed, triangles).size());
}
}
