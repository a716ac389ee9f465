// SPDX-License-Identifier: BSD-3-Clause
// Moment arms by tendon excursion along a motion: r = -dL/dq from the lengths at its frames.
#pragma once

#include <cstddef>
#include <vector>

namespace md
{
/// A coordinate moves between two frames when it changes by more than this (radians, or the
/// coordinate's unit) and the others by no more.
constexpr double kCoordinateMoves = 1e-9;

/// The moment arm about each coordinate at every frame of a motion, r = -dL/dq (OpenSim's sign:
/// positive where increasing q shortens the length), from `lengths[k]` and `coordinates[k][c]`
/// (radians for a rotational coordinate) at frames k = 0, 1, ...: a central difference over
/// frames k - 1 and k + 1 where exactly one coordinate moves between them, else a one-sided
/// difference with frame k - 1 or k + 1 where exactly one moves between that frame and k. About
/// a coordinate that does not move there, or where several move at once (the difference cannot
/// tell them apart), NaN. Exact for a length linear in q; O(dq^2) central.
std::vector<std::vector<double>> MomentArmsAlongMotion(
  const std::vector<std::vector<double>>& coordinates, const std::vector<double>& lengths);

/// The difference MomentArmsAlongMotion takes at a frame: r = -(L[to] - L[from]) / (q[to] -
/// q[from]) of coordinate `coordinate`; none (coordinate -1) where it has no moment arm.
struct ExcursionDifference
{
  std::size_t from = 0, to = 0;
  int coordinate = -1;
  double dq = 0; ///< q[to] - q[from] of that coordinate
  /// The moment arm of `lengths` at this frame (NaN for none).
  double Of(const std::vector<double>& lengths) const;
  /// The moment arm of a length that is `atFrom` at frame `from` and `atTo` at frame `to`.
  double Of(double atFrom, double atTo) const { return -(atTo - atFrom) / this->dq; }
};
/// The differences at every frame of `coordinates` (as MomentArmsAlongMotion): found once, they
/// serve every length measured over the same frames.
std::vector<ExcursionDifference> ExcursionDifferences(const std::vector<std::vector<double>>& coordinates);
}
