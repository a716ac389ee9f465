// SPDX-License-Identifier: BSD-3-Clause
#include "Anatomy/MuscleFibres.h"

#include "Anatomy/FibreField.h"

#include "Geometry/MeanValueCoordinates.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/Polyline.h"
#include "Geometry/TriangleTree.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/IterativeLinearSolvers>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>

namespace md
{
namespace
{
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// A carried fibre point outside its muscle (or inside a bone) is found when it is out by less
/// than this many grid spacings (the search's radius: a point deeper inside costs little).
constexpr double kEscapeReach = 1.5;
/// A bone can poke into a muscle deeper than a fibre point strays out of it in a frame: an
/// obstacle without a distance grid (a bone refitted to a frame) is searched this many times farther.
constexpr double kObstacleReach = 3.0;
/// Share of the muscle's extent along its lines that makes an end's cap where it has no area.
constexpr double kCapShare = 0.05;

Eigen::Vector3d Centroid(const Points& points, const std::vector<Eigen::Index>& indices)
{
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (Eigen::Index i : indices)
  {
    sum += points.row(i).transpose();
  }
  return sum / static_cast<double>(std::max<size_t>(indices.size(), 1));
}

/// The outward angle-weighted pseudo-normal (Baerentzen & Aanaes 2005) at `closest`, the point of
/// the tree's surface nearest some x, of the feature it lies on (the triangle, an edge or a
/// corner): x - closest is along it outside and against it inside, for a closed surface.
/// `around` lists each point's triangles; without it (an obstacle), none on an edge or a corner.
std::optional<Eigen::Vector3d> OuterNormal(
  const TriangleTree& tree, const TriangleTree::Closest& closest, const std::vector<std::vector<Eigen::Index>>* around)
{
  const Triangles& triangles = tree.Mesh().triangles;
  const Points& points = tree.Mesh().points;
  const auto corner = [&](Eigen::Index t, int c) -> Eigen::Vector3d {
    return points.row(triangles(t, c)).transpose();
  };
  const auto normal = [&](Eigen::Index t) -> Eigen::Vector3d {
    return (corner(t, 1) - corner(t, 0)).cross(corner(t, 2) - corner(t, 0));
  };
  const Eigen::Index t = closest.triangle;
  const Eigen::Vector3d n = normal(t);
  const double area = n.squaredNorm();
  const Eigen::Vector3d& q = closest.point;
  std::array<double, 3> bary{};
  if (area > 0)
  {
    bary[0] = (corner(t, 2) - corner(t, 1)).cross(q - corner(t, 1)).dot(n) / area;
    bary[1] = (corner(t, 0) - corner(t, 2)).cross(q - corner(t, 2)).dot(n) / area;
    bary[2] = 1 - bary[0] - bary[1];
  }
  constexpr double kOnFeature = 1e-9;
  const int onEdges =
    static_cast<int>(std::count_if(bary.begin(), bary.end(), [](double b) { return b <= kOnFeature; }));
  if (area > 0 && onEdges == 0)
  {
    return n;
  }
  if (!around || !(area > 0))
  {
    return std::nullopt;
  }
  Eigen::Vector3d pseudo = Eigen::Vector3d::Zero();
  if (onEdges == 1)
  {
    // On the edge opposite the corner whose coordinate is 0: its two triangles' normals.
    const int opposite = static_cast<int>(std::min_element(bary.begin(), bary.end()) - bary.begin());
    const Eigen::Index a = triangles(t, (opposite + 1) % 3), b = triangles(t, (opposite + 2) % 3);
    for (Eigen::Index other : (*around)[size_t(a)])
    {
      if ((triangles.row(other).array() == b).any())
      {
        pseudo += normal(other).normalized();
      }
    }
  }
  else
  {
    // On a corner: its triangles' normals weighted by their angles there.
    const int at = static_cast<int>(std::max_element(bary.begin(), bary.end()) - bary.begin());
    const Eigen::Index p = triangles(t, at);
    for (Eigen::Index other : (*around)[size_t(p)])
    {
      int c = 0;
      while (triangles(other, c) != p)
      {
        ++c;
      }
      const Eigen::Vector3d e1 = corner(other, (c + 1) % 3) - corner(other, c);
      const Eigen::Vector3d e2 = corner(other, (c + 2) % 3) - corner(other, c);
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      pseudo += angle * normal(other).normalized();
    }
  }
  return pseudo;
}

bool OnOuterSide(const TriangleTree& tree, const TriangleTree::Closest& closest, const Eigen::Vector3d& x,
  const std::vector<std::vector<Eigen::Index>>* around = nullptr)
{
  const std::optional<Eigen::Vector3d> normal = OuterNormal(tree, closest, around);
  return normal ? (x - closest.point).dot(*normal) > 0 : !tree.Inside(x);
}

/// Where x breaks the rules, if anywhere: the muscle's wall it is outside of, or the obstacle
/// it is inside of (the surface's point nearest it), searched within `reach`.
struct Breach
{
  bool outsideMuscle = false, insideObstacle = false;
  Eigen::Vector3d wall, obstacle;
};

/// An obstacle as a query needs it: the tree, and the motions to its pose and back.
struct PlacedObstacle
{
  const TriangleTree* tree;
  RigidTransform toNow, toTree;
};

Breach Check(const Eigen::Vector3d& x, double reach, const TriangleTree& muscle, Eigen::Index hint,
  const std::vector<std::vector<Eigen::Index>>& around, const std::vector<PlacedObstacle>& obstacles)
{
  Breach breach;
  const TriangleTree::Closest wall = muscle.ClosestPoint(x, reach, hint);
  // The nearest wall's side decides locally, and cheaply; where the surface folds through itself
  // it flips between two sheets under the slightest change of x, so an outside is confirmed by the
  // winding number, which changes only where x crosses the surface.
  if (wall.triangle >= 0 && OnOuterSide(muscle, wall, x, &around) && muscle.Winding(x) == 0)
  {
    breach.outsideMuscle = true;
    breach.wall = wall.point;
  }
  for (const PlacedObstacle& obstacle : obstacles)
  {
    const Eigen::Vector3d there = obstacle.toTree.Apply(x);
    if (!obstacle.tree->InBounds(there))
    {
      continue;
    }
    // Searched as far as the point may be inside: by the obstacle's distance grid (none needed
    // where it is surely outside), else a few reaches.
    double radius = kObstacleReach * reach;
    if (const auto bounds = obstacle.tree->SignedDistanceBounds(there))
    {
      if (bounds->first > 0)
      {
        continue;
      }
      radius = std::max(-bounds->first, bounds->second);
    }
    const TriangleTree::Closest bone = obstacle.tree->ClosestPoint(there, radius);
    if (bone.triangle >= 0 && !OnOuterSide(*obstacle.tree, bone, there))
    {
      breach.insideObstacle = true;
      breach.obstacle = obstacle.toNow.Apply(bone.point);
      break;
    }
  }
  return breach;
}

/// Keeps x inside `muscle` and out of `obstacles`: 0 where it was, 1 moved, 2 could not be kept
/// in (then where it was). Outside the muscle, x goes `depth` below the wall it left; inside an
/// obstacle, half that out of it (the muscle may lie on it); where the muscle's wall lies closer
/// to the obstacle than that, halfway between the two.
int KeepInside(Eigen::Vector3d& x, double depth, double reach, const TriangleTree& muscle, Eigen::Index hint,
  const std::vector<std::vector<Eigen::Index>>& around, const std::vector<PlacedObstacle>& obstacles)
{
  const Eigen::Vector3d carried = x;
  Breach breach = Check(x, reach, muscle, hint, around, obstacles);
  if (!breach.outsideMuscle && !breach.insideObstacle)
  {
    return 0;
  }
  std::optional<Eigen::Vector3d> wall, obstacle;
  for (int round = 0; round < 4; ++round)
  {
    if (breach.outsideMuscle)
    {
      wall = breach.wall;
      x = breach.wall - depth * (x - breach.wall).normalized();
    }
    else if (breach.insideObstacle)
    {
      obstacle = breach.obstacle;
      x = breach.obstacle + 0.5 * depth * (breach.obstacle - x).normalized();
    }
    if (wall && obstacle && round > 0)
    {
      x = 0.5 * (*wall + *obstacle);
    }
    breach = Check(x, reach, muscle, hint, around, obstacles);
    if (!breach.outsideMuscle && !breach.insideObstacle)
    {
      return 1;
    }
  }
  x = carried;
  return 2;
}

/// Mean value weights of `x` with the smallest left out, continuously (a weight that crosses the
/// threshold enters from nothing, so that the carried point does not jump under a small change of
/// the input): the threshold tau is where the weights, largest first, reach `share` of their
/// absolute sum (interpolated between two weights); a weight of at least 2 tau is kept whole, one
/// between tau and 2 tau fades in smoothly, the rest is dropped. The kept points are as many more
/// as make them span space (next to a flat part of the surface the largest weights are all on
/// it). Last, the kept weights are corrected to sum to 1 and reproduce x from the rest surface.
void KeepLargest(const Points& surface, const Eigen::Vector3d& x, const Eigen::RowVectorXd& weights, double share,
  std::vector<Eigen::Triplet<float, int>>& entries, Eigen::Index row)
{
  std::vector<Eigen::Index> order(size_t(weights.size()));
  std::iota(order.begin(), order.end(), Eigen::Index(0));
  std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) {
    return std::abs(weights[a]) > std::abs(weights[b]) || (std::abs(weights[a]) == std::abs(weights[b]) && a < b);
  });
  const double total = weights.cwiseAbs().sum();
  double tau = 0, cumulative = 0;
  for (size_t i = 0; i < order.size(); ++i)
  {
    const double here = std::abs(weights[order[i]]);
    if (cumulative + here >= share * total)
    {
      const double next = i + 1 < order.size() ? std::abs(weights[order[i + 1]]) : 0.0;
      const double f = here > 0 ? (share * total - cumulative) / here : 0.0;
      tau = here + f * (next - here);
      break;
    }
    cumulative += here;
  }
  const auto fade = [&](double size) {
    if (size >= 2 * tau)
    {
      return 1.0;
    }
    const double t = tau > 0 ? std::clamp(size / tau - 1, 0.0, 1.0) : 1.0;
    return t * t * (3 - 2 * t);
  };
  size_t count = 0;
  while (count < order.size() && (std::abs(weights[order[count]]) > tau || count < 4))
  {
    ++count;
  }
  // Constraints sum w (v - x) / size = 0 and sum w = 1 on the kept points.
  const double size = (surface.rowwise() - x.transpose()).rowwise().norm().maxCoeff();
  const auto constraintOf = [&](size_t n) {
    Eigen::Matrix<double, 4, Eigen::Dynamic> constraint(4, static_cast<Eigen::Index>(n));
    for (size_t i = 0; i < n; ++i)
    {
      constraint.col(Eigen::Index(i)) << (surface.row(order[i]).transpose() - x) / size, 1.0;
    }
    return constraint;
  };
  constexpr double kSpanning = 1e-10; // smallest over largest eigenvalue of the constraints' Gram matrix
  Eigen::Matrix<double, 4, Eigen::Dynamic> constraint = constraintOf(count);
  for (;;)
  {
    const Eigen::Vector4d eigen =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(constraint * constraint.transpose(), Eigen::EigenvaluesOnly)
        .eigenvalues();
    if (eigen[0] > kSpanning * eigen[3] || count == order.size())
    {
      break;
    }
    count = std::min(order.size(), 2 * count);
    constraint = constraintOf(count);
  }
  Eigen::VectorXd w(static_cast<Eigen::Index>(count));
  for (size_t i = 0; i < count; ++i)
  {
    w[Eigen::Index(i)] = weights[order[i]] * fade(std::abs(weights[order[i]]));
  }
  const Eigen::Vector4d residual = Eigen::Vector4d(0, 0, 0, 1) - constraint * w;
  w += constraint.transpose() * (constraint * constraint.transpose()).ldlt().solve(residual);
  for (size_t i = 0; i < count; ++i)
  {
    entries.emplace_back(static_cast<int>(row), static_cast<int>(order[i]), static_cast<float>(w[Eigen::Index(i)]));
  }
}
}

