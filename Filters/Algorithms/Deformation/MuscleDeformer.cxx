// SPDX-License-Identifier: BSD-3-Clause
#include "Deformation/MuscleDeformer.h"

#include "Common/MuscleFailures.h"
#include "Deformation/NearestSegment.h"
#include "Deformation/VolumeConstrainedSolver.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/RigidMotion.h"

#include <Eigen/SparseCholesky>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <iomanip>
#include <limits>
#include <numeric>
#include <queue>
#include <sstream>

namespace md
{
namespace
{
using Clock = std::chrono::steady_clock;
/// Unfold, let the volume settle, check again: at most this many times.
constexpr int maximumUnfoldings = 8;
/// A muscle whose span grows beyond this factor in the fine phase is being
/// torn apart (its volume is held): the phase stops there.
constexpr double maximumGrowth = 1.5;

/// Stacks the Laplacian rows, the dense action-line rows, one row per
/// anchored point (its position) and, with followWeight > 0, one row of that
/// weight per hull point (its position).
SparseMatrix StackRows(const SparseMatrix& laplacian, const WeightMatrix& sampleWeights,
  const std::vector<Eigen::Index>& anchored, double followWeight)
{
  const Eigen::Index n = laplacian.cols();
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<size_t>(laplacian.nonZeros() + sampleWeights.size()));
  for (Eigen::Index r = 0; r < laplacian.outerSize(); ++r)
  {
    for (SparseMatrix::InnerIterator it(laplacian, r); it; ++it)
    {
      entries.emplace_back(r, it.col(), it.value());
    }
  }
  for (Eigen::Index s = 0; s < sampleWeights.rows(); ++s)
  {
    for (Eigen::Index j = 0; j < n; ++j)
    {
      if (sampleWeights(s, j) != 0)
      {
        entries.emplace_back(laplacian.rows() + s, j, sampleWeights(s, j));
      }
    }
  }
  for (size_t a = 0; a < anchored.size(); ++a)
  {
    entries.emplace_back(laplacian.rows() + sampleWeights.rows() + static_cast<Eigen::Index>(a), anchored[a], 1.0);
  }
  const Eigen::Index followStart = laplacian.rows() + sampleWeights.rows() + static_cast<Eigen::Index>(anchored.size());
  const Eigen::Index followRows = followWeight > 0 ? n : 0;
  for (Eigen::Index i = 0; i < followRows; ++i)
  {
    entries.emplace_back(followStart + i, i, followWeight);
  }
  SparseMatrix rows(followStart + followRows, n);
  rows.setFromTriplets(entries.begin(), entries.end());
  return rows;
}

/// Whether every point lies inside the tree's surface (box tests first; the
/// first point outside decides).
bool EntirelyInside(const TriangleTree& tree, const Points& points)
{
  for (Eigen::Index i = 0; i < points.rows(); ++i)
  {
    if (!tree.InBounds(points.row(i).transpose()))
    {
      return false;
    }
  }
  for (Eigen::Index i = 0; i < points.rows(); ++i)
  {
    if (!tree.Inside(points.row(i).transpose()))
    {
      return false;
    }
  }
  return true;
}

double FractionInside(const TriangleTree& tree, const Points& points)
{
  return points.rows() ? static_cast<double>(CountInsideTree(tree, points)) / points.rows() : 0.0;
}

/// The state of one muscle through the pass.
struct MuscleState
{
  const MuscleToDeform* input = nullptr;
  double size = 0;                       // span (box diagonal) of the muscle where the pass starts
  WeightMatrix ownWeights;               // when not given
  const WeightMatrix* weights = nullptr; // full mesh = weights * hull
  std::unique_ptr<VolumeConstrainedSolver> solver;
  Points targets;
  Points currentSamples;             // action-line samples in the current pose
  Points hull;                       // X
  Points points;                     // the full mesh as it moves (W X where nothing held it)
  Points start;                      // where the pass starts
  const Points* reference = nullptr; // the shape folds are judged against (MuscleToDeform::reference)
  double hullVolume = 0, restVolume = 0;
  std::vector<char> frozen;           // inside a bone before a step: stays
  std::vector<char> stopped;          // held at an obstacle in the last move
  std::vector<char> touched;          // held at an obstacle in any move: left out of the volume gradient, which
                                      // would otherwise swing as points come off the obstacle and back
  std::unique_ptr<TriangleTree> tree; // of `points`, for the other muscles
  // Of the full mesh's points, when the unfolding first needs them: their
  // neighbours and the triangles they are corners of.
  std::vector<std::vector<std::int64_t>> neighbours;
  std::vector<std::vector<Eigen::Index>> trianglesOf;
  double orientation = 1; // +1 when the triangles face outwards
  bool converged = false;
  bool fineDone = false;
  bool fellBack = false; // the fine phase tore the muscle apart: it keeps its coarse result
  Points fineStartPoints, fineStartHull;
  int unfoldings = 0;
  bool flipsCheckedClean = false;
  bool unfoldingBlocked = false;                          // the last unfolding left folds (pinned at a bone): no more
  double fineStep = 1;                                    // step length of the fine phase
  double lastChange = std::numeric_limits<double>::max(); // largest hull change of the last fine step
  Clock::duration time{};
  DeformationResult result;
};

void Validate(const MuscleToDeform& m)
{
  const std::string name = "muscle '" + m.name + "'";
  if (!m.muscle || !m.hull || m.muscle->points.rows() == 0 || m.muscle->triangles.rows() == 0)
  {
    throw InputError(name + " has no surface");
  }
  if (!AllFinite(m.muscle->points) || !AllFinite(m.hull->points))
  {
    throw InputError(name + " has non-finite coordinates (NaN or infinity) in its surface or its hull");
  }
  if (!CheckEdges(m.hull->triangles).IsClosedOrientedManifold())
  {
    throw InputError("the hull of " + name + " is not a closed, consistently oriented manifold surface");
  }
  if (m.lines.empty())
  {
    throw InputError(name + " has no action line: nothing says where it goes");
  }
  for (const MatchedLine& line : m.lines)
  {
    if (line.rest.rows() < 2 || line.rest.rows() != line.current.rows())
    {
      throw InputError("an action line of " + name +
        " is not matched: it needs at least two points, as many in the rest pose as in the current pose");
    }
    if (!AllFinite(line.rest) || !AllFinite(line.current))
    {
      throw InputError("an action line of " + name + " has non-finite coordinates");
    }
    if (!KnotsFit(line.knots, line.rest.rows()))
    {
      throw InputError("an action line of " + name + " names its own points wrongly: " + kKnotsRule);
    }
  }
}

/// Throws InputError when an action line of muscle `m` does not pass through it: none of its
/// rest-pose samples is inside the muscle's hull.
void CheckLinesPassThrough(const MuscleToDeform& m, int samplesPerSegment)
{
  const TriangleTree hullTree(*m.hull);
  for (size_t l = 0; l < m.lines.size(); ++l)
  {
    Points restSamples, unused;
    SampleMatchedLines({ m.lines[l] }, samplesPerSegment, restSamples, unused);
    if (CountInsideTree(hullTree, restSamples) == 0)
    {
      throw InputError("action line " + std::to_string(l + 1) + " of muscle '" + m.name +
        "' does not pass through the muscle (none of its rest-pose samples is inside the muscle's hull): "
        "are the action lines in the rest pose, in the same units, paired with the right muscle?");
    }
  }
}

/// The points of the pieces of `hull` that no action-line sample (`restSamples`) lies in: a scan
/// can leave one (cut apart at a pinch), and nothing places it; its points follow their nearest
/// action-line segment, as soft rows.
std::vector<Eigen::Index> HullPointsNoLineDrives(const TriangleMesh& hull, const Points& restSamples)
{
  int pieces = 0;
  const std::vector<int> piece = Components(hull.triangles, hull.points.rows(), pieces);
  std::vector<Eigen::Index> anchored;
  for (int c = 0; pieces > 1 && c < pieces; ++c)
  {
    std::vector<Eigen::Index> faces;
    for (Eigen::Index t = 0; t < hull.triangles.rows(); ++t)
    {
      if (piece[hull.triangles(t, 0)] == c)
      {
        faces.push_back(t);
      }
    }
    Triangles pieceTriangles(static_cast<Eigen::Index>(faces.size()), 3);
    for (size_t f = 0; f < faces.size(); ++f)
    {
      pieceTriangles.row(static_cast<Eigen::Index>(f)) = hull.triangles.row(faces[f]);
    }
    bool driven = false;
    for (Eigen::Index r = 0; r < restSamples.rows() && !driven; ++r)
    {
      driven = WindingNumber(hull.points, pieceTriangles, restSamples.row(r).transpose()) > 0.5;
    }
    if (!driven)
    {
      for (Eigen::Index i = 0; i < hull.points.rows(); ++i)
      {
        if (piece[i] == c)
        {
          anchored.push_back(i);
        }
      }
    }
  }
  return anchored;
}

/// Builds the least-squares system and the mapping of one muscle.
void SetUp(MuscleState& s, const DeformationParameters& parameters)
{
  const MuscleToDeform& m = *s.input;
  const TriangleMesh& hull = *m.hull;
  s.size = BoxDiagonal(m.muscle->points);
  const MeanValueCoordinateCalculator coordinates(hull);
  if (m.weights && (m.weights->rows() != m.muscle->points.rows() || m.weights->cols() != hull.points.rows()))
  {
    throw InputError("the mean value coordinates given for muscle '" + m.name + "' do not fit its points and hull");
  }
  if (m.detail && m.detail->rows() != m.muscle->points.rows())
  {
    throw InputError("the detail given for muscle '" + m.name + "' does not fit its points");
  }
  if (!m.weights)
  {
    s.ownWeights = coordinates.Compute(m.muscle->points);
  }
  s.weights = m.weights ? m.weights : &s.ownWeights;

  Points restSamples;
  Points& currentSamples = s.currentSamples;
  SampleMatchedLines(m.lines, parameters.samplesPerSegment, restSamples, currentSamples);
  CheckLinesPassThrough(m, parameters.samplesPerSegment);
  const WeightMatrix sampleWeights = coordinates.Compute(restSamples);
  const std::vector<Eigen::Index> anchored = HullPointsNoLineDrives(hull, restSamples);
  if (!anchored.empty())
  {
    s.result.warnings.push_back(PartApartWarning(m.name, static_cast<std::int64_t>(anchored.size()),
      static_cast<std::int64_t>(hull.points.rows()), "its coarse hull"));
  }

  const SparseMatrix laplacian = CotangentLaplacian(hull);
  const Points delta = laplacian * hull.points;
  const double followWeight = std::max(0.0, parameters.followWeight);
  const Eigen::Index followStart = delta.rows() + currentSamples.rows() + static_cast<Eigen::Index>(anchored.size());
  s.targets.resize(followStart + (followWeight > 0 ? hull.points.rows() : 0), 3);
  for (Eigen::Index i = 0; i < delta.rows(); ++i)
  {
    // Rotated as the nearest action-line segment turns.
    s.targets.row(i) =
      (NearestSegment(hull.points.row(i).transpose(), m.lines).Rotation() * delta.row(i).transpose()).transpose();
  }
  s.targets.middleRows(delta.rows(), currentSamples.rows()) = currentSamples;
  for (size_t a = 0; a < anchored.size(); ++a)
  {
    s.targets.row(delta.rows() + currentSamples.rows() + static_cast<Eigen::Index>(a)) =
      NearestSegment(hull.points.row(anchored[a]).transpose(), m.lines)
        .Follow(hull.points.row(anchored[a]).transpose())
        .transpose();
  }
  if (followWeight > 0)
  {
    for (Eigen::Index i = 0; i < hull.points.rows(); ++i)
    {
      const Eigen::Vector3d p = hull.points.row(i).transpose();
      s.targets.row(followStart + i) = followWeight * NearestSegment(p, m.lines).Follow(p).transpose();
    }
  }
  s.solver = std::make_unique<VolumeConstrainedSolver>(
    StackRows(laplacian, sampleWeights, anchored, followWeight), hull.triangles);

  s.hull = hull.points;
  s.start = m.muscle->points;
  s.points = s.start;
  if (m.reference && m.reference->rows() != s.start.rows())
  {
    throw InputError("the reference shape given for muscle '" + m.name + "' does not fit its points");
  }
  s.reference = m.reference ? m.reference : &s.start;
  s.hullVolume = EnclosedVolume(hull.points, hull.triangles);
  const double ownVolume = EnclosedVolume(s.start, m.muscle->triangles);
  if (!(std::abs(ownVolume) > 0))
  {
    throw InputError("muscle '" + m.name + "' encloses no volume");
  }
  s.orientation = ownVolume > 0 ? 1.0 : -1.0;
  s.restVolume = m.targetVolume != 0 ? m.targetVolume : ownVolume;
  s.frozen.assign(static_cast<size_t>(s.start.rows()), 0);
  s.stopped.assign(static_cast<size_t>(s.start.rows()), 0);
  s.touched.assign(static_cast<size_t>(s.start.rows()), 0);

  if (parameters.measureSamplesInside)
  {
    s.result.restSamplesInside = FractionInside(TriangleTree(*m.muscle), restSamples);
  }
}

/// Coarse phase: the hull alone, its own volume held, no obstacles.
void RunCoarsePhase(MuscleState& s, const DeformationParameters& parameters)
{
  const double alpha = parameters.stepLength;
  const int limit = std::min(parameters.maximumCoarseIterations, parameters.maximumIterations);
  for (int k = 0; k < limit; ++k)
  {
    Points next;
    if (parameters.preserveVolume)
    {
      next = s.solver->Step(s.hull, s.targets, s.hullVolume, alpha);
    }
    else
    {
      next = s.solver->Step(s.hull, s.targets, 0.0, Points(), alpha);
    }
    const double change = (next - s.hull).cwiseAbs().maxCoeff();
    s.hull = next;
    ++s.result.coarseIterations;
    if (!next.allFinite())
    {
      throw ComputationError("the deformation of muscle '" + s.input->name + "' diverged on its hull");
    }
    if (change < parameters.convergenceTolerance)
    {
      break;
    }
  }
}

/// Contact rows (DeformationParameters::contactWeight): each point of the full
/// mesh (W X + detail) inside a bone it may not overlap gets a row pulling it
/// to that bone's nearest surface point, and the coarse phase runs again from
/// where it stopped; rounds until no new point comes in. A point keeps its row
/// and target once it has one, so that the rounds do not swing it in and out.
void PushOffBones(MuscleState& s, const std::vector<Obstacle>& bones, const DeformationParameters& parameters)
{
  const MuscleToDeform& m = *s.input;
  const Eigen::Index n = s.start.rows();
  const std::vector<std::vector<char>> noOverlap(bones.size(), std::vector<char>(static_cast<size_t>(n), 0));
  const std::vector<std::vector<char>>* allowed = m.boneOverlap ? m.boneOverlap : &noOverlap;
  if (allowed->size() != bones.size())
  {
    throw InputError("the bone overlap given for muscle '" + m.name + "' has " + std::to_string(allowed->size()) +
      " lists, for " + std::to_string(bones.size()) + " bones");
  }
  for (const std::vector<char>& overlap : *allowed)
  {
    if (overlap.size() != static_cast<size_t>(n))
    {
      throw InputError("the bone overlap given for muscle '" + m.name + "' does not fit its points");
    }
  }
  const std::vector<char> used = UsedMask(*m.muscle);

  std::unique_ptr<VolumeConstrainedSolver> base; // the system without contact rows, once there are some
  const Points baseTargets = s.targets;
  const double margin = 1e-3 * s.size; // just outside, so that the fine phase does not find it inside
  std::vector<Eigen::Index> contacts;
  std::vector<Eigen::Vector3d> targets;
  std::vector<char> inContact(static_cast<size_t>(n), 0);
  for (int round = 0; round < parameters.contactRounds; ++round)
  {
    Points points = *s.weights * s.hull;
    if (m.detail)
    {
      points += *m.detail;
    }
    std::vector<Eigen::Vector3d> found(static_cast<size_t>(n));
    std::vector<char> isNew(static_cast<size_t>(n), 0);
#pragma omp parallel for schedule(dynamic, 256)
    for (Eigen::Index i = 0; i < n; ++i)
    {
      if (inContact[i] || !used[i])
      {
        continue;
      }
      const Eigen::Vector3d p = points.row(i).transpose();
      for (size_t b = 0; b < bones.size(); ++b)
      {
        if ((*allowed)[b][i] || !bones[b].tree->InBounds(p) || !bones[b].tree->Inside(p))
        {
          continue;
        }
        const TriangleTree::Closest closest = bones[b].tree->ClosestPoint(p);
        if (closest.distance > 0)
        {
          found[i] = JustOutside(closest, p, margin);
          isNew[i] = 1;
        }
        break;
      }
    }
    const size_t before = contacts.size();
    for (Eigen::Index i = 0; i < n; ++i)
    {
      if (isNew[i])
      {
        inContact[i] = 1;
        contacts.push_back(i);
        targets.push_back(found[i]);
      }
    }
    if (contacts.size() == before)
    {
      break;
    }
    const Eigen::Index k = static_cast<Eigen::Index>(contacts.size());
    Eigen::MatrixXd rows(k, s.hull.rows());
    Points contactTargets(k, 3);
    for (Eigen::Index c = 0; c < k; ++c)
    {
      const Eigen::Index i = contacts[c];
      rows.row(c) = parameters.contactWeight * s.weights->row(i);
      // The row acts on W X, the target is for W X + detail.
      const Eigen::RowVector3d detail = m.detail ? Eigen::RowVector3d(m.detail->row(i)) : Eigen::RowVector3d::Zero();
      contactTargets.row(c) = parameters.contactWeight * (targets[c].transpose() - detail);
    }
    if (!base)
    {
      base = std::move(s.solver);
    }
    s.solver = std::make_unique<VolumeConstrainedSolver>(*base, rows);
    s.targets.resize(baseTargets.rows() + k, 3);
    s.targets.topRows(baseTargets.rows()) = baseTargets;
    s.targets.bottomRows(k) = contactTargets;
    RunCoarsePhase(s, parameters);
  }
  s.result.verticesInContact = static_cast<std::int64_t>(contacts.size());
}

/// How many times its starting span the muscle spans now: beyond
/// maximumGrowth it is being torn apart.
double Growth(const MuscleState& s)
{
  return BoxDiagonal(s.points) / s.size;
}

/// Moves every point of `s` from `points` to `candidate`, except where an
/// obstacle holds it.
void MoveWithObstacles(MuscleState& s, const Points& candidate, const std::vector<Obstacle>& bones,
  const std::vector<const MuscleState*>& others)
{
  const double backOff = 1e-6 * s.size;
  const Eigen::Index n = s.points.rows();
#pragma omp parallel for schedule(dynamic, 256)
  for (Eigen::Index i = 0; i < n; ++i)
  {
    s.stopped[i] = 0;
    if (s.frozen[i])
    {
      continue;
    }
    const Eigen::Vector3d from = s.points.row(i).transpose();
    const Eigen::Vector3d to = candidate.row(i).transpose();
    const double length = (to - from).norm();
    if (length == 0)
    {
      continue;
    }
    double first = 2; // fraction of the move where the earliest obstacle stops it
    for (const Obstacle& bone : bones)
    {
      if (auto hit = bone.tree->FirstHit(from, to); hit && hit->t < first)
      {
        first = hit->t;
      }
    }
    for (const MuscleState* other : others)
    {
      // Only entering moves are stopped: the hit triangle faces the move.
      if (auto hit = other->tree->FirstHit(from, to);
          hit && hit->t < first && other->orientation * other->tree->Normal(hit->triangle).dot(to - from) < 0)
      {
        first = hit->t;
      }
    }
    if (first <= 1)
    {
      const double t = std::max(0.0, first - backOff / length);
      s.points.row(i) = (from + t * (to - from)).transpose();
      s.stopped[i] = 1;
      s.touched[i] = 1;
    }
    else
    {
      s.points.row(i) = candidate.row(i);
    }
  }
}

/// Points of `members` (not frozen) inside a bone go to its nearest surface
/// point, just outside.
void SlideOnBones(MuscleState& s, const std::vector<Obstacle>& bones, const std::vector<Eigen::Index>& members)
{
  const double backOff = 1e-6 * s.size;
#pragma omp parallel for schedule(dynamic, 16)
  for (Eigen::Index a = 0; a < static_cast<Eigen::Index>(members.size()); ++a)
  {
    const Eigen::Index i = members[a];
    if (s.frozen[i])
    {
      continue;
    }
    const Eigen::Vector3d p = s.points.row(i).transpose();
    for (const Obstacle& bone : bones)
    {
      if (bone.tree->InBounds(p) && bone.tree->Inside(p))
      {
        const TriangleTree::Closest closest = bone.tree->ClosestPoint(p);
        if (closest.distance > 0)
        {
          s.points.row(i) = JustOutside(closest, p, backOff).transpose();
        }
        break;
      }
    }
  }
}

/// Points of `members` inside a bone, deeper than they were at `before` (or
/// not inside it then), go back to `before` and are pinned. Returns how many.
std::int64_t PinDeeperInBones(MuscleState& s, const std::vector<Obstacle>& bones,
  const std::vector<Eigen::Index>& members, const Points& before, std::vector<char>& pinned)
{
  std::int64_t count = 0;
#pragma omp parallel for reduction(+ : count) schedule(dynamic, 16)
  for (Eigen::Index a = 0; a < static_cast<Eigen::Index>(members.size()); ++a)
  {
    const Eigen::Index i = members[a];
    const Eigen::Vector3d p = s.points.row(i).transpose(), was = before.row(i).transpose();
    for (const Obstacle& bone : bones)
    {
      if (!bone.tree->InBounds(p) || !bone.tree->Inside(p))
      {
        continue;
      }
      const bool wasInside = bone.tree->InBounds(was) && bone.tree->Inside(was);
      if (!wasInside || bone.tree->ClosestPoint(p).distance > bone.tree->ClosestPoint(was).distance)
      {
        s.points.row(i) = before.row(i);
        pinned[i] = 1;
        ++count;
      }
      break;
    }
  }
  return count;
}

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

/// Undoes folds of the full mesh (triangles the mapping turned over, where
/// the hull deformed too unevenly for its mean value coordinates): the points
/// around the flipped triangles take back the shape their neighbourhood has
/// in the reference shape (as-rigid-as-possible: local rotations, one small
/// sparse solve with the region's border fixed), the region growing until
/// nothing is flipped. With `onBones` (bones push the muscle) the reshaping
/// keeps to the bones: a point it carries into a bone slides on the bone's
/// surface, and a point already inside one that it would carry deeper stays
/// where it was, held as part of the region's border. Returns whether any
/// point moved.
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

std::vector<const MuscleState*> OthersOf(const MuscleState& s, const std::vector<MuscleState>& states)
{
  std::vector<const MuscleState*> others;
  for (const MuscleState& o : states)
  {
    if (&o != &s)
    {
      others.push_back(&o);
    }
  }
  return others;
}

/// The volume of the full mesh, its gradient with respect to the hull points
/// (held points do not move, so they do not count), and the held points.
double FullVolume(const MuscleState& s, Points& hullGradient)
{
  Points gradient;
  const double volume = EnclosedVolume(s.points, s.input->muscle->triangles, &gradient);
  for (Eigen::Index i = 0; i < gradient.rows(); ++i)
  {
    if (s.frozen[i] || s.touched[i])
    {
      gradient.row(i).setZero();
    }
  }
  hullGradient = s.weights->transpose() * gradient;
  return volume;
}
}

