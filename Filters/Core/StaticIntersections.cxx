#include "StaticIntersections.h"

#include "MeshChecks.h"
#include "VolumeConstrainedSolver.h"

#include <algorithm>
#include <memory>

namespace md
{
namespace
{
double Diagonal(const Points& points)
{
  return points.rows() ? (points.colwise().maxCoeff() - points.colwise().minCoeff()).norm() : 0.0;
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

/// The obstacles of mesh m: the fixed ones, then the other meshes (null for itself).
struct ObstacleSet
{
  std::vector<std::unique_ptr<TriangleTree>> meshTrees;
  std::vector<const TriangleTree*> all;

  ObstacleSet(const std::vector<TriangleMesh>& meshes, const std::vector<FixedObstacle>& fixed)
  {
    for (const FixedObstacle& f : fixed)
    {
      this->all.push_back(f.tree);
    }
    for (const TriangleMesh& mesh : meshes)
    {
      this->meshTrees.push_back(std::make_unique<TriangleTree>(mesh));
      this->all.push_back(this->meshTrees.back().get());
    }
  }
  /// Obstacle o of mesh `mesh` (null for the mesh itself).
  const TriangleTree* For(size_t mesh, size_t o, size_t fixedCount) const
  {
    return o == fixedCount + mesh ? nullptr : this->all[o];
  }
};

bool Marked(const OverlapMasks* masks, size_t m, size_t o, Eigen::Index i)
{
  return masks && m < masks->size() && o < (*masks)[m].size() && !(*masks)[m][o].empty() &&
    (*masks)[m][o][static_cast<size_t>(i)];
}

/// For each point of mesh m: the obstacle it is deepest inside, a bone
/// before any muscle (-1: none, or only where `existing` marks it), the depth
/// and the nearest surface point.
struct Deepest
{
  std::vector<int> obstacle;
  std::vector<double> depth;
  Points nearest;
};

Deepest FindDeepest(const TriangleMesh& mesh, size_t m, const ObstacleSet& set, size_t fixedCount,
  const OverlapMasks* existing)
{
  const Eigen::Index n = mesh.points.rows();
  const std::vector<char> used = UsedMask(mesh);
  Deepest d{ std::vector<int>(static_cast<size_t>(n), -1), std::vector<double>(static_cast<size_t>(n), 0.0),
    Points::Zero(n, 3) };
#pragma omp parallel for schedule(dynamic, 128)
  for (Eigen::Index i = 0; i < n; ++i)
  {
    if (!used[static_cast<size_t>(i)])
    {
      continue;
    }
    const Eigen::Vector3d p = mesh.points.row(i).transpose();
    for (size_t o = 0; o < set.all.size(); ++o)
    {
      const TriangleTree* tree = set.For(m, o, fixedCount);
      if (!tree || Marked(existing, m, o, i) || !tree->InBounds(p) || !tree->Inside(p))
      {
        continue;
      }
      // Bones come first: a point inside a bone goes out of the deepest bone
      // it is in, whatever muscle it is in too (muscles may overlap a little).
      const bool isFixed = o < fixedCount, bestFixed = d.obstacle[i] >= 0 && d.obstacle[i] < static_cast<int>(fixedCount);
      if (bestFixed && !isFixed)
      {
        continue;
      }
      const TriangleTree::Closest closest = tree->ClosestPoint(p);
      if (d.obstacle[i] < 0 || (isFixed && !bestFixed) || closest.distance > d.depth[i])
      {
        d.obstacle[i] = static_cast<int>(o);
        d.depth[i] = closest.distance;
        d.nearest.row(i) = closest.point.transpose();
      }
    }
  }
  return d;
}
}

namespace
{
/// Spreads the moves of the penetrating points (obstacle >= 0) to the points
/// up to `rings` edges away, falling to zero beyond them (the moved points
/// fixed, every other point of the band the mean of its neighbours): the
/// print of the obstacle gets a smooth rim instead of a step.
void SpreadShift(const Triangles& triangles, const std::vector<int>& obstacle, int rings, Points& shift)
{
  const Eigen::Index n = shift.rows();
  std::vector<std::vector<std::int64_t>> neighbours(static_cast<size_t>(n));
  for (Eigen::Index t = 0; t < triangles.rows(); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      neighbours[triangles(t, k)].push_back(triangles(t, (k + 1) % 3));
      neighbours[triangles(t, (k + 1) % 3)].push_back(triangles(t, k));
    }
  }
  // The band: points within `rings` edges of a moved point, by breadth-first search.
  std::vector<int> ring(static_cast<size_t>(n), -1);
  std::vector<Eigen::Index> band, frontier;
  for (Eigen::Index i = 0; i < n; ++i)
  {
    if (obstacle[i] >= 0)
    {
      ring[i] = 0;
      frontier.push_back(i);
    }
  }
  for (int r = 1; r <= rings && !frontier.empty(); ++r)
  {
    std::vector<Eigen::Index> next;
    for (Eigen::Index i : frontier)
    {
      for (std::int64_t j : neighbours[i])
      {
        if (ring[j] < 0)
        {
          ring[j] = r;
          next.push_back(j);
          band.push_back(j);
        }
      }
    }
    frontier = std::move(next);
  }
  std::sort(band.begin(), band.end()); // a fixed order: the result does not depend on the search
  for (int iteration = 0; iteration < 4 * rings; ++iteration)
  {
    Points updated = shift;
    for (Eigen::Index i : band)
    {
      Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
      for (std::int64_t j : neighbours[i])
      {
        sum += shift.row(j);
      }
      updated.row(i) = sum / static_cast<double>(neighbours[i].size());
    }
    shift = std::move(updated);
  }
}
}

OverlapMasks FindOverlaps(const std::vector<TriangleMesh>& meshes, const std::vector<FixedObstacle>& fixed)
{
  const ObstacleSet set(meshes, fixed);
  OverlapMasks masks(meshes.size());
  for (size_t m = 0; m < meshes.size(); ++m)
  {
    const TriangleMesh& mesh = meshes[m];
    const std::vector<char> used = UsedMask(mesh);
    masks[m].resize(set.all.size());
    for (size_t o = 0; o < set.all.size(); ++o)
    {
      const TriangleTree* tree = set.For(m, o, fixed.size());
      if (!tree)
      {
        continue;
      }
      std::vector<char>& inside = masks[m][o];
      inside.assign(static_cast<size_t>(mesh.points.rows()), 0);
#pragma omp parallel for schedule(dynamic, 128)
      for (Eigen::Index i = 0; i < mesh.points.rows(); ++i)
      {
        const Eigen::Vector3d p = mesh.points.row(i).transpose();
        inside[i] = used[i] && tree->InBounds(p) && tree->Inside(p);
      }
    }
  }
  return masks;
}

std::vector<Penetration> MeasureNewPenetration(
  const std::vector<TriangleMesh>& meshes, const std::vector<FixedObstacle>& fixed, const OverlapMasks* existing)
{
  const ObstacleSet set(meshes, fixed);
  std::vector<Penetration> result(meshes.size());
  for (size_t m = 0; m < meshes.size(); ++m)
  {
    const Deepest d = FindDeepest(meshes[m], m, set, fixed.size(), existing);
    Penetration& p = result[m];
    for (size_t i = 0; i < d.obstacle.size(); ++i)
    {
      if (d.obstacle[i] >= 0)
      {
        ++p.count;
        p.maxDepth = std::max(p.maxDepth, d.depth[i]);
        if (d.obstacle[i] < static_cast<int>(fixed.size()))
        {
          ++p.fixedCount;
          p.fixedMaxDepth = std::max(p.fixedMaxDepth, d.depth[i]);
        }
      }
    }
  }
  return result;
}

StaticResolveResult ResolveStaticIntersections(const std::vector<TriangleMesh>& meshes,
  const std::vector<FixedObstacle>& fixed, const OverlapMasks* existing, const StaticResolveParameters& parameters)
{
  const ObstacleSet set(meshes, fixed);
  StaticResolveResult result;
  for (size_t m = 0; m < meshes.size(); ++m)
  {
    const TriangleMesh& mesh = meshes[m];
    const Eigen::Index n = mesh.points.rows();
    const Deepest d = FindDeepest(mesh, m, set, fixed.size(), existing);
    const double backOff = 1e-5 * Diagonal(mesh.points);
    Points shift = Points::Zero(n, 3);
    StaticResolveReport report;
    for (size_t o = 0; o < set.all.size(); ++o)
    {
      const TriangleTree* tree = set.For(m, o, fixed.size());
      if (!tree)
      {
        continue;
      }
      std::vector<char> member(static_cast<size_t>(n), 0);
      bool any = false;
      for (Eigen::Index i = 0; i < n; ++i)
      {
        member[i] = d.obstacle[i] == static_cast<int>(o);
        any = any || member[i];
      }
      if (!any)
      {
        continue;
      }
      const double share = o < fixed.size() ? 1.0 : parameters.deformableShare;
      const double reach = 2 * Diagonal(tree->Mesh().points);
      int groups = 0;
      const std::vector<int> group = Components(mesh.triangles, n, groups, &member);
      report.groups += groups;
      Points direction = Points::Zero(groups, 3);
      for (Eigen::Index i = 0; i < n; ++i)
      {
        if (group[i] >= 0)
        {
          direction.row(group[i]) += d.nearest.row(i) - mesh.points.row(i);
        }
      }
      for (int g = 0; g < groups; ++g)
      {
        const double length = direction.row(g).norm();
        direction.row(g) = length > 0 ? Eigen::RowVector3d(direction.row(g) / length) : Eigen::RowVector3d::Zero();
      }
#pragma omp parallel for schedule(dynamic, 64)
      for (Eigen::Index i = 0; i < n; ++i)
      {
        if (group[i] < 0)
        {
          continue;
        }
        const Eigen::Vector3d p = mesh.points.row(i).transpose();
        const Eigen::Vector3d nearest = d.nearest.row(i).transpose();
        const Eigen::Vector3d way = direction.row(group[i]).transpose();
        Eigen::Vector3d target = nearest;
        Eigen::Vector3d out = nearest - p;
        if (way.squaredNorm() > 0)
        {
          const auto exit = tree->FirstHit(p, p + reach * way);
          if (exit && (exit->point - p).norm() <= 2 * d.depth[i] + backOff)
          {
            target = exit->point;
            out = way;
          }
        }
        const double outLength = out.norm();
        if (outLength > 0)
        {
          target += (backOff / outLength) * out;
        }
        shift.row(i) = share * (target - p).transpose();
      }
    }
    if (parameters.falloffRings > 0)
    {
      SpreadShift(mesh.triangles, d.obstacle, parameters.falloffRings, shift);
    }
    // No move may enter a fixed obstacle (a bone) on the way: one out of
    // another muscle, or spread around a print, stops at the bone's surface.
#pragma omp parallel for schedule(dynamic, 64)
    for (Eigen::Index i = 0; i < n; ++i)
    {
      const double length = shift.row(i).norm();
      if (length == 0)
      {
        continue;
      }
      const Eigen::Vector3d p = mesh.points.row(i).transpose();
      const Eigen::Vector3d to = p + shift.row(i).transpose();
      for (size_t o = 0; o < fixed.size(); ++o)
      {
        if (d.obstacle[i] == static_cast<int>(o) || Marked(existing, m, o, i))
        {
          continue; // leaving this one, or inside it in the rest pose
        }
        if (const auto hit = fixed[o].tree->FirstHit(p, p + (to - p) * (1 + backOff / length)))
        {
          shift.row(i) *= std::max(0.0, hit->t * (1 + backOff / length) - backOff / length);
        }
      }
    }
    for (Eigen::Index i = 0; i < n; ++i)
    {
      if (d.obstacle[i] >= 0)
      {
        ++report.penetratingPoints;
        report.maxDepth = std::max(report.maxDepth, d.depth[i]);
      }
      report.maxShift = std::max(report.maxShift, shift.row(i).norm());
    }
    result.points.push_back(mesh.points + shift);
    result.shift.push_back(std::move(shift));
    result.reports.push_back(report);
  }
  return result;
}

std::vector<double> RestoreVolumes(std::vector<TriangleMesh>& meshes, const std::vector<double>& targetVolumes,
  const std::vector<FixedObstacle>& fixed, const std::vector<std::vector<char>>& held)
{
  const ObstacleSet set(meshes, fixed);
  std::vector<double> left(meshes.size(), 0.0);
  for (size_t m = 0; m < meshes.size(); ++m)
  {
    TriangleMesh& mesh = meshes[m];
    const Eigen::Index n = mesh.points.rows();
    std::vector<char> free(static_cast<size_t>(n), 1);
    for (Eigen::Index i = 0; i < n; ++i)
    {
      free[i] = !held[m][i];
    }
    const double backOff = 1e-6 * Diagonal(mesh.points);
    for (int iteration = 0; iteration < 4; ++iteration)
    {
      Points gradient;
      const double volume = EnclosedVolume(mesh.points, mesh.triangles, &gradient);
      for (Eigen::Index i = 0; i < n; ++i)
      {
        if (!free[i])
        {
          gradient.row(i).setZero();
        }
      }
      const double norm = gradient.squaredNorm();
      const double error = targetVolumes[m] - volume;
      if (norm == 0 || std::abs(error) <= 1e-7 * std::abs(targetVolumes[m]))
      {
        break;
      }
      const double scale = error / norm;
#pragma omp parallel for schedule(dynamic, 128)
      for (Eigen::Index i = 0; i < n; ++i)
      {
        if (!free[i])
        {
          continue;
        }
        const Eigen::Vector3d from = mesh.points.row(i).transpose();
        const Eigen::Vector3d to = from + scale * gradient.row(i).transpose();
        const double length = (to - from).norm();
        double first = 2;
        for (size_t o = 0; o < set.all.size(); ++o)
        {
          const TriangleTree* tree = set.For(m, o, fixed.size());
          if (tree)
          {
            if (const auto hit = tree->FirstHit(from, to); hit && hit->t < first)
            {
              first = hit->t;
            }
          }
        }
        if (first <= 1)
        {
          free[i] = 0; // at an obstacle from now on
          mesh.points.row(i) = (from + std::max(0.0, first - backOff / std::max(length, 1e-300)) * (to - from)).transpose();
        }
        else
        {
          mesh.points.row(i) = to.transpose();
        }
      }
    }
    left[m] = 100.0 * (EnclosedVolume(mesh.points, mesh.triangles) - targetVolumes[m]) / targetVolumes[m];
  }
  return left;
}
}
