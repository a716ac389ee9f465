// SPDX-License-Identifier: BSD-3-Clause
#include "SurfaceSettle.h"

#include "MeshChecks.h"
#include "NearestSegment.h"
#include "TriangleTree.h"
#include "VolumeConstrainedSolver.h"

#include <Eigen/SparseCholesky>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

namespace md
{
namespace
{
using Clock = std::chrono::steady_clock;

/// Barycentric coordinates of q (on the triangle's plane) in triangle t of `mesh`.
Eigen::Vector3d Barycentric(const TriangleMesh& mesh, Eigen::Index t, const Eigen::Vector3d& q)
{
  const Eigen::Vector3d a = mesh.points.row(mesh.triangles(t, 0)).transpose();
  const Eigen::Vector3d b = mesh.points.row(mesh.triangles(t, 1)).transpose();
  const Eigen::Vector3d c = mesh.points.row(mesh.triangles(t, 2)).transpose();
  const Eigen::Vector3d normal = (b - a).cross(c - a);
  const double area = normal.squaredNorm();
  if (!(area > 0))
  {
    return Eigen::Vector3d::Constant(1.0 / 3.0);
  }
  const double u = (c - b).cross(q - b).dot(normal) / area;
  const double v = (a - c).cross(q - c).dot(normal) / area;
  return { u, v, 1 - u - v };
}

using RowEntries = std::vector<std::pair<std::int64_t, double>>;

/// The sample p (inside the surface) as a combination of surface points: along
/// each axis the chord through p meets the surface at h+ (distance d+) and h-
/// (d-), and p = (d- h+ + d+ h-) / (d+ + d-), each hit a combination of its
/// triangle's corners; the mean over the axes that have both hits. Empty when
/// no axis has.
RowEntries ChordRow(const TriangleTree& tree, const Eigen::Vector3d& p, double reach)
{
  const TriangleMesh& mesh = tree.Mesh();
  RowEntries entries;
  int chords = 0;
  for (int axis = 0; axis < 3; ++axis)
  {
    const Eigen::Vector3d way = reach * Eigen::Vector3d::Unit(axis);
    const auto ahead = tree.FirstHit(p, p + way), behind = tree.FirstHit(p, p - way);
    if (!ahead || !behind || !(ahead->t + behind->t > 0))
    {
      continue;
    }
    const double toAhead = ahead->t / (ahead->t + behind->t); // share of the hit behind
    for (const auto& [hit, share] : { std::pair{ *ahead, 1 - toAhead }, std::pair{ *behind, toAhead } })
    {
      const Eigen::Vector3d weights = Barycentric(mesh, hit.triangle, hit.point);
      for (int k = 0; k < 3; ++k)
      {
        entries.emplace_back(mesh.triangles(hit.triangle, k), share * weights(k));
      }
    }
    ++chords;
  }
  for (auto& entry : entries)
  {
    entry.second /= chords;
  }
  return entries;
}

/// Where a contact row pulls p: `offset` outside the surface whose point
/// nearest to p is `closest`, p being inside or (within the band a contact
/// is kept in) outside.
Eigen::Vector3d ContactTarget(
  const TriangleTree& tree, const TriangleTree::Closest& closest, const Eigen::Vector3d& p, bool inside, double offset)
{
  if (!(closest.distance > 0))
  {
    return closest.point + offset * tree.Normal(closest.triangle);
  }
  return inside ? JustOutside(closest, p, offset) : closest.point + (offset / closest.distance) * (p - closest.point);
}
}

SurfaceEnergy::SurfaceEnergy(
  const TriangleMesh& rest, const std::vector<Points>& restLines, const SettleParameters& parameters)
  : RestPoints(rest.points)
  , SamplesPerSegment(std::max(1, parameters.samplesPerSegment))
{
  const Eigen::Index n = rest.points.rows();
  this->PointUsed = UsedMask(rest);
  this->Span = BoxDiagonal(UsedPoints(rest));
  const Eigen::Index used = std::count(this->PointUsed.begin(), this->PointUsed.end(), 1);
  if (used == 0)
  {
    throw InputError("the surface has no triangles");
  }

  // The action-line samples inside the rest muscle, as sparse rows.
  std::vector<MatchedLine> still;
  for (const Points& line : restLines)
  {
    still.push_back({ line, line });
  }
  Points samples, unused;
  SampleMatchedLines(still, this->SamplesPerSegment, samples, unused);
  const TriangleTree tree(rest);
  std::vector<RowEntries> sampleRows;
  for (Eigen::Index s = 0; s < samples.rows(); ++s)
  {
    const Eigen::Vector3d p = samples.row(s).transpose();
    if (!tree.InBounds(p) || !tree.Inside(p))
    {
      continue;
    }
    RowEntries row = ChordRow(tree, p, 2 * this->Span);
    if (!row.empty())
    {
      this->SampleIndex.push_back(s);
      sampleRows.push_back(std::move(row));
    }
  }
  if (sampleRows.empty())
  {
    throw InputError("none of its action-line samples lies inside the muscle");
  }

  const SparseMatrix laplacian = CotangentLaplacian(rest);
  this->Delta = laplacian * rest.points;
  const double balance = std::max(1.0, parameters.balancePoints);
  this->ShapeWeight = std::sqrt(static_cast<double>(used) / balance);
  this->FollowWeight = std::max(0.0, parameters.followWeight) * std::sqrt(balance / static_cast<double>(used));

  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index i = 0; i < n; ++i)
  {
    if (!this->PointUsed[i])
    {
      this->Delta.row(i).setZero();
      continue;
    }
    for (SparseMatrix::InnerIterator it(laplacian, i); it; ++it)
    {
      entries.emplace_back(i, it.col(), this->ShapeWeight * it.value());
    }
  }
  const Eigen::Index sampleStart = n, followStart = n + this->SampleCount();
  for (size_t s = 0; s < sampleRows.size(); ++s)
  {
    for (const auto& [point, weight] : sampleRows[s])
    {
      entries.emplace_back(sampleStart + static_cast<Eigen::Index>(s), point, weight);
    }
  }
  for (Eigen::Index i = 0; i < n; ++i)
  {
    // A point no triangle uses has nothing else to place it.
    entries.emplace_back(followStart + i, i, this->PointUsed[i] ? this->FollowWeight : 1.0);
  }
  this->Rows.resize(followStart + n, n);
  this->Rows.setFromTriplets(entries.begin(), entries.end());
  this->Normal = SparseMatrix(this->Rows.transpose() * this->Rows);
}