FibreEnds FindFibreEnds(
  const TriangleMesh& rest, const std::vector<Attachment>& attachments, const std::vector<Points>& restLines)
{
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
  for (const Points& line : restLines)
  {
    if (line.rows() >= 2)
    {
      direction += (line.row(line.rows() - 1) - line.row(0)).transpose().normalized();
    }
  }
  if (!(direction.norm() > 0) || !direction.allFinite())
  {
    throw InputError("its action lines have no length, so the fibres have no direction");
  }
  direction.normalize();
  FibreEnds ends;
  for (const Attachment& area : attachments)
  {
    if (area.points.empty())
    {
      continue;
    }
    const Eigen::Vector3d centre = Centroid(rest.points, area.points);
    double toFirst = std::numeric_limits<double>::max(), toLast = toFirst;
    for (const Points& line : restLines)
    {
      toFirst = std::min(toFirst, (line.row(0).transpose() - centre).norm());
      toLast = std::min(toLast, (line.row(line.rows() - 1).transpose() - centre).norm());
    }
    auto& end = toFirst <= toLast ? ends.origin : ends.insertion;
    auto& source = toFirst <= toLast ? ends.originSource : ends.insertionSource;
    end.insert(end.end(), area.points.begin(), area.points.end());
    if (source.find(" " + area.bone) == std::string::npos || source.empty())
    {
      source += (source.empty() ? "its area on " : " and on ") + area.bone;
    }
  }
  const Eigen::VectorXd along = rest.points * direction;
  const std::vector<char> usedPoints = UsedMask(rest);
  double low = std::numeric_limits<double>::max(), high = -low;
  for (Eigen::Index p = 0; p < rest.points.rows(); ++p)
  {
    if (usedPoints[size_t(p)])
    {
      low = std::min(low, along[p]);
      high = std::max(high, along[p]);
    }
  }
  const double cap = kCapShare * (high - low);
  for (int side = 0; side < 2; ++side)
  {
    auto& end = side == 0 ? ends.origin : ends.insertion;
    if (!end.empty())
    {
      std::sort(end.begin(), end.end());
      end.erase(std::unique(end.begin(), end.end()), end.end());
      continue;
    }
    for (Eigen::Index p = 0; p < rest.points.rows(); ++p)
    {
      if (usedPoints[size_t(p)] && (side == 0 ? along[p] <= low + cap : along[p] >= high - cap))
      {
        end.push_back(p);
      }
    }
    (side == 0 ? ends.originSource : ends.insertionSource) = "its end along its action lines";
  }
  return ends;
}

