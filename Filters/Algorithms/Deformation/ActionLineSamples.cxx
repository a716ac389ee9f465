// SPDX-License-Identifier: BSD-3-Clause
// Action lines for the one pass (docs/DESIGN.md section 4): their own points checked, long lines
// thinned, and the samples the action-line rows pull.
#include "Deformation/MuscleDeformer.h"

#include "Deformation/NearestSegment.h"
#include "Geometry/MeshChecks.h"

#include <algorithm>
#include <functional>
#include <iomanip>
#include <queue>
#include <sstream>
#include <string>

namespace md
{
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
}
