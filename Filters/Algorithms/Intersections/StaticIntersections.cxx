// SPDX-License-Identifier: BSD-3-Clause
#include "Intersections/StaticIntersections.h"

#include "Deformation/MuscleDeformer.h"
#include "Deformation/VolumeConstrainedSolver.h"
#include "Geometry/MeshChecks.h"

#include <algorithm>
#include <limits>
#include <memory>
#include <queue>

namespace md
{
namespace
{
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
    this->meshTrees.resize(meshes.size());
#pragma omp parallel for schedule(dynamic, 1)
    for (int m = 0; m < static_cast<int>(meshes.size()); ++m)
    {
      this->meshTrees[m] = std::make_unique<TriangleTree>(meshes[m]);
    }
    for (const auto& tree : this->meshTrees)
    {
      this->all.push_back(tree.get());
    }
  }
  /// Obstacle o of mesh `mesh` (null for the mesh itself).
  const TriangleTree* For(size_t mesh, size_t o, size_t fixedCount) const
  {
    return o == fixedCount + mesh ? nullptr : this->all[o];
  }
};

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
  const OverlapMasks* existing, const std::vector<char>* outsideFixed = nullptr)
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
      const bool knownOutside =
        outsideFixed && o < fixedCount && (*outsideFixed)[static_cast<size_t>(i) * fixedCount + o];
      if (!tree || knownOutside || InOverlap(existing, m, o, i) || !tree->InBounds(p) || !tree->Inside(p))
      {
        continue;
      }
      // Bones come first: a point inside a bone goes out of the deepest bone
      // it is in, whatever muscle it is in too (muscles may overlap a little).
      const bool isFixed = o < fixedCount,
                 bestFixed = d.obstacle[i] >= 0 && d.obstacle[i] < static_cast<int>(fixedCount);
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

/// The new penetration FindDeepest found.
Penetration PenetrationOf(const Deepest& d, size_t fixedCount)
{
  Penetration p;
  for (size_t i = 0; i < d.obstacle.size(); ++i)
  {
    if (d.obstacle[i] >= 0)
    {
      ++p.count;
      p.maxDepth = std::max(p.maxDepth, d.depth[i]);
      if (d.obstacle[i] < static_cast<int>(fixedCount))
      {
        ++p.fixedCount;
        p.fixedMaxDepth = std::max(p.fixedMaxDepth, d.depth[i]);
      }
    }
  }
  return p;
}
}

namespace
{
/// Makes the ways out of the penetrating points a smooth field over them and
/// their rims. On entry `shift` holds each penetrating point's way out and
/// `rim` the width of its group's rim (> 0 marks the penetrating points);
/// every other shift is 0. The points within that width of a penetrating
/// point (along the edges) join them. The field is then the membrane over
/// them: each point the mean of its neighbours, zero beyond the rim, except
/// that no penetrating point may stay short of the obstacle's tangent plane
/// at its way out's end (`normal`: the obstacle's outward normal there), and
/// `pinned` points keep their shift. It is an obstacle problem, solved by
/// projected over-relaxed Gauss-Seidel sweeps in a fixed order, from the
/// shift given.
void SmoothPrints(const Points& points, const std::vector<std::vector<std::int64_t>>& neighbours,
  const std::vector<double>& rim, const Points& normal, const std::vector<char>& pinned, Points& shift)
{
  const Eigen::Index n = points.rows();
  // Who is in a rim: multi-source Dijkstra on what is left of each width.
  std::vector<double> left(static_cast<size_t>(n), 0.0);
  std::priority_queue<std::pair<double, Eigen::Index>> queue; // most left first
  double largest = 0;
  for (Eigen::Index i = 0; i < n; ++i)
  {
    if (rim[i] > 0)
    {
      left[i] = rim[i];
      queue.emplace(rim[i], i);
      largest = std::max(largest, shift.row(i).norm());
    }
  }
  while (!queue.empty())
  {
    const auto [remaining, i] = queue.top();
    queue.pop();
    if (remaining < left[i])
    {
      continue;
    }
    for (std::int64_t j : neighbours[i])
    {
      const double reach = remaining - (points.row(i) - points.row(j)).norm();
      if (reach > left[j])
      {
        left[j] = reach;
        queue.emplace(reach, j);
      }
    }
  }
  std::vector<Eigen::Index> region;
  for (Eigen::Index i = 0; i < n; ++i)
  {
    if (left[i] > 0 && !neighbours[i].empty())
    {
      region.push_back(i);
    }
  }
  // Each penetrating point must reach the plane through its target with the
  // obstacle's normal there: its move along that normal at least `least`.
  std::vector<double> least(static_cast<size_t>(n), 0.0);
  for (Eigen::Index i : region)
  {
    least[i] = rim[i] > 0 ? shift.row(i).dot(normal.row(i)) : 0.0;
  }
  constexpr double overRelaxation = 1.5;
  constexpr int maximumSweeps = 500;
  const double tolerance = 1e-4 * largest;
  for (int sweep = 0; sweep < maximumSweeps; ++sweep)
  {
    double change = 0;
    for (Eigen::Index i : region)
    {
      if (pinned[i])
      {
        continue;
      }
      Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
      for (std::int64_t j : neighbours[i])
      {
        mean += shift.row(j);
      }
      mean /= static_cast<double>(neighbours[i].size());
      Eigen::RowVector3d next = shift.row(i) + overRelaxation * (mean - shift.row(i));
      if (rim[i] > 0)
      {
        next += std::max(0.0, least[i] - next.dot(normal.row(i))) * normal.row(i);
      }
      change = std::max(change, (next - shift.row(i)).cwiseAbs().maxCoeff());
      shift.row(i) = next;
    }
    if (change <= tolerance)
    {
      break;
    }
  }
}
}