MuscleFibres::MuscleFibres(const TriangleMesh& rest, const FibreEnds& given, const FibreParameters& parameters,
  const std::vector<const TriangleMesh*>& obstacles)
{
  if (given.origin.empty() || given.insertion.empty())
  {
    throw InputError("the fibres need an origin and an insertion");
  }
  if (parameters.count < 1 || parameters.pointsPerFibre < 3)
  {
    throw InputError("the fibres need a count of at least 1 and at least 3 points each");
  }
  const TriangleTree tree(rest);
  std::vector<TriangleTree> obstacleTrees;
  for (const TriangleMesh* obstacle : obstacles)
  {
    obstacleTrees.emplace_back(*obstacle);
  }
  // Inside the muscle and outside every obstacle.
  const auto free = [&](const Eigen::Vector3d& x) {
    return tree.Inside(x) && std::none_of(obstacleTrees.begin(), obstacleTrees.end(), [&](const TriangleTree& o) {
      return o.InBounds(x) && o.Inside(x);
    });
  };
  // A muscle too slender for its grid (no inside next to an end, the ends not joined, or few
  // streamlines that stay inside) is traced once more on a grid of four times the nodes; the
  // attempt with more fibres is kept.
  const auto wanted = size_t(parameters.count);
  TracedFibres traced;
  std::string firstError;
  int nodes = parameters.gridNodes;
  for (int attempt = 0; attempt < 2 && 2 * traced.fibres.size() < wanted; ++attempt, nodes *= 4)
  {
    try
    {
      TracedFibres more = TraceFibres(rest, given, parameters, nodes, obstacles, free);
      if (more.fibres.size() > traced.fibres.size())
      {
        traced = std::move(more);
      }
    }
    catch (const InputError& error)
    {
      firstError = firstError.empty() ? error.what() : firstError;
    }
  }
  std::vector<Points>& fibres = traced.fibres;
  std::vector<std::array<FibreEnd, 2>>& ends = traced.ends;
  if (fibres.empty())
  {
    throw InputError(firstError.empty() ? "no fibre could be traced from its origin to its insertion" : firstError);
  }
  if (traced.gridNodes != parameters.gridNodes)
  {
    this->Said.push_back("traced on a grid of " + std::to_string(traced.gridNodes) + " nodes, not " +
      std::to_string(parameters.gridNodes) + ": the muscle is too slender for that");
  }
  if (fibres.size() < wanted)
  {
    this->Said.push_back(
      std::to_string(fibres.size()) + " fibres, not " + std::to_string(wanted) + ": the others could not be traced");
  }
  this->Fibres = static_cast<int>(fibres.size());
  this->PerFibre = parameters.pointsPerFibre;
  this->RestPoints.resize(Eigen::Index(this->Fibres) * this->PerFibre, 3);
  for (size_t f = 0; f < fibres.size(); ++f)
  {
    this->RestPoints.middleRows(Eigen::Index(f) * this->PerFibre, this->PerFibre) = fibres[f];
  }
  // Inner points by their mean value weights (sparse); a fibre's ends, near the surface, as the
  // point of the segment between the area's point (carried by its triangle's corners, exactly
  // with the surface) and the next fibre point: the mean value weights of a point that near the
  // surface are all on the few points around it, and a sparse row there would depend on their
  // choice (on the input's rounding) many times over.
  std::vector<Eigen::Index> inner;
  for (Eigen::Index p = 0; p < this->RestPoints.rows(); ++p)
  {
    if (p % this->PerFibre != 0 && p % this->PerFibre != this->PerFibre - 1)
    {
      inner.push_back(p);
    }
  }
  Points innerPoints(static_cast<Eigen::Index>(inner.size()), 3);
  for (size_t i = 0; i < inner.size(); ++i)
  {
    innerPoints.row(Eigen::Index(i)) = this->RestPoints.row(inner[i]);
  }
  const WeightMatrix dense = MeanValueCoordinates(rest, innerPoints);
  std::vector<std::vector<Eigen::Triplet<float, int>>> rows(size_t(this->RestPoints.rows()));
  for (size_t i = 0; i < inner.size(); ++i)
  {
    KeepLargest(rest.points, innerPoints.row(Eigen::Index(i)).transpose(), dense.row(Eigen::Index(i)),
      parameters.keptWeightShare, rows[size_t(inner[i])], inner[i]);
  }
  for (int f = 0; f < this->Fibres; ++f)
  {
    for (int side = 0; side < 2; ++side)
    {
      // (1 - share) of the area's point (its triangle's corners) and share of the next point,
      // the next point added once it is carried (its weights not repeated: fewer to read).
      const FibreEnd& end = ends[size_t(f)][size_t(side)];
      const Eigen::Index p = Eigen::Index(f) * this->PerFibre + (side == 0 ? 0 : this->PerFibre - 1);
      const Eigen::Index next = side == 0 ? p + 1 : p - 1;
      for (int c = 0; c < 3; ++c)
      {
        rows[size_t(p)].emplace_back(static_cast<int>(p), static_cast<int>(end.anchor.ids[size_t(c)]),
          static_cast<float>((1 - end.share) * end.anchor.weights[c]));
      }
      this->EndBlends.push_back({ p, next, end.share });
    }
  }
  std::vector<Eigen::Triplet<float, int>> entries;
  for (const auto& row : rows)
  {
    entries.insert(entries.end(), row.begin(), row.end());
  }
  this->RestTriangles = rest.triangles;
  this->Around.assign(size_t(rest.points.rows()), {});
  for (Eigen::Index t = 0; t < rest.triangles.rows(); ++t)
  {
    for (int c = 0; c < 3; ++c)
    {
      this->Around[size_t(rest.triangles(t, c))].push_back(t);
    }
  }
  this->RestTree = std::make_shared<const TriangleTree>(tree);
  this->Depth.resize(this->RestPoints.rows());
  this->NearestWall.resize(size_t(this->RestPoints.rows()));
  this->Reach = kEscapeReach * traced.spacing;
  for (Eigen::Index p = 0; p < this->RestPoints.rows(); ++p)
  {
    const Eigen::Vector3d x = this->RestPoints.row(p).transpose();
    const TriangleTree::Closest wall = tree.ClosestPoint(x);
    this->NearestWall[size_t(p)] = wall.triangle;
    double depth = wall.distance;
    for (const TriangleTree& o : obstacleTrees)
    {
      const TriangleTree::Closest nearest = o.ClosestPoint(x, depth);
      depth = nearest.triangle >= 0 ? nearest.distance : depth;
    }
    this->Depth[p] = std::min(depth, kFibreClearance * traced.spacing);
  }
  this->Weights.resize(this->RestPoints.rows(), rest.points.rows());
  this->Weights.setFromTriplets(entries.begin(), entries.end());
}

