// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMusculoskeletalPhantom.h"

#include "MDBlocks.h"
#include "MDConvert.h"
#include "MDReport.h"
#include "Phantom/Phantom.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCompositeDataSet.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkObjectFactory.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>

vtkStandardNewMacro(vtkMusculoskeletalPhantom);

namespace
{
/// The lines of one muscle as polylines, each named in cell array ActionLineName.
vtkSmartPointer<vtkPolyData> Polylines(const std::vector<md::Points>& lines, const std::vector<std::string>& names)
{
  vtkSmartPointer<vtkPolyData> polyData = mdvtk::ToPolyLines(lines);
  vtkNew<vtkStringArray> lineNames;
  lineNames->SetName(mdvtk::array::ActionLineName);
  for (const std::string& name : names)
  {
    lineNames->InsertNextValue(name);
  }
  polyData->GetCellData()->AddArray(lineNames);
  return polyData;
}
}

vtkMusculoskeletalPhantom::vtkMusculoskeletalPhantom()
{
  this->SetNumberOfInputPorts(0);
  this->SetNumberOfOutputPorts(5);
}

int vtkMusculoskeletalPhantom::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  md::PhantomParameters parameters;
  parameters.flexionDegrees = this->Flexion;
  parameters.scale = this->Scale;
  parameters.resolution = this->Resolution;
  md::Phantom phantom;
  int result = 1;
  if (!mdvtk::CallCore(
        this, "", [&] { phantom = md::BuildPhantom(parameters); }, result))
  {
    return result;
  }
  auto output = [&](int port) {
    return vtkMultiBlockDataSet::GetData(outputVector, port);
  };

  for (const md::PhantomMuscle& muscle : phantom.muscles)
  {
    mdvtk::AddBlock(output(MUSCLES), muscle.name, mdvtk::ToPolyData(muscle.rest));
    mdvtk::AddBlock(output(ACTION_LINES_REST), muscle.name, Polylines(muscle.actionLinesRest, muscle.actionLineNames));
    mdvtk::AddBlock(
      output(ACTION_LINES_CURRENT), muscle.name, Polylines(muscle.actionLinesCurrent, muscle.actionLineNames));
  }
  for (const md::PhantomBone& bone : phantom.bones)
  {
    mdvtk::AddBlock(output(BONES_REST), bone.name, mdvtk::ToPolyData(bone.rest));
    mdvtk::AddBlock(
      output(BONES_CURRENT), bone.name, mdvtk::ToPolyData(md::TriangleMesh{ bone.currentPoints, bone.rest.triangles }));
  }
  mdvtk::MarkRoles(output(MUSCLES), mdvtk::Role::Muscle);
  for (int port : { BONES_REST, BONES_CURRENT })
  {
    mdvtk::MarkRoles(output(port), mdvtk::Role::Bone);
  }
  for (int port : { ACTION_LINES_REST, ACTION_LINES_CURRENT })
  {
    mdvtk::MarkRoles(output(port), mdvtk::Role::ActionLine);
  }
  return 1;
}

void vtkMusculoskeletalPhantom::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Flexion: " << this->Flexion << "\n";
  os << indent << "Scale: " << this->Scale << "\n";
  os << indent << "Resolution: " << this->Resolution << "\n";
}
