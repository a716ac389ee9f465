// SPDX-License-Identifier: BSD-3-Clause
// The names the MuscleDeformation filters read and write: the roles of the model's pieces (Role)
// and the arrays users' scripts rely on. Not part of the public API; MDBlocks.h and MDConvert.cxx
// build on it.
#pragma once

#include <string>

namespace mdvtk
{
/// What a piece of the model is. The filters write it as cell array "Role" on their outputs (the
/// active scalars, unless the data brings its own), and the plugin registers a categorical colour
/// map for that array (DefaultDisplaySettings): ParaView then shows bones in bone colour, muscles in
/// muscle shades and action lines in blue without any setting, in the GUI and in pvpython.
enum class Role : unsigned char
{
  Bone = 0,
  Muscle = 1, ///< the muscles take the values 1 ... MuscleShades in turn, by block
  ActionLine = 9,
  Hull = 10,
  AsGiven = 255, ///< keep the input's Role, add none (filters that move whatever they are given)
};
constexpr int MuscleShades = 8;
constexpr const char* RoleArrayName = "Role";

/// Names of the arrays that more than one filter writes or reads (users' scripts rely on them).
constexpr const char* CurrentPositionArrayName = "CurrentPosition"; ///< the matched action lines' current pose
constexpr const char* DisplacementArrayName = "Displacement";       ///< from the rest pose, per point
constexpr const char* StaticShiftArrayName = "StaticShift";         ///< the static resolution's move, per point
constexpr const char* VolumeChangeArrayName = "VolumeChangePercent";
constexpr const char* FailedArrayName = "DeformationFailed"; ///< field data of a muscle not processed
constexpr const char* FailureMessageArrayName = "FailureMessage";
/// The measures the filters write as field data and table columns (docs/DESIGN.md, "Measures").
namespace array
{
constexpr const char* NewPenetrationCount = "NewPenetrationCount";
constexpr const char* MaxNewPenetrationDepth = "MaxNewPenetrationDepth";
constexpr const char* NewBonePenetrationCount = "NewBonePenetrationCount";
constexpr const char* MaxNewBonePenetrationDepth = "MaxNewBonePenetrationDepth";
constexpr const char* MaxStaticShift = "MaxStaticShift";
constexpr const char* StepStaticShift = "StepStaticShift";
constexpr const char* SharpEdgeCount = "SharpEdgeCount";
constexpr const char* FlippedTriangleCount = "FlippedTriangleCount";
constexpr const char* NumberOfIterations = "NumberOfIterations";
constexpr const char* Converged = "Converged";
constexpr const char* PointsFrozenInObstacles = "PointsFrozenInObstacles";
constexpr const char* InterpolationStep = "InterpolationStep";
constexpr const char* NumberOfSteps = "NumberOfSteps";
constexpr const char* HullSeconds = "HullSeconds";
constexpr const char* StepSeconds = "StepSeconds";
constexpr const char* ElapsedSeconds = "ElapsedSeconds";
constexpr const char* SecondDifference = "SecondDifference";
constexpr const char* SmoothnessRatio = "SmoothnessRatio";
constexpr const char* FrameSeconds = "FrameSeconds";
constexpr const char* Frame = "Frame";
constexpr const char* Time = "Time";
constexpr const char* ActionLineName = "ActionLineName";
/// PathsOverBones' point array: 1 at a path's own points (origin, via points, insertion), 0 at the
/// points it puts between them. The deformation filters take a line piece by piece from one of
/// its own points to the next (md::Knots); a line without it has only its own points.
constexpr const char* PathOwnPoint = "PathOwnPoint";
constexpr const char* Body = "Body"; ///< a body's name: BodyTransforms' first column, MoveWithBodies' field data
/// BodyTransforms' field data (and MoveWithBodies' output's): the names of the rotational
/// coordinates among the pose's coordinate values (in degrees; the others in the model's unit).
constexpr const char* RotationalCoordinates = "RotationalCoordinates";
/// The motion filter's fibres (a cell array of output Fibres) and its MomentArms table's columns.
constexpr const char* FibreLength = "FibreLength";
/// BodyTransforms' column naming the pose of each row where OpenSimModelReader's MomentArmStep
/// adds rows: empty for the frame's own pose, "<coordinate>+" or "<coordinate>-" for the frame's
/// pose stepped by +-MomentArmStep in that coordinate. Absent: every row is the frame's.
constexpr const char* Pose = "Pose";
/// OpenSimModelReader's field data of each muscle path, which MuscleFromPath reads: OpenSim's
/// class of the path's actuator, metres per length unit of the output, and the muscle's
/// properties under OpenSim's names (lengths in the output's unit; absent for a path actuator).
constexpr const char* MuscleType = "MuscleType";
constexpr const char* MetresPerLengthUnit = "MetresPerLengthUnit";
constexpr const char* MaxIsometricForce = "max_isometric_force";
constexpr const char* OptimalFiberLength = "optimal_fiber_length";
constexpr const char* TendonSlackLength = "tendon_slack_length";
constexpr const char* PennationAngleAtOptimal = "pennation_angle_at_optimal";
/// BodyTransforms' field data (and MoveWithBodies' output's): the step of the stepped poses, degrees.
constexpr const char* MomentArmStep = "MomentArmStep";
/// BodyTransforms' other columns (OpenSimModelReader writes them, MoveWithBodies reads them): each
/// body's rest-to-current rotation, row by row, then its translation.
constexpr const char* TransformColumns[12] = { "R00", "R01", "R02", "R10", "R11", "R12", "R20", "R21", "R22", "Tx",
  "Ty", "Tz" };
}

/// The point array of a block's points at a stepped pose (array::Pose): "PointsAt(<pose>)".
inline std::string PointsAt(const std::string& pose)
{
  return "PointsAt(" + pose + ")";
}
/// The pose of a point array named PointsAt(<pose>) (PointsAt's inverse); empty for another name.
inline std::string PoseOfPointsAt(const std::string& name)
{
  const std::string opening = "PointsAt(";
  const bool named =
    name.size() > opening.size() + 1 && name.compare(0, opening.size(), opening) == 0 && name.back() == ')';
  return named ? name.substr(opening.size(), name.size() - opening.size() - 1) : std::string();
}
}
