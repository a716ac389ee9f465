// SPDX-License-Identifier: BSD-3-Clause
// Coordinates relative to a local origin and in a power-of-two unit, so that the method's
// arithmetic (volumes and their gradients, cross products, tolerances relative to a size) gives
// the same answer wherever the data sits and whatever its units.
#pragma once

#include "Common/MeshTypes.h"

#include <vector>

namespace md
{
/// local = (world - origin) / unit. The unit is the power of two at or above the largest extent
/// of the data the frame is made around; the origin is the multiple of 16 units nearest the
/// data's centre, or 0 while that is within 8 units of it. So data within a few times its own
/// size of the coordinates' origin keeps origin 0 and is only divided by a power of two, which is
/// exact: its results are bit for bit those computed in its own coordinates. Data far away (a
/// scan 1e12 from the origin) is moved near it by a shift that is itself exact (a multiple of a
/// power of two at least as coarse as the data's own rounding), and data in metres or in
/// millimetres gets local numbers of the same size, equal to rounding.
struct LocalFrame
{
  Eigen::RowVector3d origin = Eigen::RowVector3d::Zero();
  double unit = 1.0;
  /// A few roundings of the data's own coordinates, in local units: points brought back to the
  /// world and read again can be this far from where they were (for a muscle in millimetres
  /// 1e12 from the origin, 1e-4 mm), so tests of "inside" allow it.
  double rounding = 0.0;

  /// The frame of the points of `parts` (null or empty parts are skipped; none: the identity).
  static LocalFrame Around(const std::vector<const Points*>& parts);

  void ToLocal(Points& points) const { points = (points.rowwise() - this->origin) / this->unit; }
  void ToWorld(Points& points) const { points = (points * this->unit).rowwise() + this->origin; }
  /// Displacements, distances: no origin.
  void VectorsToWorld(Points& vectors) const { vectors *= this->unit; }
  double LengthToLocal(double length) const { return length / this->unit; }
  double LengthToWorld(double length) const { return length * this->unit; }
  double VolumeToWorld(double volume) const { return volume * this->unit * this->unit * this->unit; }
};
}
