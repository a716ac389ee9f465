// SPDX-License-Identifier: BSD-3-Clause
#include "Motion/ActionLineMatching.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace md
{
std::vector<double> NormalisedArcLength(const Points& line)
{
  const Eigen::Index n = line.rows();
  if (n < 2)
  {
    throw InputError("an action line needs at least two points, this one has " + std::to_string(n));
  }
  if (!AllFinite(line))
  {
    throw InputError("an action line has non-finite (NaN or infinite) coordinates");
  }
  std::vector<double> t(static_cast<size_t>(n), 0.0);
  for (Eigen::Index i = 1; i < n; ++i)
  {
    t[i] = t[i - 1] + (line.row(i) - line.row(i - 1)).norm();
  }
  const double length = t.back();
  if (!(length > 0))
  {
    throw InputError("an action line has zero length (all its points coincide)");
  }
  for (double& value : t)
  {
    value /= length;
  }
  t.back() = 1.0; // exact, whatever the rounding of the sum
  return t;
}

Eigen::RowVector3d PointAtParameter(const Points& line, const std::vector<double>& parameters, double s)
{
  s = std::clamp(s, 0.0, 1.0);
  // First segment end with parameter >= s; segments of zero length are skipped
  // because upper_bound/lower_bound land on the last of equal parameters.
  auto upper = std::lower_bound(parameters.begin() + 1, parameters.end(), s);
  if (upper == parameters.end())
  {
    upper = parameters.end() - 1;
  }
  const auto k = static_cast<Eigen::Index>(upper - parameters.begin());
  const double t0 = parameters[k - 1];
  const double t1 = parameters[k];
  if (s == t1)
  {
    return line.row(k);
  }
  const double f = t1 > t0 ? (s - t0) / (t1 - t0) : 0.0;
  return (1.0 - f) * line.row(k - 1) + f * line.row(k);
}

namespace
{
double SmallestPositiveGap(const std::vector<double>& t)
{
  double gap = 1.0;
  for (size_t i = 1; i < t.size(); ++i)
  {
    const double d = t[i] - t[i - 1];
    if (d > 0)
    {
      gap = std::min(gap, d);
    }
  }
  return gap;
}

struct Pair
{
  double restT;
  double currentT;
  Eigen::Index restIndex;    // -1 when inserted on the RP line
  Eigen::Index currentIndex; // -1 when inserted on the CP line
};
}

double EffectiveMatchingTolerance(
  const std::vector<double>& restParameters, const std::vector<double>& currentParameters, double requestedTolerance)
{
  const double cap = 0.5 * std::min(SmallestPositiveGap(restParameters), SmallestPositiveGap(currentParameters));
  return std::clamp(requestedTolerance, 0.0, cap);
}

MatchedActionLines MatchActionLines(const Points& rest, const Points& current, double tolerance)
{
  const std::vector<double> tR = NormalisedArcLength(rest);
  const std::vector<double> tC = NormalisedArcLength(current);
  const double eps = EffectiveMatchingTolerance(tR, tC, tolerance);

  std::vector<Pair> pairs;
  pairs.reserve(tR.size() + tC.size());
  std::vector<bool> currentMatched(tC.size(), false);
  for (size_t i = 0; i < tR.size(); ++i)
  {
    Pair pair{ tR[i], tR[i], static_cast<Eigen::Index>(i), -1 };
    // The first unmatched partner within eps. Arc lengths increase, so the partners lie in a
    // window: searched from a little before it (2 eps, so that rounding cannot move the answer)
    // rather than from the start, which made long lines quadratic.
    const auto from = std::lower_bound(tC.begin(), tC.end(), tR[i] - 2 * eps) - tC.begin();
    for (size_t j = static_cast<size_t>(from); j < tC.size() && tC[j] <= tR[i] + 2 * eps; ++j)
    {
      if (!currentMatched[j] && std::abs(tR[i] - tC[j]) <= eps)
      {
        currentMatched[j] = true;
        pair.currentT = tC[j];
        pair.currentIndex = static_cast<Eigen::Index>(j);
        break;
      }
    }
    pairs.push_back(pair);
  }
  for (size_t j = 0; j < tC.size(); ++j)
  {
    if (!currentMatched[j])
    {
      pairs.push_back(Pair{ tC[j], tC[j], -1, static_cast<Eigen::Index>(j) });
    }
  }
  // The tolerance cap makes this order consistent on both lines.
  std::stable_sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
    if (a.restT != b.restT)
    {
      return a.restT < b.restT;
    }
    return a.currentT < b.currentT;
  });

  MatchedActionLines result;
  const auto n = static_cast<Eigen::Index>(pairs.size());
  result.rest.resize(n, 3);
  result.current.resize(n, 3);
  result.tolerance = eps;
  for (Eigen::Index k = 0; k < n; ++k)
  {
    const Pair& p = pairs[k];
    result.rest.row(k) =
      p.restIndex >= 0 ? Eigen::RowVector3d(rest.row(p.restIndex)) : PointAtParameter(rest, tR, p.restT);
    result.current.row(k) =
      p.currentIndex >= 0 ? Eigen::RowVector3d(current.row(p.currentIndex)) : PointAtParameter(current, tC, p.currentT);
    result.restParameters.push_back(p.restT);
    result.currentParameters.push_back(p.currentT);
    result.restInserted.push_back(p.restIndex < 0);
    result.currentInserted.push_back(p.currentIndex < 0);
  }
  return result;
}

Knots MatchedKnots(const Knots& own, const std::vector<bool>& restInserted)
{
  Knots matched;
  Eigen::Index original = 0; // points of the rest line before matched point k
  auto next = own.begin();
  for (size_t k = 0; k < restInserted.size() && next != own.end(); ++k)
  {
    if (restInserted[k])
    {
      continue;
    }
    if (*next == original)
    {
      matched.push_back(static_cast<Eigen::Index>(k));
      ++next;
    }
    ++original;
  }
  return matched;
}
}
