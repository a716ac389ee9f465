// SPDX-License-Identifier: BSD-3-Clause
// What the MuscleDeformation filters share about their inputs and outputs: walking and pairing the
// leaves of polydata / multiblock inputs, putting results back in the input's structure, the
// roles and array names (MDArrays.h). Not part of the public API; with
// MDConvert.h (VTK <-> the core's meshes), MDReport.h (calling the core, failures, measures) and
// MDTime.h (time steps).
#pragma once

#include "Common/MeshTypes.h"
#include "MDArrays.h"

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

namespace md
{
struct BoneMotion;
}

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

/// How messages and tables name a leaf: its block name, else its label.
std::string NameOf(const Leaf& leaf);

/// The surface of muscle `leaf` (ReadTriangles; `converted`, optional, receives its count of cells
/// that were not triangles); false, with `error` naming the leaf, when it has no triangles.
bool ReadMuscleSurface(const Leaf& leaf, md::TriangleMesh& surface, std::string& error, vtkIdType* converted = nullptr);

/// The meshes of every block of every connection of a repeatable input port
/// (such as Obstacles), named by block name or label. Fails, with a message,
/// on a block without triangles or with non-finite coordinates; with `skipEmpty`, a block with no
/// points (a model's body without a mesh) is passed over instead.
bool ReadMeshes(vtkInformationVector* port, const std::string& portName, std::vector<std::string>& names,
  std::vector<md::TriangleMesh>& meshes, std::string& error, bool skipEmpty = false);

/// The bones of `rest` (input `restName`) and `current` (input `currentName`) paired as PairLeaves
/// pairs them, each with the same points in both; an empty block in both is skipped. Fails, naming
/// the block, on a bone empty in one pose only, another number of points, or no polygons.
/// `leafOfBone` (optional) receives the leaf of `rest` of each bone.
bool ReadBones(vtkObject* reporter, vtkDataObject* rest, const std::string& restName, vtkDataObject* current,
  const std::string& currentName, std::vector<md::BoneMotion>& bones, std::string& error,
  std::vector<size_t>* leafOfBone = nullptr);
}
