// SPDX-License-Identifier: BSD-3-Clause
#include "Geometry/LocalFrame.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace md
{
LocalFrame LocalFrame::Around(const std::vector<const Points*>& parts)
{
  Eigen::RowVector3d low = Eigen::RowVector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::RowVector3d high = -low;
  for (const Points* part : parts)
  {
    if (part && part->rows() > 0)
    {
      low = low.cwiseMin(part->colwise().minCoeff());
      high = high.cwiseMax(part->colwise().maxCoeff());
    }
  }
  LocalFrame frame;
  const double extent = (high - low).maxCoeff();
  if (!(extent > 0) || !std::isfinite(extent))
  {
    return frame; // nothing, one point, or input the callers refuse anyway
  }
  // ilogb/ldexp: exact powers of two, even for extents near the ends of the double range.
  int exponent = std::ilogb(extent);
  if (std::ldexp(1.0, exponent) < extent)
  {
    ++exponent;
  }
  frame.unit = std::ldexp(1.0, exponent);
  // Origin 0 while the centre is within 8 units of it: then a frame made around data already
  // in a local frame is the identity.
  const double spacing = std::ldexp(1.0, exponent + 4);
  const Eigen::RowVector3d centre = 0.5 * low + 0.5 * high;
  for (int k = 0; k < 3; ++k)
  {
    frame.origin[k] = std::abs(centre[k]) <= 0.5 * spacing ? 0.0 : spacing * std::round(centre[k] / spacing);
  }
  const double largest = std::max(low.cwiseAbs().maxCoeff(), high.cwiseAbs().maxCoeff());
  frame.rounding = 4 * std::numeric_limits<double>::epsilon() * largest / frame.unit;
  return frame;
}
}
