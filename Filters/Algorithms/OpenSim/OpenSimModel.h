// SPDX-License-Identifier: BSD-3-Clause
// An OpenSim musculoskeletal model (.osim, format 3.x and 4.x) read into plain data:
// bodies, joints, coordinates, muscle paths, wrap objects, coordinate couplers.
// Forward kinematics and path geometry are in OpenSimKinematics.h.
#pragma once

#include "Common/MeshTypes.h"
#include "Common/MuscleProperties.h"
#include "Geometry/RigidMotion.h"
#include "OpenSim/OpenSimFunction.h"

#include <array>
#include <limits>
#include <string>
#include <vector>

namespace md::osim
{
/// The largest magnitude a number of a model's geometry (offsets, scale factors, function values)
/// or of a motion may have: beyond it, the poses of bodies built on one another overflow. Readers
/// refuse larger ones, naming where they are.
constexpr double kLargestValue = 1e12;

enum class MotionType
{
  Rotational,
  Translational,
  Coupled
};

struct Coordinate
{
  std::string name;
  std::string joint;
  double defaultValue = 0.0;
  double rangeMin = -std::numeric_limits<double>::infinity();
  double rangeMax = std::numeric_limits<double>::infinity();
  /// OpenSim 4's rule (used for 3.x files too, as OpenSim 4 does): rotational when the coordinate
  /// drives a rotation axis as a LinearFunction of slope +-1 (or is a pin/ball/... angle),
  /// translational likewise for translation axes, otherwise coupled. Motion files in degrees
  /// convert rotational coordinates only.
  MotionType motionType = MotionType::Coupled;
};

/// One of a joint's six spatial axes: displacement function(coordinate) along or about `axis`.
struct TransformAxis
{
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();
  int coordinate = -1; ///< index into Model::coordinates; -1: the function takes no coordinate
  Function function = Function::Constant(0.0);
};

/// A joint as a spatial transform of its coordinates (every joint type is written this way):
/// child-in-ground = parent-in-ground * parentOffset * X(q) * inverse(childOffset), with
/// X(q) = (R(f0, a0) R(f1, a1) R(f2, a2), f3 a3 + f4 a4 + f5 a5), the rotations body-fixed and
/// the translation in the parent offset frame (Simbody's function-based mobiliser).
struct Joint
{
  std::string name;
  std::string type; ///< CustomJoint, PinJoint, ...
  int parentBody = 0;
  int childBody = 0;
  RigidTransform parentOffset;
  RigidTransform childOffset;
  std::array<TransformAxis, 6> axes;
};

/// A mesh file attached to a body, placed in the body's frame.
struct Geometry
{
  std::string file;
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();
  RigidTransform placement; ///< mesh frame -> body frame
};

struct Body
{
  std::string name;
  std::vector<Geometry> geometry;
};

enum class WrapShape
{
  Cylinder,
  Sphere,
  Ellipsoid,
  Torus
};

struct WrapObject
{
  std::string name;
  WrapShape shape = WrapShape::Cylinder;
  int body = 0;
  RigidTransform placement; ///< wrap frame -> body frame
  /// Cylinder: radius, length; sphere: radius; ellipsoid: the three radii; torus: the radius of
  /// its centre circle and of its tube.
  std::vector<double> dimensions;
  bool active = true;
  /// The quadrant a path wraps over (`quadrant`): the axis (0 x, 1 y, 2 z) and its side (+1, -1),
  /// or side 0 for all of it.
  int quadrantAxis = 0;
  int quadrantSign = 0;
};

/// How a path finds the plane it wraps an ellipsoid in (OpenSim's PathWrap `method`): from the
/// coordinate axis most nearly along the path, from the ellipsoid's points nearest the straight
/// segment, or a blend of the two (hybrid, OpenSim's default); from the segment's midpoint.
enum class EllipsoidWrapMethod
{
  Hybrid,
  Midpoint,
  Axial
};

/// A path's use of a wrap object (OpenSim's PathWrap).
struct PathWrap
{
  std::string name;    ///< the wrap object's
  int wrapObject = -1; ///< index into Model::wrapObjects
  /// The path points (1-based, as OpenSim's `range`) between which the path may wrap; below 1:
  /// the first (last) point.
  int rangeStart = -1, rangeEnd = -1;
  EllipsoidWrapMethod method = EllipsoidWrapMethod::Hybrid; ///< how an ellipsoid is wrapped
};

enum class PathPointKind
{
  Fixed,
  Conditional,
  Moving
};

struct PathPoint
{
  std::string name;
  PathPointKind kind = PathPointKind::Fixed;
  int body = 0;
  RigidTransform frame;                               ///< the point's frame -> body frame (identity on a body)
  Eigen::Vector3d location = Eigen::Vector3d::Zero(); ///< in the point's frame
  // Conditional: active while coordinate is in [rangeMin - 1e-5, rangeMax + 1e-5].
  int coordinate = -1;
  double rangeMin = 0.0, rangeMax = 0.0;
  // Moving: location[i] = function[i](clamped coordinate[i]).
  std::array<Function, 3> locationFunction = { Function::Constant(0), Function::Constant(0), Function::Constant(0) };
  std::array<int, 3> locationCoordinate = { -1, -1, -1 };
};

/// A muscle (or any path actuator) and its path points in order.
struct Path
{
  std::string name;
  std::string type; ///< e.g. Thelen2003Muscle
  /// The muscle's max_isometric_force, optimal_fiber_length, tendon_slack_length (metres, as the
  /// file) and pennation_angle_at_optimal (pennation_angle in older files); unknown for a path
  /// actuator that is not a muscle.
  MuscleProperties muscle;
  std::vector<PathPoint> points;
  std::vector<PathWrap> wraps; ///< in the order OpenSim applies them
};

/// dependent = scale * function(independent)
struct CoordinateCoupler
{
  std::string name;
  int dependent = -1;
  int independent = -1;
  Function function = Function::Constant(0.0);
  double scale = 1.0;
};

struct Model
{
  std::string name;
  std::string file;
  int version = 0;           ///< OpenSimDocument Version (30000: 3.x, 40000: 4.x)
  std::vector<Body> bodies;  ///< bodies[0] is ground
  std::vector<Joint> joints; ///< parents before children
  std::vector<Coordinate> coordinates;
  std::vector<CoordinateCoupler> couplers; ///< in the order to apply them
  std::vector<Path> paths;
  std::vector<WrapObject> wrapObjects;
  std::vector<std::string> warnings; ///< what was read but is not honoured, or was assumed

  int FindBody(const std::string& name) const;
  int FindCoordinate(const std::string& name) const;
  int FindPath(const std::string& name) const;
  int FindWrapObject(const std::string& name) const;
};

/// Reads an .osim file. Throws InputError naming the file, the line, the element and the problem
/// (malformed XML, an unknown joint or function type, a reference to a missing body or
/// coordinate, ...).
Model ReadModel(const std::string& fileName);
/// The same from the text of a model; `fileName` names it in messages.
Model ParseModel(const std::string& text, const std::string& fileName);
}
