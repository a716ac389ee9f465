// SPDX-License-Identifier: BSD-3-Clause
// What the deformation filters share about attachment areas: the landmarks read from an input or
// a landmark table, and the areas found and reported (Anatomy/AttachmentAreas.h). Not part of the
// public API.
#pragma once

#include "Anatomy/AttachmentAreas.h"

#include <string>
#include <vector>

class vtkAlgorithm;
class vtkDataObject;
class vtkInformation;

namespace mdvtk
{
/// How a deformation filter attaches its muscles (the AttachmentAreas property).
enum AttachmentMode
{
  ATTACHMENTS_OFF = 0,
  ATTACHMENTS_GIVEN_OR_FOUND = 1 ///< the landmarks given, else at the action lines' ends
};

/// The landmark sets of `input` (none: no input) and of the landmark table `fileName` (empty: none).
/// `input` is a vtkPolyData or a multiblock of them whose points are landmarks, with the string
/// point arrays "Muscle" and "Bone" (and optionally "Area"); where "Muscle" is absent, the block's
/// name names the muscle. Throws md::InputError naming the input or file and the problem.
std::vector<md::LandmarkSet> ReadLandmarks(vtkDataObject* input, const std::string& fileName);

/// Sets the Attachments input port's information: optional, polydata or multiblock.
void OptionalLandmarkInput(vtkInformation* info);

/// The areas of `muscles` on `bones` for `mode` (ATTACHMENTS_OFF: none), and says how each
/// muscle's were found in the output messages (one text for all, `filterName` first) and warns of
/// landmarks not used, its distances in `messageUnit`s of the coordinates given (the data's
/// length of a local frame's unit). Returns the report's text.
std::string AttachAndReport(vtkAlgorithm* filter, const std::string& filterName, int mode,
  const std::vector<md::LandmarkSet>& landmarks, const std::vector<std::string>& muscleNames,
  const std::vector<md::TriangleMesh>& muscles, const std::vector<std::vector<md::Points>>& restLines,
  const std::vector<std::string>& boneNames, const std::vector<md::TriangleMesh>& bones,
  std::vector<std::vector<md::Attachment>>& areas, double messageUnit = 1.0);
}