std::optional<RigidTransform> RigidMotionOf(const Points& rest, const Points& now, double tolerance)
{
  if (rest.rows() != now.rows() || rest.rows() == 0)
  {
    return std::nullopt;
  }
  // Fitted to a few hundred points spread over the surface, then checked at every point.
  const Eigen::Index stride = std::max<Eigen::Index>(1, rest.rows() / 500);
  const Eigen::Index sampled = (rest.rows() + stride - 1) / stride;
  Points from(sampled, 3), to(sampled, 3);
  for (Eigen::Index i = 0; i < sampled; ++i)
  {
    from.row(i) = rest.row(i * stride);
    to.row(i) = now.row(i * stride);
  }
  const RigidTransform motion = FitRigidTransform(from, to).transform;
  const double squared = tolerance * tolerance;
  int beyond = 0; // points off the motion by more than the tolerance (or not finite)
#pragma omp parallel for schedule(static) reduction(+ : beyond)
  for (Eigen::Index p = 0; p < rest.rows(); ++p)
  {
    beyond +=
      !((motion.rotation * rest.row(p).transpose() + motion.translation - now.row(p).transpose()).squaredNorm() <=
        squared);
  }
  return beyond == 0 ? std::optional<RigidTransform>(motion) : std::nullopt;
}

