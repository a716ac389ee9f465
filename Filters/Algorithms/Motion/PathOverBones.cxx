// SPDX-License-Identifier: BSD-3-Clause
#include "Motion/PathOverBones.h"

#include "Geometry/Polyline.h"

#include <Eigen/Cholesky>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace md
{
namespace
{
using Vector = Eigen::Vector3d;

/// Directions around a segment tried for lifting a string out of a bone (the first frame).
constexpr int kLiftDirections = 16;
/// A round has settled when no point moved further than this share of the segment's spacing.
constexpr double kSettledShare = 1e-9;
/// A round moves no point further than this many spacings: the string is not thrown through a
/// thin bone by one linearisation.
constexpr double kLargestMoveInSpacings = 1.0;
/// The smallest share of its step a round takes (see Settle).
constexpr double kSmallestShare = 1.0 / 1024;
/// Planes of a crease whose normals are closer than this (cosine) are one plane: the newer is kept.
constexpr double kSamePlaneCosine = 1 - 1e-6;

/// A plane a free point is held on: normal . x = offset, the normal pointing out of the bone.
struct Plane
{
  Vector normal = Vector::Zero();
  double offset = 0;
  Eigen::Index triangle = -1; ///< the bone's triangle nearest where it was taken
};

/// A free point held on a bone: on one plane, or in a concave crease of the bone on two or three
/// (the planes of the faces on either side, which a single plane would alternate between).
struct Hold
{
  int bone = -1; ///< -1: not held
  std::vector<Plane> planes;
  bool Held() const { return this->bone >= 0; }
};

/// Where a point is against the bones it may not enter: the bone it is deepest in, or nearest to
/// within `band` (signed distance, negative inside), with the surface point and the outward
/// direction there. bone -1: none within the band.
struct Nearest
{
  int bone = -1;
  Eigen::Index triangle = -1;
  double signedDistance = std::numeric_limits<double>::max();
  Vector surface = Vector::Zero();
  Vector outward = Vector::Zero();
};

class Segment
{
public:
  Segment(const Vector& from, const Vector& to, const std::vector<const TriangleTree*>& bones,
    const PathOverBonesParameters& parameters)
    : From(from)
    , To(to)
    , Bones(bones)
    , Count(parameters.pointsPerSegment)
    , Spacing((to - from).norm() / (parameters.pointsPerSegment + 1))
    , Clearance(parameters.clearanceShare * Spacing)
  {
    this->X.resize(this->Count);
    for (int j = 0; j < this->Count; ++j)
    {
      this->X[j] = this->From + this->T(j) * (this->To - this->From);
    }
    this->FindExemptions();
  }

  /// The free points as `start` has them (the last frame's answer), pushed out of bones that moved
  /// into them.
  void StartFrom(const Points& start, Eigen::Index first)
  {
    for (int j = 0; j < this->Count; ++j)
    {
      this->X[j] = start.row(first + j).transpose();
    }
    for (int j = 0; j < this->Count; ++j)
    {
      const Nearest near = this->NearestBone(j, this->X[j]);
      if (near.bone >= 0 && near.signedDistance < this->Clearance)
      {
        this->X[j] = near.surface + this->Clearance * near.outward;
      }
    }
  }

  /// The free points inside a bone lifted out of it along the direction around the segment that
  /// lifts the deepest of them least.
  void LiftOutOfBones()
  {
    std::vector<int> inside;
    for (int j = 0; j < this->Count; ++j)
    {
      const Nearest near = this->NearestBone(j, this->X[j]);
      if (near.bone >= 0 && near.signedDistance < 0)
      {
        inside.push_back(j);
      }
    }
    if (inside.empty())
    {
      return;
    }
    const Vector axis = (this->To - this->From).normalized();
    const Vector first = axis.unitOrthogonal(), second = axis.cross(first);
    double reach = 0;
    for (const TriangleTree* bone : this->Bones)
    {
      reach =
        std::max(reach, (bone->Mesh().points.colwise().maxCoeff() - bone->Mesh().points.colwise().minCoeff()).norm());
    }
    double best = std::numeric_limits<double>::max();
    std::vector<double> bestLift;
    Vector bestDirection = first;
    for (int k = 0; k < kLiftDirections; ++k)
    {
      const double angle = 2 * M_PI * k / kLiftDirections;
      const Vector direction = std::cos(angle) * first + std::sin(angle) * second;
      std::vector<double> lift;
      double deepest = 0;
      for (const int j : inside)
      {
        lift.push_back(this->ExitDistance(j, direction, reach));
        deepest = std::max(deepest, lift.back());
      }
      if (deepest < best)
      {
        best = deepest;
        bestLift = lift;
        bestDirection = direction;
      }
    }
    for (size_t i = 0; i < inside.size(); ++i)
    {
      this->X[inside[i]] += (bestLift[i] + this->Clearance) * bestDirection;
    }
  }

  /// Rounds of linearisation and solution until the string settles; the rounds taken (negative:
  /// not settled within `limit`).
  int Settle(int limit)
  {
    std::vector<Hold>& holds = this->Holds;
    holds.assign(this->Count, Hold{});
    double share = 1;
    std::vector<Vector> lastStep(this->Count, Vector::Zero());
    for (int round = 1; round <= limit; ++round)
    {
      bool changed = false;
      for (int j = 0; j < this->Count; ++j)
      {
        changed = this->Rehold(j, holds[j]) || changed;
      }
      // Solved, and solved again without the planes the string pulls a point away from (one
      // per point at a time), until it pulls against none.
      std::vector<Vector> next = this->Solve(holds);
      for (bool released = true; released;)
      {
        released = false;
        for (int j = 0; j < this->Count; ++j)
        {
          released = this->LetGo(j, next, holds[j]) || released;
        }
        if (released)
        {
          changed = true;
          next = this->Solve(holds);
        }
      }
      double largest = 0, along = 0;
      for (int j = 0; j < this->Count; ++j)
      {
        largest = std::max(largest, (next[j] - this->X[j]).norm());
        along += (next[j] - this->X[j]).dot(lastStep[j]);
      }
      if (!changed && largest <= kSettledShare * this->Spacing)
      {
        return round;
      }
      // A point held over a ridge is linearised on one side of it and then on the other: a round
      // that steps back against the last takes half the share of its step that one did, until
      // the points held change.
      share = changed ? 1.0 : along < 0 ? std::max(kSmallestShare, share / 2) : share;
      const double scale = largest > 0 ? share * std::min(1.0, kLargestMoveInSpacings * this->Spacing / largest) : 0.0;
      for (int j = 0; j < this->Count; ++j)
      {
        lastStep[j] = scale * (next[j] - this->X[j]);
        this->X[j] += lastStep[j];
      }
    }
    return -limit;
  }

  const std::vector<Vector>& Points() const { return this->X; }

  /// The bone free point j was held on at the end of Settle; -1 for none.
  int BoneOf(int j) const { return this->Holds.empty() ? -1 : this->Holds[j].bone; }

private:
  double T(int j) const { return static_cast<double>(j + 1) / (this->Count + 1); }

  /// Bone b is not held against points at parameters below LeaveFrom[b] (the segment starts in
  /// it) or above EnterTo[b] (it ends in it).
  void FindExemptions()
  {
    this->LeaveFrom.assign(this->Bones.size(), 0.0);
    this->EnterTo.assign(this->Bones.size(), 1.0);
    for (size_t b = 0; b < this->Bones.size(); ++b)
    {
      const TriangleTree& bone = *this->Bones[b];
      if (bone.Inside(this->From))
      {
        const auto hit = bone.FirstHit(this->From, this->To);
        this->LeaveFrom[b] = hit ? hit->t : 1.0;
      }
      if (bone.Inside(this->To))
      {
        const auto hit = bone.FirstHit(this->To, this->From);
        this->EnterTo[b] = hit ? 1.0 - hit->t : 0.0;
      }
    }
  }

  bool Exempt(int j, size_t b) const
  {
    const double t = this->T(j);
    return t < this->LeaveFrom[b] || t > this->EnterTo[b];
  }

  Nearest NearestBone(int j, const Vector& x) const
  {
    Nearest nearest;
    const double band = this->Clearance + 2 * this->Spacing;
    for (size_t b = 0; b < this->Bones.size(); ++b)
    {
      const TriangleTree& bone = *this->Bones[b];
      if (this->Exempt(j, b))
      {
        continue;
      }
      const TriangleTree::Closest closest = bone.ClosestPoint(x, band);
      if (closest.triangle < 0)
      {
        continue;
      }
      const bool inside = bone.Inside(x);
      const double signedDistance = inside ? -closest.distance : closest.distance;
      if (signedDistance >= nearest.signedDistance)
      {
        continue;
      }
      nearest.bone = static_cast<int>(b);
      nearest.triangle = closest.triangle;
      nearest.signedDistance = signedDistance;
      nearest.surface = closest.point;
      nearest.outward = closest.distance > kDegenerateShare * this->Spacing
        ? Vector((inside ? -1.0 : 1.0) * (x - closest.point) / closest.distance)
        : bone.Normal(closest.triangle);
    }
    return nearest;
  }

  /// How far free point j goes along `direction` before it leaves every bone it is in.
  double ExitDistance(int j, const Vector& direction, double reach) const
  {
    double distance = 0;
    for (size_t b = 0; b < this->Bones.size(); ++b)
    {
      const TriangleTree& bone = *this->Bones[b];
      if (this->Exempt(j, b) || !bone.Inside(this->X[j]))
      {
        continue;
      }
      const auto hit = bone.FirstHit(this->X[j], this->X[j] + reach * direction);
      distance = std::max(distance, hit ? hit->t * reach : reach);
    }
    return distance;
  }

  /// Free point j held anew at its place `X[j]`: on the plane of its nearest bone's surface when
  /// it is within the clearance of it (or was held already); that plane added to the ones it was
  /// held on where it is within the clearance of the new one (a concave crease, whose faces one
  /// plane at a time would alternate between), else in their place; a plane of the face still
  /// nearest is renewed and the others kept. True when the point or its planes changed.
  bool Rehold(int j, Hold& hold) const
  {
    const Nearest near = this->NearestBone(j, this->X[j]);
    const bool wasHeld = hold.Held();
    if (near.bone < 0 || (!wasHeld && near.signedDistance >= this->Clearance))
    {
      hold = Hold{};
      return wasHeld;
    }
    const Plane plane{ near.outward, near.outward.dot(near.surface) + this->Clearance, near.triangle };
    const bool sameBone = wasHeld && hold.bone == near.bone;
    for (Plane& old : sameBone ? hold.planes : std::vector<Plane>{})
    {
      if (old.triangle == plane.triangle)
      {
        old = plane; // still nearest the same face: its plane where the point is now
        return false;
      }
    }
    std::vector<Plane> kept;
    if (sameBone && near.signedDistance < (1 - 1e-6) * this->Clearance)
    {
      for (const Plane& old : hold.planes)
      {
        if (old.normal.dot(plane.normal) < kSamePlaneCosine && kept.size() < 2)
        {
          kept.push_back(old);
        }
      }
    }
    kept.push_back(plane);
    const bool changed = !wasHeld || kept.size() != hold.planes.size();
    hold.bone = near.bone;
    hold.planes = std::move(kept);
    return changed;
  }

  /// Lets go of the planes of point j whose hold the string pulls against at `x` (the energy's
  /// gradient 2 (2 x_j - x_(j-1) - x_(j+1)) as a sum of the planes' normals needs a negative
  /// share of one): the most negative; true when one was let go.
  bool LetGo(int j, const std::vector<Vector>& x, Hold& hold) const
  {
    if (!hold.Held())
    {
      return false;
    }
    const Vector before = j > 0 ? x[j - 1] : this->From, after = j + 1 < this->Count ? x[j + 1] : this->To;
    const Vector gradient = 2 * x[j] - before - after;
    const auto k = static_cast<Eigen::Index>(hold.planes.size());
    Eigen::Matrix<double, 3, Eigen::Dynamic> normals(3, k);
    for (Eigen::Index i = 0; i < k; ++i)
    {
      normals.col(i) = hold.planes[static_cast<size_t>(i)].normal;
    }
    const Eigen::VectorXd shares = (normals.transpose() * normals).ldlt().solve(normals.transpose() * gradient);
    Eigen::Index weakest = 0;
    if (shares.minCoeff(&weakest) >= 0)
    {
      return false;
    }
    hold.planes.erase(hold.planes.begin() + weakest);
    if (hold.planes.empty())
    {
      hold = Hold{};
    }
    return true;
  }

  /// Free point j as base + basis z: its three coordinates, or along the line or the plane its
  /// planes leave it (none where three hold it).
  static void Unknowns(const Hold& hold, Vector& base, Eigen::Matrix<double, 3, Eigen::Dynamic>& basis)
  {
    if (!hold.Held())
    {
      base.setZero();
      basis = Eigen::Matrix3d::Identity();
      return;
    }
    const auto k = static_cast<Eigen::Index>(hold.planes.size());
    Eigen::Matrix<double, 3, Eigen::Dynamic> normals(3, k);
    Eigen::VectorXd offsets(k);
    for (Eigen::Index i = 0; i < k; ++i)
    {
      normals.col(i) = hold.planes[static_cast<size_t>(i)].normal;
      offsets[i] = hold.planes[static_cast<size_t>(i)].offset;
    }
    base = normals * (normals.transpose() * normals).ldlt().solve(offsets);
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(normals * normals.transpose(), Eigen::ComputeFullU);
    basis = svd.matrixU().rightCols(3 - k);
  }

  /// The minimum of the sum of squared chords with the held points on their planes: the gradient
  /// 2 (2 x_j - x_(j-1) - x_(j+1)) is zero along every point's unknowns.
  std::vector<Vector> Solve(const std::vector<Hold>& holds) const
  {
    std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>> basis(this->Count);
    std::vector<Eigen::Index> offset(this->Count + 1, 0);
    std::vector<Vector> base(this->Count, Vector::Zero()); // x_j = base_j + basis_j z_j
    for (int j = 0; j < this->Count; ++j)
    {
      Unknowns(holds[j], base[j], basis[j]);
      offset[j + 1] = offset[j] + basis[j].cols();
    }
    const Eigen::Index n = offset[this->Count];
    Eigen::MatrixXd matrix = Eigen::MatrixXd::Zero(n, n);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
    for (int j = 0; j < this->Count; ++j)
    {
      const auto& bj = basis[j];
      matrix.block(offset[j], offset[j], bj.cols(), bj.cols()) = 2 * bj.transpose() * bj;
      // Neighbours: the path's ends are fixed, a held point's base is fixed.
      Vector known = -2 * base[j];
      for (const int k : { j - 1, j + 1 })
      {
        if (k < 0 || k >= this->Count)
        {
          known += k < 0 ? this->From : this->To;
          continue;
        }
        known += base[k];
        matrix.block(offset[j], offset[k], bj.cols(), basis[k].cols()) = -bj.transpose() * basis[k];
      }
      rhs.segment(offset[j], bj.cols()) = bj.transpose() * known;
    }
    const Eigen::VectorXd z = matrix.llt().solve(rhs);
    std::vector<Vector> x(this->Count);
    for (int j = 0; j < this->Count; ++j)
    {
      x[j] = base[j] + basis[j] * z.segment(offset[j], basis[j].cols());
    }
    return x;
  }

  Vector From, To;
  const std::vector<const TriangleTree*>& Bones;
  int Count;
  double Spacing, Clearance;
  std::vector<Vector> X;
  std::vector<Hold> Holds; ///< per free point, after Settle
  std::vector<double> LeaveFrom, EnterTo;
};

void CheckPath(const Points& fixed, const PathOverBonesParameters& parameters)
{
  if (fixed.rows() < 2)
  {
    throw InputError("a path over the bones needs at least two points; it has " + std::to_string(fixed.rows()));
  }
  if (!fixed.allFinite())
  {
    throw InputError("a path over the bones has a point that is not a finite number");
  }
  if (parameters.pointsPerSegment < 1)
  {
    throw InputError("a path over the bones needs at least one point per segment; asked " +
      std::to_string(parameters.pointsPerSegment));
  }
}
}

Points SubdividedPath(const Points& fixed, int pointsPerSegment)
{
  const int per = pointsPerSegment + 1;
  Points path((fixed.rows() - 1) * per + 1, 3);
  for (Eigen::Index s = 0; s + 1 < fixed.rows(); ++s)
  {
    for (int j = 0; j < per; ++j)
    {
      const double t = static_cast<double>(j) / per;
      path.row(s * per + j) = (1 - t) * fixed.row(s) + t * fixed.row(s + 1);
    }
  }
  path.row(path.rows() - 1) = fixed.row(fixed.rows() - 1);
  return path;
}

PathOverBonesResult PathOverBones(const Points& fixed, const std::vector<const TriangleTree*>& bones,
  const PathOverBonesParameters& parameters, const Points* start)
{
  CheckPath(fixed, parameters);
  PathOverBonesResult result;
  result.points = SubdividedPath(fixed, parameters.pointsPerSegment);
  result.straightLength = PolylineLength(fixed);
  result.pointsOnBone.assign(bones.size(), 0);
  result.boneOfPoint.assign(static_cast<size_t>(result.points.rows()), -1);
  const int per = parameters.pointsPerSegment + 1;
  const bool warm = start && start->rows() == result.points.rows() && start->allFinite();
  const double size = (fixed.colwise().maxCoeff() - fixed.colwise().minCoeff()).norm();
  for (Eigen::Index s = 0; s + 1 < fixed.rows(); ++s)
  {
    if ((fixed.row(s + 1) - fixed.row(s)).norm() <= kDegenerateShare * size)
    {
      continue; // two points in one place: their segment's points are that place
    }
    Segment segment(fixed.row(s).transpose(), fixed.row(s + 1).transpose(), bones, parameters);
    if (warm)
    {
      segment.StartFrom(*start, s * per + 1);
    }
    else
    {
      segment.LiftOutOfBones();
    }
    const int rounds = segment.Settle(parameters.maximumIterations);
    result.converged = result.converged && rounds > 0;
    result.iterations = std::max(result.iterations, std::abs(rounds));
    for (int j = 0; j < parameters.pointsPerSegment; ++j)
    {
      result.points.row(s * per + 1 + j) = segment.Points()[j].transpose();
      const int bone = segment.BoneOf(j);
      result.boneOfPoint[static_cast<size_t>(s * per + 1 + j)] = bone;
      if (bone >= 0)
      {
        ++result.pointsOnBone[static_cast<size_t>(bone)];
      }
    }
  }
  result.length = PolylineLength(result.points);
  return result;
}
}