Points SurfaceEnergy::RightHandSide(const std::vector<MatchedLine>& lines) const
{
  const Eigen::Index n = this->RestPoints.rows();
  Points targets(this->Rows.rows(), 3);
  for (Eigen::Index i = 0; i < n; ++i)
  {
    const Eigen::Vector3d p = this->RestPoints.row(i).transpose();
    const NearestSegment nearest(p, lines);
    targets.row(i) = this->ShapeWeight * (nearest.Rotation() * this->Delta.row(i).transpose()).transpose();
    targets.row(n + this->SampleCount() + i) =
      (this->PointUsed[i] ? this->FollowWeight : 1.0) * nearest.Follow(p).transpose();
  }
  Points restSamples, currentSamples;
  SampleMatchedLines(lines, this->SamplesPerSegment, restSamples, currentSamples);
  for (Eigen::Index s = 0; s < this->SampleCount(); ++s)
  {
    targets.row(n + s) = currentSamples.row(this->SampleIndex[static_cast<size_t>(s)]);
  }
  return this->Rows.transpose() * targets;
}

namespace
{
/// One muscle through the settle.
struct SettleState
{
  Points base;            // right-hand side without contact
  std::vector<char> held; // points with a contact row
  Points targets;         // where those rows pull
  Eigen::SimplicialLDLT<SparseMatrix> solver;
  bool factorised = false;
  double seconds = 0;
};
}

