// SPDX-License-Identifier: BSD-3-Clause
// Matching of rest-pose and current-pose action lines (Hajkova & Kohout, sec. 4.2, eq. 2).
#pragma once

#include "Common/MeshTypes.h"

#include <vector>

namespace md
{
/// Normalised arc-length parameter of every point: t_0 = 0, t_last = 1.
/// Throws InputError for fewer than two points, non-finite points or zero length.
std::vector<double> NormalisedArcLength(const Points& line);

/// The point of a polyline at normalised arc length s in [0, 1], given the
/// parameters from NormalisedArcLength.
Eigen::RowVector3d PointAtParameter(const Points& line, const std::vector<double>& parameters, double s);

/// The default matching tolerance (in normalised arc length): the filters'.
constexpr double kDefaultMatchingTolerance = 0.01;

/// The matching tolerance actually applied: the requested one, capped at half
/// the smallest positive spacing of parameters along either line. With that cap
/// every point has at most one partner within tolerance and matched pairs keep
/// the order of both lines, so the matched lines never double back.
double EffectiveMatchingTolerance(
  const std::vector<double>& restParameters, const std::vector<double>& currentParameters, double requestedTolerance);

struct MatchedActionLines
{
  Points rest;                           ///< matched RP line: every original RP point plus inserted ones
  Points current;                        ///< matched CP line, same number of points, pairwise matched
  std::vector<double> restParameters;    ///< normalised arc length on the RP line
  std::vector<double> currentParameters; ///< normalised arc length on the CP line
  std::vector<bool> restInserted;        ///< point was inserted on the RP line
  std::vector<bool> currentInserted;     ///< point was inserted on the CP line
  double tolerance = 0;                  ///< effective tolerance used
};

/// Match two polylines: each RP point P_i takes, in increasing j, the first
/// unmatched CP point with |t_i - t'_j| <= tolerance, or a new CP point inserted
/// at t' = t_i; CP points left unmatched get a new RP point at t = t'_j. Both
/// results list the matched pairs in order along the lines.
MatchedActionLines MatchActionLines(const Points& rest, const Points& current, double tolerance);

/// The own points `own` of a rest line (rising indices of its points) as indices of its matched
/// line, whose points are the line's own and those matching inserted (`restInserted`).
Knots MatchedKnots(const Knots& own, const std::vector<bool>& restInserted);
}