bool InOverlap(const OverlapMasks* masks, size_t m, size_t o, Eigen::Index i)
{
  return masks && m < masks->size() && o < (*masks)[m].size() && !(*masks)[m][o].empty() &&
    (*masks)[m][o][static_cast<size_t>(i)];
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

std::string MostlyInAnObstacle(const TriangleMesh& mesh, const std::string& name, size_t m,
  const std::vector<FixedObstacle>& fixed, const OverlapMasks& masks)
{
  const std::vector<char> used = UsedMask(mesh);
  const Eigen::Index points = std::count(used.begin(), used.end(), 1);
  const double onSurface = 1e-6 * BoxDiagonal(mesh.points);
  for (size_t o = 0; o < fixed.size(); ++o)
  {
    Eigen::Index in = 0;
    for (Eigen::Index i = 0; i < mesh.points.rows(); ++i)
    {
      in += used[i] &&
        (InOverlap(&masks, m, o, i) ||
          fixed[o].tree->ClosestPoint(mesh.points.row(i).transpose(), onSurface).triangle >= 0);
    }
    if (2 * in > points)
    {
      return "muscle '" + name + "' lies in bone '" + fixed[o].name + "' in the rest pose (" + std::to_string(in) +
        " of its " + std::to_string(points) +
        " points inside it or on its surface): is it given as a bone too? A muscle must lie outside the bones, "
        "but for where its scan overlaps them";
    }
  }
  return "";
}

std::vector<Penetration> MeasureNewPenetration(
  const std::vector<TriangleMesh>& meshes, const std::vector<FixedObstacle>& fixed, const OverlapMasks* existing)
{
  const ObstacleSet set(meshes, fixed);
  std::vector<Penetration> result(meshes.size());
  for (size_t m = 0; m < meshes.size(); ++m)
  {
    result[m] = PenetrationOf(FindDeepest(meshes[m], m, set, fixed.size(), existing), fixed.size());
  }
  return result;
}

namespace
{
/// Where a muscle's penetrating points go out: each point's move (`shift`), the outward normal
/// of the obstacle where it goes out (the tangent plane there is the half-space it must reach),
/// the width of its group's rim (> 0 marks a penetrating point) and the obstacle it leaves (a
/// bone, or a muscle it leaves wholly; null where it takes a share of the way).
struct Prints
{
  Points shift;
  Points normal;
  std::vector<double> rim;
  std::vector<const TriangleTree*> leaving;
};

/// The ways out of obstacle `tree` (`share` of each) of the points `d` finds deepest in it: each
/// connected group of them goes out along its mean way where that leaves the obstacle within
/// twice the point's depth, else to the nearest surface point; `backOff` beyond. Adds the
/// groups to `report`.
void WaysOut(const TriangleMesh& mesh, const Deepest& d, int o, const TriangleTree& tree, double share, double falloff,
  double backOff, Prints& prints, StaticResolveReport& report)
{
  const Eigen::Index n = mesh.points.rows();
  std::vector<char> member(static_cast<size_t>(n), 0);
  bool any = false;
  for (Eigen::Index i = 0; i < n; ++i)
  {
    member[i] = d.obstacle[i] == o;
    any = any || member[i];
  }
  if (!any)
  {
    return;
  }
  const double reach = 2 * BoxDiagonal(tree.Mesh().points);
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
    Eigen::Vector3d surfaceNormal = out.normalized(); // at the nearest point, the way there
    if (way.squaredNorm() > 0)
    {
      const auto exit = tree.FirstHit(p, p + reach * way);
      if (exit && (exit->point - p).norm() <= 2 * d.depth[i] + backOff)
      {
        target = exit->point;
        out = way;
        surfaceNormal = tree.Normal(exit->triangle);
        if (surfaceNormal.dot(way) < 0)
        {
          surfaceNormal = -surfaceNormal; // outward: the way leaves through it
        }
      }
    }
    const double outLength = out.norm();
    if (outLength > 0)
    {
      target += (backOff / outLength) * out;
    }
    prints.shift.row(i) = share * (target - p).transpose();
    prints.normal.row(i) = (surfaceNormal.allFinite() ? surfaceNormal : way).transpose();
    prints.leaving[i] = share == 1.0 ? &tree : nullptr; // a share of the way need not leave
  }
  std::vector<double> deepest(static_cast<size_t>(groups), 0.0);
  for (Eigen::Index i = 0; i < n; ++i)
  {
    if (group[i] >= 0)
    {
      deepest[group[i]] = std::max(deepest[group[i]], prints.shift.row(i).norm());
    }
  }
  for (Eigen::Index i = 0; i < n; ++i)
  {
    if (group[i] >= 0)
    {
      // Every penetrating point is marked, however small its group's move.
      prints.rim[i] = std::max(falloff * deepest[group[i]], std::numeric_limits<double>::min());
    }
  }
}

/// The prints smoothed over their rims (SmoothPrints). Smoothing can leave a point of a concave
/// obstacle inside it: such a point (its move does not cross the obstacle's surface an odd
/// number of times) is pinned to its own way out and the rest smoothed again.
void SmoothPinned(const TriangleMesh& mesh, Prints& prints)
{
  const Eigen::Index n = mesh.points.rows();
  const Points target = prints.shift;
  const std::vector<std::vector<std::int64_t>> neighbours = PointNeighbours(mesh.triangles, n);
  std::vector<char> pinned(static_cast<size_t>(n), 0);
  for (int round = 0; round < 4; ++round)
  {
    SmoothPrints(mesh.points, neighbours, prints.rim, prints.normal, pinned, prints.shift);
    std::int64_t failed = 0;
#pragma omp parallel for reduction(+ : failed) schedule(dynamic, 64)
    for (Eigen::Index i = 0; i < n; ++i)
    {
      const Eigen::Vector3d p = mesh.points.row(i).transpose();
      if (prints.leaving[i] && !pinned[i] &&
        prints.leaving[i]->Crossings(p, p + prints.shift.row(i).transpose()) % 2 == 0)
      {
        pinned[i] = 1;
        prints.shift.row(i) = target.row(i);
        ++failed;
      }
    }
    if (failed == 0)
    {
      break;
    }
  }
}

/// No move may enter a fixed obstacle (a bone) on the way: one out of another muscle, or spread
/// around a print, stops at the bone's surface (`backOff` short), but for the bone the point
/// leaves (`d`) and those it overlapped at rest (`existing`).
void StopAtBones(const TriangleMesh& mesh, size_t m, const Deepest& d, const std::vector<FixedObstacle>& fixed,
  const OverlapMasks* existing, double backOff, Points& shift)
{
#pragma omp parallel for schedule(dynamic, 64)
  for (Eigen::Index i = 0; i < mesh.points.rows(); ++i)
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
      if (d.obstacle[i] == static_cast<int>(o) || InOverlap(existing, m, o, i))
      {
        continue; // leaving this one, or inside it in the rest pose
      }
      if (const auto hit = fixed[o].tree->FirstHit(p, p + (to - p) * (1 + backOff / length)))
      {
        shift.row(i) *= std::max(0.0, hit->t * (1 + backOff / length) - backOff / length);
      }
    }
  }
}
}

