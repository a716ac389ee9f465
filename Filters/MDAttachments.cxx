// SPDX-License-Identifier: BSD-3-Clause
#include "MDAttachments.h"

#include "MDBlocks.h"
#include "MDConvert.h"

#include <vtkAbstractArray.h>
#include <vtkAlgorithm.h>
#include <vtkInformation.h>
#include <vtkOutputWindow.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>

#include <fstream>
#include <map>
#include <sstream>

namespace mdvtk
{
std::vector<md::LandmarkSet> ReadLandmarks(vtkDataObject* input, const std::string& fileName)
{
  std::vector<md::LandmarkSet> sets;
  if (!fileName.empty())
  {
    std::ifstream file(fileName);
    if (!file)
    {
      throw md::InputError("AttachmentFileName '" + fileName + "' cannot be read");
    }
    std::stringstream text;
    text << file.rdbuf();
    sets = md::ParseLandmarkTable(text.str(), fileName);
  }
  if (!input)
  {
    return sets;
  }
  std::vector<Leaf> leaves;
  std::string error;
  if (!CollectLeaves(input, "Attachments", leaves, error))
  {
    throw md::InputError(error);
  }
  for (const Leaf& leaf : leaves)
  {
    if (!leaf.data || leaf.data->GetNumberOfPoints() == 0)
    {
      continue;
    }
    auto* muscles = vtkStringArray::SafeDownCast(leaf.data->GetPointData()->GetAbstractArray("Muscle"));
    auto* bones = vtkStringArray::SafeDownCast(leaf.data->GetPointData()->GetAbstractArray("Bone"));
    auto* areas = vtkStringArray::SafeDownCast(leaf.data->GetPointData()->GetAbstractArray("Area"));
    if (!bones || (!muscles && leaf.name.empty()))
    {
      throw md::InputError(leaf.label +
        ": landmarks need a string point array 'Bone' (the bone each is on) and "
        "'Muscle' (or the block's name) naming their muscle");
    }
    const md::Points points = ToPoints(leaf.data->GetPoints());
    std::map<std::string, size_t> setOf; // this leaf's sets
    std::vector<md::LandmarkSet> own;
    std::vector<std::vector<Eigen::Index>> members;
    for (Eigen::Index i = 0; i < points.rows(); ++i)
    {
      const auto id = static_cast<vtkIdType>(i);
      md::LandmarkSet set{ muscles ? muscles->GetValue(id) : leaf.name, bones->GetValue(id),
        areas ? areas->GetValue(id) : "", md::Points() };
      const std::string key = set.muscle + "\n" + set.area + "\n" + set.bone;
      const auto [entry, added] = setOf.emplace(key, own.size());
      if (added)
      {
        own.push_back(set);
        members.emplace_back();
      }
      members[entry->second].push_back(i);
    }
    for (size_t k = 0; k < own.size(); ++k)
    {
      own[k].points.resize(static_cast<Eigen::Index>(members[k].size()), 3);
      for (size_t j = 0; j < members[k].size(); ++j)
      {
        own[k].points.row(static_cast<Eigen::Index>(j)) = points.row(members[k][j]);
      }
      sets.push_back(std::move(own[k]));
    }
  }
  return sets;
}

void OptionalLandmarkInput(vtkInformation* info)
{
  AcceptPolyDataOrMultiBlock(info);
  info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
}

std::string AttachAndReport(vtkAlgorithm* filter, const std::string& filterName, int mode,
  const std::vector<md::LandmarkSet>& landmarks, const std::vector<std::string>& muscleNames,
  const std::vector<md::TriangleMesh>& muscles, const std::vector<std::vector<md::Points>>& restLines,
  const std::vector<std::string>& boneNames, const std::vector<md::TriangleMesh>& bones,
  std::vector<std::vector<md::Attachment>>& areas, double messageUnit)
{
  areas.assign(muscles.size(), {});
  if (mode == ATTACHMENTS_OFF)
  {
    return "";
  }
  md::AttachmentParameters parameters;
  parameters.messageUnit = messageUnit;
  const md::FoundAttachments found =
    md::FindAttachments(muscleNames, muscles, restLines, boneNames, bones, landmarks, true, parameters);
  areas = found.areas;
  std::string report = filterName + ", attachment areas:";
  for (const std::string& line : found.messages)
  {
    report += "\n  " + line;
  }
  vtkOutputWindow::GetInstance()->DisplayText((report + "\n").c_str());
  for (const std::string& warning : found.warnings)
  {
    vtkOutputWindow::GetInstance()->DisplayWarningText(
      (filterName + " (" + filter->GetClassName() + "): " + warning + "\n").c_str());
  }
  return report;
}
}
