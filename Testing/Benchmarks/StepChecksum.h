// SPDX-License-Identifier: BSD-3-Clause
// A checksum of a step's (or a frame's) muscles and measures, so that two runs of a benchmark can
// be compared to the bit: a change that should not move a bit (a refactoring) is checked by it.
#pragma once

#include "Common/Fnv1a.h"
#include "Method/InterpolatedDeformation.h"

#include <cstdint>
#include <vector>

/// Adds every point of `points` and the deterministic measures of `measures` (not the times).
inline void AddStepToChecksum(
  md::Fnv1a& checksum, const std::vector<md::Points>& points, const std::vector<md::MuscleStepMeasures>& measures)
{
  for (const md::Points& p : points)
  {
    checksum.Add(p.data(), sizeof(double) * static_cast<size_t>(p.size()));
  }
  for (const md::MuscleStepMeasures& s : measures)
  {
    for (const double value : { s.volumeChangePercent, s.maxNewPenetrationDepth, s.maxNewBonePenetrationDepth,
           s.stepStaticShift, s.maxStaticShift })
    {
      checksum.Add(value);
    }
    for (const std::int64_t count : { s.newPenetrationCount, s.newBonePenetrationCount, s.staticallyMovedPoints,
           s.sharpEdgeCount, s.flippedTriangleCount, static_cast<std::int64_t>(s.stepIterations) })
    {
      checksum.Add(count);
    }
  }
}
