// SPDX-License-Identifier: BSD-3-Clause
// Where each settle of a motion starts (docs/DESIGN.md section 7, "Where each settle starts"):
// the rest pose, the unconstrained minima and how far they move, the parts a step is settled in,
// and the bones' clearances carried from one settle to the next.
#include "Settle/SurfaceSettle.h"

#include "Geometry/RigidMotion.h"

#include <algorithm>
#include <cmath>
#include <memory>

namespace md
{
SettleMotion StartMotion(const std::vector<TriangleMesh>& muscles, const std::vector<const SurfaceEnergy*>& energies,
  const std::vector<std::vector<MatchedLine>>& restLines, const std::vector<FixedObstacle>& restBones)
{
  SettleMotion motion;
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    motion.points.push_back(muscles[m].points);
    motion.restDepths.push_back(energies[m]->SampleDepthsInBones(restLines[m], restBones));
  }
  motion.free = FreeMinima(energies, restLines, restBones);
  auto reference = std::make_shared<std::vector<Points>>();
  for (const FixedObstacle& bone : restBones)
  {
    reference->push_back(bone.tree->Mesh().points);
  }
  motion.boneReference = std::move(reference);
  return motion;
}

std::vector<std::vector<char>> ProvenOutsideBones(const std::vector<std::vector<double>>& boneClearance)
{
  std::vector<std::vector<char>> outside(boneClearance.size());
  for (size_t m = 0; m < boneClearance.size(); ++m)
  {
    outside[m].resize(boneClearance[m].size());
    std::transform(boneClearance[m].begin(), boneClearance[m].end(), outside[m].begin(),
      [](double c) { return static_cast<char>(c > 0); });
  }
  return outside;
}

std::vector<RigidFit> PlaceBones(
  const std::shared_ptr<const std::vector<Points>>& reference, const std::vector<FixedObstacle>& bones)
{
  if (!reference || reference->size() != bones.size())
  {
    return {};
  }
  for (size_t b = 0; b < bones.size(); ++b)
  {
    if ((*reference)[b].rows() != bones[b].tree->Mesh().points.rows() || (*reference)[b].rows() == 0)
    {
      return {};
    }
  }
  std::vector<RigidFit> placements(bones.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (int b = 0; b < static_cast<int>(bones.size()); ++b)
  {
    placements[b] = FitRigidTransform((*reference)[b], bones[b].tree->Mesh().points);
  }
  return placements;
}

std::vector<std::vector<double>> BoneClearancesNow(
  const SettleMotion& motion, const std::vector<TriangleMesh>& muscles, const std::vector<RigidFit>& placements)
{
  const size_t count = muscles.size(), bones = placements.size(), obstacles = bones + count;
  if (bones == 0 || motion.bonePlacements.size() != bones || motion.boneClearance.size() != count ||
    motion.points.size() != count)
  {
    return {};
  }
  for (size_t m = 0; m < count; ++m)
  {
    if (motion.points[m].rows() != muscles[m].points.rows() ||
      motion.boneClearance[m].size() != static_cast<size_t>(muscles[m].points.rows()) * bones)
    {
      return {};
    }
  }
  std::vector<std::vector<double>> now(count);
  for (size_t m = 0; m < count; ++m)
  {
    const Points& then = motion.points[m];
    const Points& points = muscles[m].points;
    now[m].assign(static_cast<size_t>(points.rows()) * obstacles, 0.0);
    for (size_t b = 0; b < bones; ++b)
    {
      const RigidTransform fromThen = Inverse(motion.bonePlacements[b].transform);
      const RigidTransform fromNow = Inverse(placements[b].transform);
      const double residuals = motion.bonePlacements[b].maxResidual + placements[b].maxResidual;
      for (Eigen::Index i = 0; i < points.rows(); ++i)
      {
        const double clearance = motion.boneClearance[m][static_cast<size_t>(i) * bones + b];
        if (!(clearance > 0))
        {
          continue;
        }
        const Eigen::Vector3d here = points.row(i).transpose(), there = then.row(i).transpose();
        const double moved = (fromNow.Apply(here) - fromThen.Apply(there)).norm();
        now[m][static_cast<size_t>(i) * obstacles + b] = std::max(0.0, clearance - moved - residuals);
      }
    }
  }
  return now;
}

std::vector<Points> FreeMinima(const std::vector<const SurfaceEnergy*>& energies,
  const std::vector<std::vector<MatchedLine>>& lines, const std::vector<FixedObstacle>& bones)
{
  std::vector<Points> free(energies.size());
  const std::vector<int> order = CostliestFirst(energies);
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < static_cast<int>(energies.size()); ++k)
  {
    const int m = order[static_cast<size_t>(k)];
    free[m] = energies[m]->Solve(energies[m]->RightHandSide(lines[m], bones));
  }
  return free;
}

double LargestStartMove(
  const SettleMotion& motion, const std::vector<const SurfaceEnergy*>& energies, const std::vector<Points>& freeMinima)
{
  const size_t count = energies.size();
  if (motion.free.size() != count || freeMinima.size() != count)
  {
    return 0;
  }
  double largest = 0;
  for (size_t m = 0; m < count; ++m)
  {
    largest = std::max(largest, (freeMinima[m] - motion.free[m]).rowwise().norm().maxCoeff() / energies[m]->Size());
  }
  return largest;
}

int SettleParts(double startMove, const SettleParameters& parameters, bool carriesContacts)
{
  constexpr int kMostParts = 64;
  const double largest = carriesContacts && parameters.largestCarriedMove > 0
    ? std::min(parameters.largestStartMove, parameters.largestCarriedMove)
    : parameters.largestStartMove;
  if (!(largest > 0))
  {
    return 1;
  }
  return static_cast<int>(std::clamp(std::ceil(startMove / largest), 1.0, double(kMostParts)));
}
}
