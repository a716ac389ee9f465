// SPDX-License-Identifier: BSD-3-Clause
// Plain data types shared by the algorithm core (no VTK here).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace md
{
/// n x 3 point coordinates, one point per row.
using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// The points of a polyline that are its own (a path's origin, via points and insertion), in
/// rising order from its first point to its last, where PathsOverBones has put points between
/// them. Empty: every point is the line's own.
using Knots = std::vector<Eigen::Index>;
/// m x 3 point indices, one triangle per row.
using Triangles = Eigen::Matrix<std::int64_t, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// Tolerances the stages share, relative to a size (a mesh's bounding-box diagonal, a length
/// the test is about): the arithmetic is double, so about 1e-16 of a size is rounding.
/// A point this close to a surface is on it (a hull touching its muscle, a cage's face).
constexpr double kOnSurfaceShare = 1e-9;
/// A length, area, determinant or volume this small is zero (degenerate input).
constexpr double kDegenerateShare = 1e-12;

struct TriangleMesh
{
  Points points;
  Triangles triangles;
};

/// True when both meshes have the same points and triangles, bit for bit.
inline bool SameMesh(const TriangleMesh& a, const TriangleMesh& b)
{
  return a.points.rows() == b.points.rows() && a.triangles.rows() == b.triangles.rows() && a.points == b.points &&
    a.triangles == b.triangles;
}

/// What the core throws when it hands on no result; the message says what went wrong so that
/// the VTK adapters can report it together with the name of the input.
class Error : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
  /// Set when the failure is one muscle's alone (its index among the muscles of the call): a
  /// caller can then go on without that muscle (DeformByInterpolation does).
  std::optional<size_t> muscle;
};

/// `error`, marked as muscle `index`'s own, unless it is already marked.
template<class E>
E OfMuscle(E error, size_t index)
{
  if (!error.muscle)
  {
    error.muscle = index;
  }
  return error;
}

/// Thrown when input data cannot be used.
class InputError : public Error
{
public:
  using Error::Error;
};

/// Thrown when a computation cannot finish on input of a sound form (a deformation that
/// diverges): not the input's fault as such, but no result is handed on.
class ComputationError : public Error
{
public:
  using Error::Error;
};

/// Thrown through the core by a progress or cancel callback when the user stops a computation
/// (ParaView's abort): the core unwinds, nothing half-done is handed on.
class Cancelled : public std::runtime_error
{
public:
  Cancelled()
    : std::runtime_error("cancelled")
  {
  }
};

/// True when every coordinate is finite (no NaN, no infinity).
inline bool AllFinite(const Points& points)
{
  return points.allFinite();
}
}