std::vector<SettleReport> SettleMuscles(std::vector<TriangleMesh>& meshes,
  const std::vector<const SurfaceEnergy*>& energies, const std::vector<std::vector<MatchedLine>>& lines,
  const std::vector<double>& volumes, const std::vector<FixedObstacle>& bones, const OverlapMasks* restOverlap,
  const SettleParameters& parameters)
{
  // Contact: a point inside an obstacle (or held by a row and still within a small offset
  // of its surface) gets a row pulling it just outside. The row's target is taken where the
  // point would go without it (its position moved back by the row's pull through its own
  // stiffness), so that a point in contact slides along the surface as the energy wants
  // instead of being held where it first touched; a row whose point the energy pulls away
  // lets go. The matrix is factorised again only when the set of rows changes.
  const size_t count = meshes.size();
  std::vector<SettleReport> reports(count);
  const double contact = parameters.contactWeight * parameters.contactWeight;
  const double share = std::clamp(parameters.muscleShare, 0.0, 1.0);
  auto seconds = [](Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
  };
  std::vector<SettleState> states(count);
  for (size_t m = 0; m < count; ++m)
  {
    const auto start = Clock::now();
    SettleState& state = states[m];
    state.base = energies[m]->RightHandSide(lines[m]);
    state.solver.analyzePattern(energies[m]->NormalMatrix());
    state.held.assign(static_cast<size_t>(meshes[m].points.rows()), 0);
    state.targets = Points::Zero(meshes[m].points.rows(), 3);
    state.seconds += seconds(start);
  }
  std::vector<std::unique_ptr<TriangleTree>> trees(count);
  for (int iteration = 0; iteration < parameters.maximumIterations; ++iteration)
  {
#pragma omp parallel for schedule(dynamic, 1)
    for (int m = 0; m < static_cast<int>(count); ++m)
    {
      if (trees[m])
      {
        trees[m]->Refit(meshes[m].points);
      }
      else
      {
        trees[m] = std::make_unique<TriangleTree>(meshes[m]);
      }
    }
    auto obstacle = [&](size_t o) -> const TriangleTree& {
      return o < bones.size() ? *bones[o].tree : *trees[o - bones.size()];
    };
    bool settled = true;
    std::vector<Points> next(count);
    for (size_t m = 0; m < count; ++m)
    {
      const auto start = Clock::now();
      SettleState& state = states[m];
      const SurfaceEnergy& energy = *energies[m];
      const SparseMatrix& normal = energy.NormalMatrix();
      const Points& x = meshes[m].points;
      const Eigen::Index n = x.rows();
      const double offset = 1e-3 * energy.Size();
      std::vector<char> held(static_cast<size_t>(n), 0);
      Points targets = Points::Zero(n, 3);
#pragma omp parallel for schedule(dynamic, 256)
      for (Eigen::Index i = 0; i < n; ++i)
      {
        if (!energy.Used()[i])
        {
          continue;
        }
        Eigen::Vector3d p = x.row(i).transpose();
        if (state.held[i])
        {
          // Where the point would be without its row.
          p -= contact * (state.targets.row(i).transpose() - p) / normal.coeff(i, i);
        }
        for (size_t o = 0; o < bones.size() + count && !held[i]; ++o)
        {
          if ((o >= bones.size() && o - bones.size() == m) || InOverlap(restOverlap, m, o, i))
          {
            continue;
          }
          const TriangleTree& tree = obstacle(o);
          const bool inside = tree.InBounds(p) && tree.Inside(p);
          if (!inside && !state.held[i])
          {
            continue;
          }
          const TriangleTree::Closest closest = tree.ClosestPoint(p);
          if (!inside && closest.distance >= offset)
          {
            continue; // the energy pulls it away: the row lets go
          }
          const Eigen::Vector3d target = ContactTarget(tree, closest, p, inside, offset);
          targets.row(i) = (o < bones.size() ? target : Eigen::Vector3d(p + share * (target - p))).transpose();
          held[i] = 1;
        }
      }
      const bool sameRows = held == state.held;
      if (!sameRows || !state.factorised)
      {
        SparseMatrix system = normal;
        for (Eigen::Index i = 0; i < n; ++i)
        {
          if (held[i])
          {
            system.coeffRef(i, i) += contact;
          }
        }
        state.solver.factorize(system);
        if (state.solver.info() != Eigen::Success)
        {
          throw OfMuscle(ComputationError("the full-mesh system of a muscle could not be factorised"), m);
        }
        state.factorised = true;
      }
      state.held = std::move(held);
      state.targets = std::move(targets);
      Points rhs = state.base;
      for (Eigen::Index i = 0; i < n; ++i)
      {
        if (state.held[i])
        {
          rhs.row(i) += contact * state.targets.row(i);
        }
      }
      // The volume held by a Lagrange multiplier on its linearisation at x.
      Points gradient;
      const double volume = EnclosedVolume(x, meshes[m].triangles, &gradient);
      const Eigen::MatrixXd g = gradient;
      const Eigen::MatrixXd free = state.solver.solve(Eigen::MatrixXd(rhs));
      const Eigen::MatrixXd along = state.solver.solve(g);
      const double rate = (g.array() * along.array()).sum();
      const double linear = volume + (g.array() * (free - x).array()).sum() - volumes[m];
      next[m] = free - (rate > 0 ? linear / rate : 0.0) * along;
      if (!next[m].allFinite())
      {
        throw OfMuscle(ComputationError("the full-mesh deformation of a muscle diverged"), m);
      }
      const double change = (next[m] - x).cwiseAbs().maxCoeff();
      reports[m].iterations = iteration + 1;
      reports[m].pointsInContact = std::count(state.held.begin(), state.held.end(), 1);
      if (change > parameters.tolerance * energy.Size() || !sameRows ||
        std::abs(volume - volumes[m]) > 1e-9 * std::abs(volumes[m]))
      {
        settled = false;
      }
      state.seconds += seconds(start);
    }
    for (size_t m = 0; m < count; ++m)
    {
      meshes[m].points = std::move(next[m]);
    }
    if (settled)
    {
      for (SettleReport& report : reports)
      {
        report.converged = true;
      }
      break;
    }
  }
  for (size_t m = 0; m < count; ++m)
  {
    reports[m].seconds = states[m].seconds;
  }
  return reports;
}
}