namespace
{
double SegmentDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
  return (a + SegmentFoot(p, a, b) * (b - a) - p).norm();
}
}

bool KnotsFit(const Knots& knots, Eigen::Index points)
{
  return knots.empty() ||
    (knots.size() >= 2 && knots.front() == 0 && knots.back() == points - 1 &&
      std::adjacent_find(knots.begin(), knots.end(), std::greater_equal<>()) == knots.end());
}

std::vector<std::string> LimitActionLinePoints(std::vector<MatchedLine>& lines, Eigen::Index maximumPoints)
{
  std::vector<std::string> notes;
  maximumPoints = std::max<Eigen::Index>(maximumPoints, 2);
  for (size_t l = 0; l < lines.size(); ++l)
  {
    MatchedLine& line = lines[l];
    const Eigen::Index n = line.rest.rows();
    if (n <= maximumPoints || line.current.rows() != n)
    {
      continue;
    }
    // The point of (first, last) that deviates most from its chord, in either pose.
    struct Span
    {
      double deviation;
      Eigen::Index first, last, worst;
      bool operator<(const Span& other) const { return this->deviation < other.deviation; }
    };
    auto span = [&](Eigen::Index first, Eigen::Index last) {
      Span out{ 0.0, first, last, -1 };
      for (Eigen::Index k = first + 1; k < last; ++k)
      {
        const double d = std::max(SegmentDistance(line.rest.row(k).transpose(), line.rest.row(first).transpose(),
                                    line.rest.row(last).transpose()),
          SegmentDistance(
            line.current.row(k).transpose(), line.current.row(first).transpose(), line.current.row(last).transpose()));
        if (d > out.deviation || out.worst < 0)
        {
          out.deviation = d;
          out.worst = k;
        }
      }
      return out;
    };
    // Deviations below rounding of the line's size: the points lie on the kept line.
    const double negligible = kDegenerateShare * BoxDiagonal(line.rest);
    std::vector<char> keep(static_cast<size_t>(n), 0);
    std::priority_queue<Span> queue;
    const Knots ends{ 0, n - 1 };
    const Knots& own = line.knots.empty() ? ends : line.knots;
    for (size_t j = 0; j < own.size(); ++j)
    {
      keep[static_cast<size_t>(own[j])] = 1;
      if (j + 1 < own.size())
      {
        queue.push(span(own[j], own[j + 1]));
      }
    }
    auto kept = static_cast<Eigen::Index>(own.size());
    double left = 0.0;
    while (!queue.empty())
    {
      const Span top = queue.top();
      if (top.worst < 0)
      {
        queue.pop();
        continue;
      }
      if (kept >= maximumPoints || top.deviation <= negligible)
      {
        left = top.deviation;
        break;
      }
      queue.pop();
      keep[static_cast<size_t>(top.worst)] = 1;
      ++kept;
      queue.push(span(top.first, top.worst));
      queue.push(span(top.worst, top.last));
    }
    MatchedLine reduced;
    reduced.rest.resize(kept, 3);
    reduced.current.resize(kept, 3);
    Eigen::Index r = 0;
    for (Eigen::Index k = 0; k < n; ++k)
    {
      if (keep[static_cast<size_t>(k)])
      {
        if (!line.knots.empty() && std::binary_search(line.knots.begin(), line.knots.end(), k))
        {
          reduced.knots.push_back(r);
        }
        reduced.rest.row(r) = line.rest.row(k);
        reduced.current.row(r) = line.current.row(k);
        ++r;
      }
    }
    line = std::move(reduced);
    std::ostringstream note;
    note << "action line " << l + 1 << " has " << n << " points; it was cut down to " << kept
         << " (the points left out lie within " << std::setprecision(3) << left << " of it)";
    notes.push_back(note.str());
  }
  return notes;
}

