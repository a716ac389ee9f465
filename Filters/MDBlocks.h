// SPDX-License-Identifier: BSD-3-Clause
// What the MuscleDeformation filters share about their inputs and outputs: walking and pairing the
// leaves of polydata / multiblock inputs, putting results back in the input's structure, the
// roles (Role) and the names of the arrays the filters write. Not part of the public API; with
// MDConvert.h (VTK <-> the core's meshes), MDReport.h (calling the core, failures, measures) and
// MDTime.h (time steps).
#pragma once

#include "Common/MeshTypes.h"

#include <vtkSmartPointer.h>
#include <vtkType.h>

#include <string>
#include <vector>

class vtkDataObject;
class vtkInformation;
class vtkInformationVector;
class vtkMultiBlockDataSet;
class vtkObject;
class vtkPolyData;

namespace mdvtk
{
/// One polydata of an input: the input itself, or a leaf of a multiblock.
struct Leaf
{
  std::string name; ///< block name; empty when unnamed or not a multiblock
  vtkPolyData* data = nullptr;
  std::string label; ///< how messages name it, e.g. "CurrentPose block 'Femur'"
};

/// The polydata leaves of `input` (a vtkPolyData or a vtkMultiBlockDataSet),
/// in iteration order. Fails, with a message in `error`, when a leaf is not a
/// vtkPolyData, when the input is missing or has no leaves, or when a leaf has
/// non-finite coordinates (or beyond 1e100), a cell referring to a point it does
/// not have, or a point array whose length is not its number of points.
bool CollectLeaves(vtkDataObject* input, const std::string& inputName, std::vector<Leaf>& leaves, std::string& error);

/// Fails, naming the block by `label`, on coordinates that are not finite or beyond 1e100, a cell
/// that refers to a point the block does not have, or a point array whose tuples do not match the
/// points: what would otherwise be read past an array's end or overflow.
bool CheckPolyData(vtkPolyData* data, const std::string& label, std::string& error);

/// The latest modification time of `input` and of every leaf of it (a multiblock's own time
/// does not change when a leaf is modified in place); 0 for none.
vtkMTimeType DataMTime(vtkDataObject* input);

/// Which input last passed CollectLeaves' checks, and when (DataMTime): a filter that runs at
/// every frame of a motion need not check again an input that has not changed (the rest pose's
/// bones, 130 000 points on the LHDL hip).
class InputCheck
{
public:
  /// Whether `input`, whose DataMTime is `time`, is the one that last passed, unmodified since.
  bool Unchanged(vtkDataObject* input, vtkMTimeType time) const { return input == this->Input && time == this->Time; }
  void Passed(vtkDataObject* input, vtkMTimeType time)
  {
    this->Input = input;
    this->Time = time;
  }

private:
  const vtkDataObject* Input = nullptr; ///< compared, never read
  vtkMTimeType Time = 0;
};

/// CollectLeaves, checking the leaves' data only where `checked` has not seen this input pass
/// unmodified, and recording it as passed.
bool CollectLeaves(vtkDataObject* input, const std::string& inputName, std::vector<Leaf>& leaves, std::string& error,
  InputCheck& checked);

/// partner[i] = index in `b` of the leaf paired with a[i]: by name when every leaf of both inputs
/// has a unique name and some names are shared or the counts differ (then all must pair);
/// otherwise by order, with a
/// warning through `reporter` (may be null) saying which block goes with which when both inputs
/// have names but share none (as Group Datasets in the GUI names blocks after its inputs). Fails,
/// naming the unmatched block, when the pairing cannot be made.
bool PairLeaves(vtkObject* reporter, const std::vector<Leaf>& a, const std::string& nameA, const std::vector<Leaf>& b,
  const std::string& nameB, std::vector<size_t>& partner, std::string& error);

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

/// Writes `role` as the cell array Role of every polydata leaf of `data` (in leaf order: muscle
/// k gets shade k modulo MuscleShades), the active cell scalars unless the leaf has other active
/// scalars. Role::AsGiven leaves `data` as it is.
void MarkRoles(vtkDataObject* data, Role role);

/// The representation proxy (ServerManagerXML) the filters ask for to show action lines.
constexpr const char* ActionLinesRepresentation = "MuscleDeformationActionLinesRepresentation";

/// The plugin's display defaults as vtkSMSettings JSON, for the plugin to register when it loads:
/// the colour map of array Role (categories with names) and tubes for ActionLinesRepresentation.
std::string DefaultDisplaySettings();

/// Puts one result per leaf of `input` into `output`, which is of the same
/// type as `input` (see vtkPassInputTypeAlgorithm): for a multiblock input the
/// output gets the input's structure and block names. The results then get `role` (MarkRoles);
/// they must be the filter's own objects, not the input's.
void AssignLeaves(
  vtkDataObject* input, vtkDataObject* output, const std::vector<vtkSmartPointer<vtkPolyData>>& results, Role role);

/// Appends `block` to `tree` under the block name `name`.
void AddBlock(vtkMultiBlockDataSet* tree, const std::string& name, vtkDataObject* block);

/// RequestDataObject of a filter whose output k has the type of input `followed[k]` (when that
/// input is connected) and whose output `tablePort` is a vtkTable.
void OutputsFollowInputs(vtkInformationVector** inputVector, vtkInformationVector* outputVector,
  const std::vector<int>& followed, int tablePort);

/// Empties every output. Called when a filter is about to run again (its update extent is
/// requested only then): if an input then fails upstream, the pipeline never calls RequestData,
/// and the outputs would otherwise keep the last result, easy to take for the new one.
void ClearOutputs(vtkInformationVector* outputVector);

/// Accept vtkPolyData or vtkMultiBlockDataSet on an input port.
void AcceptPolyDataOrMultiBlock(vtkInformation* info);
}
