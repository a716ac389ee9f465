#include "vtkMusculoskeletalPhantom.h"

#include "MDBlocks.h"
#include "Phantom.h"

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
void AddBlock(vtkMultiBlockDataSet* tree, const std::string& name, vtkDataObject* block)
{
  const unsigned int index = tree->GetNumberOfBlocks();
  tree->SetBlock(index, block);
  tree->GetMetaData(index)->Set(vtkCompositeDataSet::NAME(), name.c_str());
}

vtkSmartPointer<vtkPolyData> Polylines(
  const std::vector<md::Points>& lines, const std::vector<std::string>& names)
{
  vtkIdType total = 0;
  for (const md::Points& line : lines)
  {
    total += line.rows();
  }
  md::Points all(total, 3);
  vtkNew<vtkCellArray> cells;
  vtkNew<vtkStringArray> lineNames;
  lineNames->SetName("ActionLineName");
  vtkIdType next = 0;
  for (size_t l = 0; l < lines.size(); ++l)
  {
    all.middleRows(next, lines[l].rows()) = lines[l];
    cells->InsertNextCell(static_cast<int>(lines[l].rows()));
    for (vtkIdType k = 0; k < lines[l].rows(); ++k)
    {
      cells->InsertCellPoint(next + k);
    }
    next += lines[l].rows();
    lineNames->InsertNextValue(names[l]);
  }
  auto polyData = vtkSmartPointer<vtkPolyData>::New();
  polyData->SetPoints(mdvtk::ToVtkPoints(all));
  polyData->SetLines(cells);
  polyData->GetCellData()->AddArray(lineNames);
  return polyData;
}
}

vtkMusculoskeletalPhantom::vtkMusculoskeletalPhantom()
{
  this->SetNumberOfInputPorts(0);
  this->SetNumberOfOutputPorts(5);
}

int vtkMusculoskeletalPhantom::RequestData(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  md::PhantomParameters parameters;
  parameters.flexionDegrees = this->Flexion;
  parameters.scale = this->Scale;
  parameters.resolution = this->Resolution;
  md::Phantom phantom;
  int result = 1;
  if (!mdvtk::CallCore(this, "", [&] { phantom = md::BuildPhantom(parameters); }, result))
  {
    return result;
  }
  auto output = [&](int port) { return vtkMultiBlockDataSet::GetData(outputVector, port); };

  for (const md::PhantomMuscle& muscle : phantom.muscles)
  {
    AddBlock(output(MUSCLES), muscle.name, mdvtk::ToPolyData(muscle.rest));
    AddBlock(output(ACTION_LINES_REST), muscle.name,
      Polylines(muscle.actionLinesRest, muscle.actionLineNames));
    AddBlock(output(ACTION_LINES_CURRENT), muscle.name,
      Polylines(muscle.actionLinesCurrent, muscle.actionLineNames));
  }
  for (const md::PhantomBone& bone : phantom.bones)
  {
    AddBlock(output(BONES_REST), bone.name, mdvtk::ToPolyData(bone.rest));
    AddBlock(output(BONES_CURRENT), bone.name,
      mdvtk::ToPolyData(md::TriangleMesh{ bone.currentPoints, bone.rest.triangles }));
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