void SampleMatchedLines(
  const std::vector<MatchedLine>& lines, int samplesPerSegment, Points& restSamples, Points& currentSamples)
{
  samplesPerSegment = std::max(1, samplesPerSegment);
  Eigen::Index count = 0;
  for (const MatchedLine& line : lines)
  {
    ForEachSpan(line, [&](const LineSpan&) { count += samplesPerSegment; });
    ++count;
  }
  restSamples.resize(count, 3);
  currentSamples.resize(count, 3);
  Eigen::Index s = 0;
  for (const MatchedLine& line : lines)
  {
    ForEachSpan(line, [&](const LineSpan& span) {
      for (int j = 0; j < samplesPerSegment; ++j)
      {
        const double t = static_cast<double>(j) / samplesPerSegment;
        restSamples.row(s) = span.At(line.rest, line.rest, t).transpose();
        currentSamples.row(s) = span.At(line.rest, line.current, t).transpose();
        ++s;
      }
    });
    restSamples.row(s) = line.rest.bottomRows(1);
    currentSamples.row(s) = line.current.bottomRows(1);
    ++s;
  }
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

std::int64_t CountInsideTree(const TriangleTree& tree, const Points& points)
{
  std::int64_t inside = 0;
#pragma omp parallel for reduction(+ : inside) schedule(dynamic, 64)
  for (Eigen::Index i = 0; i < points.rows(); ++i)
  {
    const Eigen::Vector3d p = points.row(i).transpose();
    inside += tree.InBounds(p) && tree.Inside(p) ? 1 : 0;
  }
  return inside;
}

namespace
{
/// The index of a muscle's state among the muscles of the call.
size_t IndexOf(const MuscleState& s, const std::vector<MuscleToDeform>& muscles)
{
  return static_cast<size_t>(s.input - muscles.data());
}
}

std::vector<Obstacle> BuildObstacles(const std::vector<std::string>& names, const std::vector<TriangleMesh>& meshes)
{
  std::vector<Obstacle> obstacles(meshes.size());
  std::string error;
  std::vector<std::exception_ptr> failed(meshes.size()); // no exception may leave a parallel region
#pragma omp parallel for schedule(dynamic, 1)
  for (size_t b = 0; b < meshes.size(); ++b)
  {
    try
    {
      obstacles[b] = { names[b], std::make_shared<TriangleTree>(meshes[b]) };
    }
    catch (const InputError& e)
    {
#pragma omp critical
      error = "obstacle '" + names[b] + "': " + e.what();
    }
    catch (...)
    {
      failed[b] = std::current_exception();
    }
  }
  if (!error.empty())
  {
    throw InputError(error);
  }
  for (const std::exception_ptr& failure : failed)
  {
    if (failure)
    {
      std::rethrow_exception(failure);
    }
  }
  return obstacles;
}

namespace
{
/// Each muscle checked, set up and taken through the coarse phase on its hull (then pushed off
/// the bones where bones push): the first half of `report`'s range.
void RunCoarsePhases(std::vector<MuscleState>& states, const std::vector<MuscleToDeform>& muscles,
  const std::vector<Obstacle>& bones, const DeformationParameters& parameters,
  const std::function<void(double)>& report)
{
  const double share = 1.0 / std::max<size_t>(1, muscles.size());
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    const auto start = Clock::now();
    MuscleState& s = states[m];
    s.input = &muscles[m];
    try
    {
      Validate(muscles[m]);
      const Points used = UsedPoints(*muscles[m].muscle);
      for (const Obstacle& bone : bones)
      {
        if (EntirelyInside(*bone.tree, used))
        {
          throw InputError("muscle '" + muscles[m].name + "' lies entirely inside obstacle '" + bone.name +
            "' before it moves: are the obstacles in the current pose, in the same units as the muscle?");
        }
      }
      SetUp(s, parameters);
      report((m + 0.3) * share * 0.5);
      RunCoarsePhase(s, parameters);
      if (parameters.contactWeight > 0 && parameters.dynamicIntersections && !bones.empty()) // pushed by bones
      {
        PushOffBones(s, bones, parameters);
      }
    }
    catch (Error& e)
    {
      e.muscle = e.muscle.value_or(m); // this muscle's alone
      throw;
    }
    s.time += Clock::now() - start;
    report((m + 1) * share * 0.5);
  }
}

/// The fine phase starts from the coarse result, W X. Overlap with a bone there (present in the
/// rest pose already, or made by the bone's motion) is what the dynamic rule cannot undo: those
/// points stay, as the paper's rule says; the static resolution deals with them afterwards.
void StartFinePhase(MuscleState& s, const std::vector<MuscleToDeform>& muscles, const std::vector<Obstacle>& bones,
  const DeformationParameters& parameters)
{
  const auto start = Clock::now();
  s.fineStep = parameters.stepLength;
  s.points = *s.weights * s.hull;
  if (s.input->detail)
  {
    s.points += *s.input->detail;
  }
  // The coarse result torn apart (the muscle grown far beyond its size) is no start for the
  // fine phase, nor a result it could fall back on. (A hull point far off that hardly weighs on
  // the muscle is no harm.)
  if (Growth(s) > maximumGrowth)
  {
    throw OfMuscle(ComputationError("the deformation of muscle '" + s.input->name +
                     "' diverged on its hull: the muscle spans " + std::to_string(Growth(s)) +
                     " times its starting size after " + std::to_string(s.result.coarseIterations) + " iterations"),
      IndexOf(s, muscles));
  }
  if (parameters.dynamicIntersections)
  {
    const std::int64_t used = UsedPoints(*s.input->muscle).rows();
    for (const Obstacle& bone : bones)
    {
      std::int64_t inside = 0;
#pragma omp parallel for reduction(+ : inside) schedule(dynamic, 64)
      for (Eigen::Index i = 0; i < s.points.rows(); ++i)
      {
        const Eigen::Vector3d p = s.points.row(i).transpose();
        if (bone.tree->InBounds(p) && bone.tree->Inside(p))
        {
          s.frozen[i] = 1;
          ++inside;
        }
      }
      if (2 * inside > used)
      {
        s.result.warnings.push_back(std::to_string(inside) + " of " + std::to_string(used) + " points of muscle '" +
          s.input->name + "' are inside obstacle '" + bone.name +
          "'; they cannot move (are the obstacles in the current pose?)");
      }
    }
    s.tree = std::make_unique<TriangleTree>(TriangleMesh{ s.points, s.input->muscle->triangles });
  }
  s.time += Clock::now() - start;
}

/// Muscles as obstacles for each other: the coarse phase moved each one without regard to the
/// others. A point that now lies inside another muscle but did not in the rest pose (new
/// overlap) moves out to the nearest point of that muscle's surface (in turn, each muscle
/// against the others' latest shape; back along its way would drag it far when both muscles
/// moved together). Overlap the scans already had is left alone.
void SeparateMuscles(std::vector<MuscleState>& states)
{
  std::vector<std::unique_ptr<TriangleTree>> restTrees;
  for (const MuscleState& s : states)
  {
    restTrees.push_back(std::make_unique<TriangleTree>(*s.input->muscle));
  }
  for (MuscleState& s : states)
  {
    const auto start = Clock::now();
    for (size_t o = 0; o < states.size(); ++o)
    {
      const MuscleState& other = states[o];
      if (&other == &s)
      {
        continue;
      }
#pragma omp parallel for schedule(dynamic, 64)
      for (Eigen::Index i = 0; i < s.points.rows(); ++i)
      {
        const Eigen::Vector3d p = s.points.row(i).transpose(), rest = s.start.row(i).transpose();
        if (s.frozen[i] || !other.tree->InBounds(p) || !other.tree->Inside(p) ||
          (restTrees[o]->InBounds(rest) && restTrees[o]->Inside(rest)))
        {
          continue;
        }
        const TriangleTree::Closest closest = other.tree->ClosestPoint(p);
        if (closest.distance > 0)
        {
          s.points.row(i) = JustOutside(closest, p, 1e-6 * s.size).transpose();
          s.touched[i] = 1;
        }
      }
    }
    s.tree->Refit(s.points);
    s.time += Clock::now() - start;
  }
}

/// One fine-phase iteration of muscle `s` against the bones and the other muscles' latest shape
/// (`states`): a Gauss-Newton step of its hull with the full mesh's volume, the muscle moved with
/// it as the obstacles allow; on convergence any fold undone and the volume let settle again
/// (a few times at most); a muscle torn apart keeps its coarse result.
void FineIteration(MuscleState& s, std::vector<MuscleState>& states, const std::vector<MuscleToDeform>& muscles,
  const std::vector<Obstacle>& bones, const DeformationParameters& parameters)
{
  Points next;
  if (parameters.preserveVolume)
  {
    Points gradient;
    const double volume = FullVolume(s, gradient);
    next = s.solver->Step(s.hull, s.targets, volume - s.restVolume, gradient, s.fineStep);
  }
  else
  {
    next = s.solver->Step(s.hull, s.targets, 0.0, Points(), s.fineStep);
  }
  if (!next.allFinite())
  {
    throw OfMuscle(ComputationError("the deformation of muscle '" + s.input->name + "' diverged on its full mesh"),
      IndexOf(s, muscles));
  }
  const Points change = next - s.hull;
  const double largest = change.cwiseAbs().maxCoeff();
  // Points held by obstacles make the full mesh's volume respond less than the step assumes,
  // and full steps can then swing back and forth: a change larger than the last halves the
  // step length.
  if (largest > s.lastChange)
  {
    s.fineStep = std::max(0.5 * s.fineStep, 0.05);
  }
  s.lastChange = largest;
  s.hull = next;
  const Points candidate = s.points + *s.weights * change;
  if (parameters.dynamicIntersections)
  {
    MoveWithObstacles(s, candidate, bones, OthersOf(s, states));
    s.tree->Refit(s.points);
  }
  else
  {
    s.points = candidate;
  }
  ++s.result.iterations;
  const int total = s.result.coarseIterations + s.result.iterations;
  const bool pushedByBones = parameters.contactWeight > 0 && parameters.dynamicIntersections;
  if (Growth(s) > maximumGrowth)
  {
    // With many points held by obstacles the hull, which knows nothing of them, can run on
    // through a bone while the volume held on the full mesh inflates the rest: the muscle is
    // torn apart. It keeps its coarse result (the static resolution settles its overlap).
    s.points = s.fineStartPoints;
    s.hull = s.fineStartHull;
    if (s.tree)
    {
      s.tree->Refit(s.points);
    }
    s.fellBack = s.fineDone = true;
    s.result.warnings.push_back("the fine phase of muscle '" + s.input->name + "' diverged (" +
      std::to_string(
        std::count(s.frozen.begin(), s.frozen.end(), 1) + std::count(s.touched.begin(), s.touched.end(), 1)) +
      " points held by obstacles): the muscle keeps its coarse result, without the volume of its full mesh held");
  }
  else if (largest < parameters.convergenceTolerance)
  {
    // Converged: undo any fold, then let the volume settle again (a few times at most).
    if (s.unfoldings < maximumUnfoldings && !s.unfoldingBlocked &&
      UnfoldFlippedTriangles(s, bones, parameters.dynamicIntersections, pushedByBones))
    {
      ++s.unfoldings;
      s.lastChange = std::numeric_limits<double>::max();
      if (s.tree)
      {
        s.tree->Refit(s.points);
      }
    }
    else
    {
      s.converged = s.fineDone = true;
      // The check just found none and nothing moved since (unless folds were left held at a bone).
      s.flipsCheckedClean = s.unfoldings < maximumUnfoldings && !s.unfoldingBlocked;
    }
  }
  else if (total >= parameters.maximumIterations)
  {
    s.fineDone = true;
  }
}

/// What muscle `s`'s pass gives: its points and hull, volume change, flips, points held, and
/// whether it converged (one unconverged and torn apart throws; one unconverged but sound warns).
DeformationResult ResultOf(
  MuscleState& s, const std::vector<MuscleToDeform>& muscles, const DeformationParameters& parameters)
{
  const auto start = Clock::now();
  DeformationResult& r = s.result;
  r.iterations += r.coarseIterations;
  r.converged = s.converged;
  r.points = s.points;
  r.hullPoints = s.hull;
  const double volume = EnclosedVolume(s.points, s.input->muscle->triangles);
  r.volumeChangePercent = 100.0 * (volume - s.restVolume) / s.restVolume;
  r.flippedTriangles =
    s.flipsCheckedClean ? 0 : CountFlippedTriangles(*s.reference, s.points, s.input->muscle->triangles);
  for (size_t i = 0; i < s.frozen.size(); ++i)
  {
    r.verticesFrozen += s.frozen[i];
    r.verticesStopped += s.stopped[i];
  }
  if (parameters.measureSamplesInside)
  {
    r.currentSamplesInside =
      FractionInside(TriangleTree(TriangleMesh{ s.points, s.input->muscle->triangles }), s.currentSamples);
  }
  if (!r.converged)
  {
    // Unconverged but sound (a small swing) is a warning; unconverged and torn apart (volume far
    // off, or the muscle grown far beyond its size) is no result to hand on.
    if (!s.fellBack &&
      ((parameters.preserveVolume && std::abs(r.volumeChangePercent) > 10.0) || Growth(s) > maximumGrowth))
    {
      throw OfMuscle(ComputationError("the deformation of muscle '" + s.input->name + "' diverged: after " +
                       std::to_string(parameters.maximumIterations) + " iterations its volume is off by " +
                       std::to_string(r.volumeChangePercent) + " % and it spans " + std::to_string(Growth(s)) +
                       " times its starting size"),
        IndexOf(s, muscles));
    }
    if (!s.fellBack)
    {
      r.warnings.push_back("muscle '" + s.input->name + "' did not converge in " +
        std::to_string(parameters.maximumIterations) + " iterations");
    }
  }
  s.time += Clock::now() - start;
  r.seconds = std::chrono::duration<double>(s.time).count();
  return std::move(r);
}
}

