// SPDX-License-Identifier: BSD-3-Clause
// Helpers shared by the MuscleDeformation filters: walking and pairing the
// leaves of polydata / multiblock inputs, and moving geometry between VTK and
// the Eigen-based core. Not part of the public API.
#pragma once

#include "Common/MeshTypes.h"

#include <vtkSmartPointer.h>
#include <vtkType.h>

#include <functional>
#include <map>
#include <string>
#include <vector>

class vtkAlgorithm;
class vtkDataArray;
class vtkDoubleArray;
class vtkDataObject;
class vtkFieldData;
class vtkInformation;
class vtkInformationVector;
class vtkMultiBlockDataSet;
class vtkObject;
class vtkPoints;
class vtkPolyData;

namespace md
{
struct BoneMotion;
struct MuscleStepMeasures;
}

namespace mdvtk
{
using md::Points;
using md::TriangleMesh;
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
constexpr const char* Body = "Body"; ///< a body's name: BodyTransforms' first column, MoveWithBodies' field data
/// BodyTransforms' other columns (OpenSimModelReader writes them, MoveWithBodies reads them): each
/// body's rest-to-current rotation, row by row, then its translation.
constexpr const char* TransformColumns[12] = { "R00", "R01", "R02", "R10", "R11", "R12", "R20", "R21", "R22", "Tx",
  "Ty", "Tz" };
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

/// Adds a one-value array to field data (a double, or an int for counts).
void AddFieldValue(vtkFieldData* fieldData, const char* name, double value);
void AddFieldValue(vtkFieldData* fieldData, const char* name, int value);
void AddFieldValue(vtkFieldData* fieldData, const char* name, std::int64_t value);

/// Advertises the time steps and range of `from` (an input's information) on `to` (an output's),
/// or none when `from` has none.
void CopyTimeSteps(vtkInformation* from, vtkInformation* to);

/// A progress callback for the core: reports `offset + share * fraction` as the filter's
/// progress and throws md::Cancelled when the user has asked the filter to stop (ParaView's
/// abort). Call only from the filter's own thread.
std::function<void(double)> ProgressOrCancel(vtkAlgorithm* filter, double offset = 0.0, double share = 1.0);
/// Reports `fraction` as the filter's progress; true when the user has asked it to stop (the
/// executive then empties the outputs, and RequestData returns 1).
bool ProgressOrStop(vtkAlgorithm* filter, double fraction);
/// Runs `work` (calls into the core) and turns the core's exceptions into what a filter reports:
/// md::InputError becomes an error (`context` + its message) and RequestData's result 0;
/// md::Cancelled (the user stopped the run) notes the abort, so that the executive empties the
/// outputs, and the result 1. Returns true when `work` completed; otherwise `result` is what
/// RequestData returns, and `reported` (optional) receives the error reported (empty when the
/// user stopped the run), for a filter that goes on with its other muscles.
bool CallCore(vtkAlgorithm* filter, const std::string& context, const std::function<void()>& work, int& result,
  std::string* reported = nullptr);

/// How messages and tables name a leaf: its block name, else its label.
std::string NameOf(const Leaf& leaf);

/// The surface of muscle `leaf` (ReadTriangles); false, with `error` naming the leaf, when it has
/// no triangles.
bool ReadMuscleSurface(const Leaf& leaf, TriangleMesh& surface, std::string& error);

/// Reports `message` as an error of `filter` (unless `reported`) and records it as the failure of
/// muscle block `block`: one muscle's fault leaves that muscle out, the others go on.
void FailBlock(vtkObject* filter, std::map<size_t, std::string>& failedBlocks, size_t block, const std::string& message,
  bool reported = false);

/// A copy of `input` at `points`: its cells and arrays shared, its field data its own (for the
/// measures a filter adds).
vtkSmartPointer<vtkPolyData> MovedCopy(vtkPolyData* input, const Points& points);
/// MovedCopy of a muscle, with point array Displacement (`displacement`, a row per point).
vtkSmartPointer<vtkPolyData> MovedMuscle(vtkPolyData* input, const Points& points, const Points& displacement);

/// One measure of a muscle, as the filters write it: to the muscle's field data (an int array for
/// a count, a double array otherwise) and to a column of their measures table.
struct Measure
{
  const char* name;
  double value;
  bool count = false;
};
/// Adds each of `measures` to `fieldData` (AddFieldValue).
void AddMeasures(vtkFieldData* fieldData, const std::vector<Measure>& measures);
/// What a muscle's step of the method, or frame of a motion, measured, in the order the filters
/// write it: `iterations` is the count to report, `stepShift` adds StepStaticShift.
std::vector<Measure> StepMeasures(const md::MuscleStepMeasures& s, int iterations, bool stepShift);

/// The time steps 0, 1, ..., `steps` of a filter whose time is its interpolation step.
std::vector<double> StepTimes(int steps);
/// Advertises `times` (TIME_STEPS and TIME_RANGE) on every output of `outputVector`, or none
/// when `times` is empty.
void AdvertiseTimes(vtkInformationVector* outputVector, const std::vector<double>& times);
/// The interpolation step asked of output `outInfo` (its UPDATE_TIME_STEP rounded into
/// [0, steps]), or `fallback` when none is asked.
int StepAsked(vtkInformation* outInfo, int steps, int fallback);
/// Asks the inputs of ports 0 .. `ports` - 1 for their default time (a filter whose time is its
/// interpolation step, not one of its inputs').
void InputsAtTheirOwnTime(vtkInformationVector** inputVector, int ports);
/// Brings the inputs of `ports` up to date, for RequestInformation to read their data.
void UpdateInputs(vtkAlgorithm* filter, const std::vector<int>& ports);
/// RequestInformation of a filter whose time is its interpolation step: `numberOfSteps` steps, or
/// when that is 0 as many as `automatic` finds (called once the inputs of `ports` are up to date;
/// it returns RequestInformation's result, and sets `steps` when that is 1), advertised as the
/// times 0 ... N on every output, N in `resolved`. Returns RequestInformation's result.
int AdvertiseSteps(vtkAlgorithm* filter, vtkInformationVector* outputVector, int numberOfSteps,
  const std::vector<int>& ports, const std::function<int(int& steps)>& automatic, int& resolved);
/// Index of the entry of `times` (ascending, not empty) nearest `time`; the earlier one at a tie.
int NearestTime(const std::vector<double>& times, double time);
/// Stamps every output of `outputVector` with DATA_TIME_STEP `time`.
void SetDataTime(vtkInformationVector* outputVector, double time);

/// The output block of a muscle that could not be processed: no geometry (nothing silently
/// wrong to show), the input block's field data, and DeformationFailed / FailureMessage.
vtkSmartPointer<vtkPolyData> FailedMuscle(vtkPolyData* input, const std::string& message);
/// Whether the user has asked `filter` to stop; safe to ask from worker threads (it only reads
/// the flag), for md::HullParameters::cancelled.
std::function<bool()> AbortRequested(vtkAlgorithm* filter);

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

/// Point coordinates in double precision.
Points ToPoints(vtkPoints* points);
/// The tuples of a 3-component array (such as CurrentPosition) in double precision.
Points ToPoints(vtkDataArray* array);
vtkSmartPointer<vtkPoints> ToVtkPoints(const Points& points);
/// A 3-component point array named `name` holding the rows of `values` (displacements, shifts).
vtkSmartPointer<vtkDoubleArray> ToVtkArray(const char* name, const Points& values);
vtkSmartPointer<vtkPolyData> ToPolyData(const TriangleMesh& mesh);
/// The polygons of `input` as triangles (polygons and strips triangulated),
/// with all of its points. Returns the number of cells that were not triangles.
vtkIdType ReadTriangles(vtkPolyData* input, TriangleMesh& mesh);
/// The polylines of a polydata, each as its point coordinates, or as the rows
/// of `values` (one per point of the polydata, e.g. a point array) when given.
std::vector<Points> ToPolylines(vtkPolyData* polyData, const Points* values = nullptr);
/// A polydata with one polyline cell per entry of `lines`, their points in order.
vtkSmartPointer<vtkPolyData> ToPolyLines(const std::vector<Points>& lines);
/// The meshes of every block of every connection of a repeatable input port
/// (such as Obstacles), named by block name or label. Fails, with a message,
/// on a block without triangles or with non-finite coordinates.
bool ReadMeshes(vtkInformationVector* port, const std::string& portName, std::vector<std::string>& names,
  std::vector<TriangleMesh>& meshes, std::string& error);

/// The bones of `rest` (input `restName`) and `current` (input `currentName`) paired as PairLeaves
/// pairs them, each with the same points in both; an empty block in both is skipped. Fails, naming
/// the block, on a bone empty in one pose only, another number of points, or no polygons.
/// `leafOfBone` (optional) receives the leaf of `rest` of each bone.
bool ReadBones(vtkObject* reporter, vtkDataObject* rest, const std::string& restName, vtkDataObject* current,
  const std::string& currentName, std::vector<md::BoneMotion>& bones, std::string& error,
  std::vector<size_t>* leafOfBone = nullptr);
}
