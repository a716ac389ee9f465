// SPDX-License-Identifier: BSD-3-Clause
#include "Anatomy/TendonExcursion.h"

#include <cmath>
#include <cstddef>
#include <limits>

namespace md
{
namespace
{
/// The one coordinate that moves from frame a to frame b; -1 for none or several.
int OneMoving(const std::vector<double>& a, const std::vector<double>& b)
{
  int moving = -1;
  for (size_t c = 0; c < a.size(); ++c)
  {
    if (std::abs(b[c] - a[c]) > kCoordinateMoves)
    {
      if (moving >= 0)
      {
        return -1;
      }
      moving = static_cast<int>(c);
    }
  }
  return moving;
}
}

std::vector<ExcursionDifference> ExcursionDifferences(const std::vector<std::vector<double>>& coordinates)
{
  const size_t frames = coordinates.size();
  std::vector<ExcursionDifference> differences(frames);
  for (size_t k = 0; k < frames; ++k)
  {
    // Central first, then backward, then forward.
    const std::pair<size_t, size_t> pairs[] = { { k - 1, k + 1 }, { k - 1, k }, { k, k + 1 } };
    for (const auto& [a, b] : pairs)
    {
      if ((a == k - 1 && k == 0) || b >= frames || a == b)
      {
        continue;
      }
      const int c = OneMoving(coordinates[a], coordinates[b]);
      if (c >= 0)
      {
        differences[k] = { a, b, c, coordinates[b][size_t(c)] - coordinates[a][size_t(c)] };
        break;
      }
    }
  }
  return differences;
}

double ExcursionDifference::Of(const std::vector<double>& lengths) const
{
  return this->coordinate >= 0 && this->to < lengths.size() ? this->Of(lengths[this->from], lengths[this->to])
                                                            : std::numeric_limits<double>::quiet_NaN();
}

std::vector<std::vector<double>> MomentArmsAlongMotion(
  const std::vector<std::vector<double>>& coordinates, const std::vector<double>& lengths)
{
  const size_t frames = std::min(coordinates.size(), lengths.size());
  const std::vector<ExcursionDifference> differences =
    ExcursionDifferences({ coordinates.begin(), coordinates.begin() + static_cast<std::ptrdiff_t>(frames) });
  std::vector<std::vector<double>> arms(frames);
  for (size_t k = 0; k < frames; ++k)
  {
    arms[k].assign(coordinates[k].size(), std::numeric_limits<double>::quiet_NaN());
    if (differences[k].coordinate >= 0)
    {
      arms[k][size_t(differences[k].coordinate)] = differences[k].Of(lengths);
    }
  }
  return arms;
}
}