std::vector<DeformationResult> DeformMuscles(const std::vector<MuscleToDeform>& muscles,
  const std::vector<Obstacle>& bones, const DeformationParameters& parameters,
  const std::function<void(double)>& progress)
{
  const std::function<void(double)> report = [&](double fraction) {
    if (progress)
    {
      progress(fraction);
    }
  };
  std::vector<MuscleState> states(muscles.size());
  RunCoarsePhases(states, muscles, bones, parameters, report);
  for (MuscleState& s : states)
  {
    StartFinePhase(s, muscles, bones, parameters);
  }
  if (parameters.dynamicIntersections && states.size() > 1)
  {
    SeparateMuscles(states);
  }
  // Fine phase: all muscles step in turn, each against the others' latest shape (each stops at
  // its own limit: maximumIterations less its coarse iterations).
  for (MuscleState& s : states)
  {
    s.fineStartPoints = s.points;
    s.fineStartHull = s.hull;
  }
  const int fineLimit = parameters.maximumIterations;
  for (int k = 0; k < fineLimit; ++k)
  {
    bool anyActive = false;
    for (MuscleState& s : states)
    {
      if (s.fineDone)
      {
        continue;
      }
      const auto start = Clock::now();
      anyActive = true;
      FineIteration(s, states, muscles, bones, parameters);
      s.time += Clock::now() - start;
    }
    report(0.5 + 0.5 * (k + 1) / std::max(1, fineLimit));
    if (!anyActive)
    {
      break;
    }
  }
  std::vector<DeformationResult> results;
  for (MuscleState& s : states)
  {
    results.push_back(ResultOf(s, muscles, parameters));
  }
  report(1.0);
  return results;
}

std::vector<DeformationResult> DeformMusclesThatCan(const std::vector<MuscleToDeform>& muscles,
  const std::vector<Obstacle>& bones, const DeformationParameters& parameters, std::vector<std::string>& failures,
  const std::function<void(double)>& progress)
{
  return ForMusclesThatCan(muscles, failures, progress,
    [&](const std::vector<MuscleToDeform>& subset, const std::function<void(double)>& forward) {
      return DeformMuscles(subset, bones, parameters, forward);
    });
}

std::string PartApartWarning(const std::string& muscle, std::int64_t points, std::int64_t of, const std::string& what)
{
  return "part of muscle '" + muscle + "' lies apart from the rest, and no action line passes through it (" +
    std::to_string(points) + " of the " + std::to_string(of) + " points of " + what +
    "): it moves with the nearest action-line segment; give that part an action line of its own if it should "
    "move otherwise";
}
}
