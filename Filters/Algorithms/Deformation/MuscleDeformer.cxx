// SPDX-License-Identifier: BSD-3-Clause
#include "Deformation/MuscleDeformer.h"

#include "Common/MuscleFailures.h"
#include "Deformation/DeformerState.h"
#include "Deformation/NearestSegment.h"
#include "Deformation/VolumeConstrainedSolver.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/RigidMotion.h"

#include <Eigen/SparseCholesky>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>

namespace md
{
namespace
{
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
}

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

namespace
{
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