Points MuscleFibres::At(const Points& surface, const std::vector<FibreObstacle>& given, std::pair<int, int>* kept) const
{
  std::vector<PlacedObstacle> obstacles;
  for (const FibreObstacle& o : given)
  {
    obstacles.push_back({ o.tree, o.toNow, Inverse(o.toNow) });
  }
  // Four lanes a point (the fourth zero), read through raw pointers: a frame reads every weight.
  Eigen::Matrix<double, 4, Eigen::Dynamic> padded(4, surface.rows());
  padded.topRows<3>() = surface.transpose();
  padded.row(3).setZero();
  Points points(this->Weights.rows(), 3);
  const float* values = this->Weights.valuePtr();
  const int* columns = this->Weights.innerIndexPtr();
  const int* starts = this->Weights.outerIndexPtr();
#pragma omp parallel for schedule(static)
  for (Eigen::Index p = 0; p < points.rows(); ++p)
  {
    Eigen::Array4d x = Eigen::Array4d::Zero();
    for (int k = starts[p]; k < starts[p + 1]; ++k)
    {
      x += static_cast<double>(values[k]) * padded.col(columns[k]).array();
    }
    points.row(p) = x.head<3>().matrix().transpose();
  }
  for (const EndBlend& end : this->EndBlends)
  {
    points.row(end.point) += end.share * points.row(end.next);
  }
  TriangleTree tree = *this->RestTree;
  tree.Refit(surface);
  int moved = 0, stuck = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : moved, stuck)
  for (Eigen::Index p = 0; p < points.rows(); ++p)
  {
    Eigen::Vector3d x = points.row(p).transpose();
    const int result =
      KeepInside(x, this->Depth[p], this->Reach, tree, this->NearestWall[size_t(p)], this->Around, obstacles);
    moved += result > 0;
    stuck += result > 1;
    points.row(p) = x.transpose();
  }
  if (kept)
  {
    *kept = { moved, stuck };
  }
  return points;
}

std::vector<double> MuscleFibres::Lengths(const Points& points) const
{
  std::vector<double> lengths;
  for (int f = 0; f < this->Fibres; ++f)
  {
    lengths.push_back(PolylineLength(points.middleRows(Eigen::Index(f) * this->PerFibre, this->PerFibre)));
  }
  return lengths;
}

double MuscleFibres::MeanWeightsPerPoint() const
{
  return this->Weights.rows() ? static_cast<double>(this->Weights.nonZeros()) / this->Weights.rows() : 0.0;
}

Spread SpreadOf(std::vector<double> values)
{
  if (values.empty())
  {
    return { kNaN, kNaN, kNaN };
  }
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  const double median = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  return { median, values.front(), values.back() };
}
}
