// SPDX-License-Identifier: BSD-3-Clause
// The one pass's contact with the bones and the other muscles (docs/DESIGN.md section 4): the
// bones' contact rows, and moves that stop where a point would go into an obstacle.
#include "Deformation/DeformerState.h"

#include "Geometry/MeshChecks.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

namespace md
{
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

double Growth(const MuscleState& s)
{
  return BoxDiagonal(s.points) / s.size;
}

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
}