StaticResolveResult ResolveStaticIntersections(const std::vector<TriangleMesh>& meshes,
  const std::vector<FixedObstacle>& fixed, const OverlapMasks* existing, const StaticResolveParameters& parameters,
  const std::vector<std::vector<char>>* outsideFixed)
{
  const ObstacleSet set(meshes, fixed);
  StaticResolveResult result;
  for (size_t m = 0; m < meshes.size(); ++m)
  {
    const TriangleMesh& mesh = meshes[m];
    const Eigen::Index n = mesh.points.rows();
    const std::vector<char>* outside = outsideFixed && outsideFixed->size() == meshes.size() &&
        (*outsideFixed)[m].size() == static_cast<size_t>(n) * fixed.size()
      ? &(*outsideFixed)[m]
      : nullptr;
    const Deepest d = FindDeepest(mesh, m, set, fixed.size(), existing, outside);
    result.found.push_back(PenetrationOf(d, fixed.size()));
    if (result.found.back().count == 0)
    {
      // Nothing to move (after a converged settle, the rule): no groups, prints or smoothing.
      result.points.push_back(mesh.points);
      result.shift.push_back(Points::Zero(n, 3));
      result.reports.emplace_back();
      continue;
    }
    const double backOff = 1e-5 * BoxDiagonal(mesh.points);
    Prints prints{ Points::Zero(n, 3), Points::Zero(n, 3), std::vector<double>(static_cast<size_t>(n), 0.0),
      std::vector<const TriangleTree*>(static_cast<size_t>(n), nullptr) };
    StaticResolveReport report;
    for (size_t o = 0; o < set.all.size(); ++o)
    {
      if (const TriangleTree* tree = set.For(m, o, fixed.size()))
      {
        const double share = o < fixed.size() ? 1.0 : parameters.deformableShare;
        WaysOut(mesh, d, static_cast<int>(o), *tree, share, parameters.falloff, backOff, prints, report);
      }
    }
    if (parameters.falloff > 0)
    {
      SmoothPinned(mesh, prints);
    }
    StopAtBones(mesh, m, d, fixed, existing, backOff, prints.shift);
    for (Eigen::Index i = 0; i < n; ++i)
    {
      if (d.obstacle[i] >= 0)
      {
        ++report.penetratingPoints;
        report.maxDepth = std::max(report.maxDepth, d.depth[i]);
      }
      report.maxShift = std::max(report.maxShift, prints.shift.row(i).norm());
    }
    result.points.push_back(mesh.points + prints.shift);
    result.shift.push_back(std::move(prints.shift));
    result.reports.push_back(report);
  }
  return result;
}

std::vector<double> RestoreVolumes(std::vector<TriangleMesh>& meshes, const std::vector<double>& targetVolumes,
  const std::vector<FixedObstacle>& fixed, const std::vector<std::vector<char>>& held)
{
  constexpr int taperRings = 3;
  constexpr double restored = 1e-7; // of the target volume: near enough, nothing moves
  // The obstacles are the meshes as given: built at the first mesh that must move, before any has.
  std::unique_ptr<const ObstacleSet> set;
  std::vector<double> left(meshes.size(), 0.0);
  for (size_t m = 0; m < meshes.size(); ++m)
  {
    TriangleMesh& mesh = meshes[m];
    const Eigen::Index n = mesh.points.rows();
    // After a settle that held the volume (every step of the full-mesh deformation) there is
    // nothing to give back: the neighbours, the taper and the obstacles' trees are not needed.
    const double given = EnclosedVolume(mesh.points, mesh.triangles);
    if (std::abs(targetVolumes[m] - given) <= restored * std::abs(targetVolumes[m]))
    {
      left[m] = 100.0 * (given - targetVolumes[m]) / targetVolumes[m];
      continue;
    }
    if (!set)
    {
      set = std::make_unique<const ObstacleSet>(meshes, fixed);
    }
    const std::vector<std::vector<std::int64_t>> neighbours = PointNeighbours(mesh.triangles, n);
    // How far each point takes part: 1 where it is free, tapering to 0 over
    // a few rings towards the held points (Jacobi steps with them fixed at 0).
    Eigen::VectorXd share(n);
    for (Eigen::Index i = 0; i < n; ++i)
    {
      share(i) = held[m][i] || neighbours[i].empty() ? 0.0 : 1.0;
    }
    for (int k = 0; k < taperRings; ++k)
    {
      Eigen::VectorXd next = share;
      for (Eigen::Index i = 0; i < n; ++i)
      {
        if (share(i) > 0)
        {
          double sum = 0;
          for (std::int64_t j : neighbours[i])
          {
            sum += share(j);
          }
          next(i) = 0.5 * share(i) + 0.5 * sum / static_cast<double>(neighbours[i].size());
        }
      }
      share = std::move(next);
    }
    // The way each point moves: its unit normal (of the gradient of the
    // volume, which points outwards), times its share.
    Points way;
    EnclosedVolume(mesh.points, mesh.triangles, &way);
    for (Eigen::Index i = 0; i < n; ++i)
    {
      const double length = way.row(i).norm();
      way.row(i) = length > 0 ? Eigen::RowVector3d(share(i) / length * way.row(i)) : Eigen::RowVector3d::Zero();
    }
    std::vector<char> moving(static_cast<size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i)
    {
      moving[i] = share(i) > 0;
    }
    const double backOff = 1e-6 * BoxDiagonal(mesh.points);
    for (int iteration = 0; iteration < 4; ++iteration)
    {
      Points gradient;
      const double volume = EnclosedVolume(mesh.points, mesh.triangles, &gradient);
      double rate = 0; // of the volume with the common distance
      for (Eigen::Index i = 0; i < n; ++i)
      {
        if (moving[i])
        {
          rate += gradient.row(i).dot(way.row(i));
        }
      }
      const double error = targetVolumes[m] - volume;
      if (rate == 0 || std::abs(error) <= restored * std::abs(targetVolumes[m]))
      {
        break;
      }
      const double distance = error / rate;
#pragma omp parallel for schedule(dynamic, 128)
      for (Eigen::Index i = 0; i < n; ++i)
      {
        if (!moving[i])
        {
          continue;
        }
        const Eigen::Vector3d from = mesh.points.row(i).transpose();
        const Eigen::Vector3d to = from + distance * way.row(i).transpose();
        const double length = (to - from).norm();
        double first = 2;
        for (size_t o = 0; o < set->all.size(); ++o)
        {
          const TriangleTree* tree = set->For(m, o, fixed.size());
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
          moving[i] = 0; // at an obstacle from now on
          mesh.points.row(i) =
            (from + std::max(0.0, first - backOff / std::max(length, 1e-300)) * (to - from)).transpose();
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

std::vector<FixedObstacle> FixedObstacles(const std::vector<Obstacle>& obstacles)
{
  std::vector<FixedObstacle> fixed;
  for (const Obstacle& o : obstacles)
  {
    fixed.push_back({ o.name, o.tree.get() });
  }
  return fixed;
}

StaticStep ResolveStatically(const std::vector<TriangleMesh>& meshes, const std::vector<TriangleMesh>* meshesRest,
  const std::vector<std::string>& obstacleNames, const std::vector<TriangleMesh>& obstacles,
  const std::vector<std::string>& restObstacleNames, const std::vector<TriangleMesh>& restObstacles,
  const StaticResolveParameters& parameters, const std::function<void(double)>& progress)
{
  auto report = [&](double fraction) {
    if (progress)
    {
      progress(fraction);
    }
  };
  const std::vector<Obstacle> trees = BuildObstacles(obstacleNames, obstacles);
  report(0.2);
  OverlapMasks existing;
  if (meshesRest)
  {
    const std::vector<Obstacle> restTrees =
      restObstacles.empty() ? std::vector<Obstacle>{} : BuildObstacles(restObstacleNames, restObstacles);
    existing = FindOverlaps(*meshesRest, FixedObstacles(restObstacles.empty() ? trees : restTrees));
  }
  report(0.4);
  const std::vector<FixedObstacle> fixed = FixedObstacles(trees);
  StaticStep step;
  step.resolved = ResolveStaticIntersections(meshes, fixed, meshesRest ? &existing : nullptr, parameters);
  report(0.8);
  std::vector<TriangleMesh> after = meshes;
  for (size_t k = 0; k < after.size(); ++k)
  {
    after[k].points = step.resolved.points[k];
    const TriangleMesh& reference = meshesRest ? (*meshesRest)[k] : meshes[k];
    const double referenceVolume = SignedVolume(reference.points, reference.triangles);
    const double volume = SignedVolume(after[k].points, after[k].triangles);
    step.volumeChangePercent.push_back(100.0 * (volume - referenceVolume) / referenceVolume);
  }
  step.left = MeasureNewPenetration(after, fixed, meshesRest ? &existing : nullptr);
  return step;
}
}
