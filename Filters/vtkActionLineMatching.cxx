// SPDX-License-Identifier: BSD-3-Clause
#include "vtkActionLineMatching.h"

#include "MDBlocks.h"
#include "MDConvert.h"
#include "MDReport.h"
#include "Motion/ActionLineMatching.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>

vtkStandardNewMacro(vtkActionLineMatching);

namespace
{
/// A polydata of polylines with the point arrays ArcLength and Inserted.
struct LineBuilder
{
  std::vector<md::Points> lines;
  std::vector<std::vector<double>> parameters;
  std::vector<std::vector<bool>> inserted;

  vtkSmartPointer<vtkPolyData> Build(vtkPolyData* source) const
  {
    auto output = mdvtk::ToPolyLines(this->lines);
    const vtkIdType total = output->GetNumberOfPoints();
    auto arcLength = vtkSmartPointer<vtkDoubleArray>::New();
    arcLength->SetName("ArcLength");
    arcLength->SetNumberOfValues(total);
    auto insertedFlag = vtkSmartPointer<vtkUnsignedCharArray>::New();
    insertedFlag->SetName("Inserted");
    insertedFlag->SetNumberOfValues(total);
    vtkIdType next = 0;
    for (size_t l = 0; l < this->lines.size(); ++l)
    {
      for (vtkIdType k = 0; k < static_cast<vtkIdType>(this->lines[l].rows()); ++k, ++next)
      {
        arcLength->SetValue(next, this->parameters[l][k]);
        insertedFlag->SetValue(next, this->inserted[l][k] ? 1 : 0);
      }
    }
    output->GetPointData()->AddArray(arcLength);
    output->GetPointData()->AddArray(insertedFlag);
    // Line cell data carries over: line l of the output is line l of the source,
    // whose cell id comes after the source's vertices.
    vtkCellData* sourceCells = source->GetCellData();
    if (sourceCells->GetNumberOfArrays() > 0)
    {
      vtkCellData* outCells = output->GetCellData();
      outCells->CopyAllocate(sourceCells, static_cast<vtkIdType>(this->lines.size()));
      const vtkIdType firstLine = source->GetNumberOfVerts();
      for (size_t l = 0; l < this->lines.size(); ++l)
      {
        outCells->CopyData(sourceCells, firstLine + static_cast<vtkIdType>(l), static_cast<vtkIdType>(l));
      }
    }
    output->GetFieldData()->PassData(source->GetFieldData());
    return output;
  }
};
}

vtkActionLineMatching::vtkActionLineMatching()
{
  this->SetNumberOfInputPorts(2);
  this->SetNumberOfOutputPorts(2);
  this->Tolerance = md::kDefaultMatchingTolerance;
}

int vtkActionLineMatching::FillInputPortInformation(int, vtkInformation* info)
{
  mdvtk::AcceptPolyDataOrMultiBlock(info);
  return 1;
}

int vtkActionLineMatching::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  mdvtk::ClearOutputs(outputVector); // no stale result if an input fails upstream
  return this->Superclass::RequestUpdateExtent(request, inputVector, outputVector);
}

int vtkActionLineMatching::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkDataObject* restInput = vtkDataObject::GetData(inputVector[0], 0);
  vtkDataObject* currentInput = vtkDataObject::GetData(inputVector[1], 0);
  std::vector<mdvtk::Leaf> restLeaves, currentLeaves;
  std::vector<size_t> partner;
  std::string error;
  if (!mdvtk::CollectLeaves(restInput, "Input", restLeaves, error) ||
    !mdvtk::CollectLeaves(currentInput, "CurrentPose", currentLeaves, error) ||
    !mdvtk::PairLeaves(this, restLeaves, "Input", currentLeaves, "CurrentPose", partner, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }

  std::vector<vtkSmartPointer<vtkPolyData>> restResults(restLeaves.size());
  std::vector<vtkSmartPointer<vtkPolyData>> currentResults(currentLeaves.size());
  for (size_t b = 0; b < restLeaves.size(); ++b)
  {
    this->UpdateProgress(static_cast<double>(b) / restLeaves.size());
    const mdvtk::Leaf& rest = restLeaves[b];
    const mdvtk::Leaf& current = currentLeaves[partner[b]];
    if (!rest.data || !current.data)
    {
      if (rest.data || current.data)
      {
        vtkErrorMacro(<< (rest.data ? current.label : rest.label) << " is empty but its partner is not");
        return 0;
      }
      continue;
    }
    const std::vector<md::Points> restLines = mdvtk::ToPolylines(rest.data);
    const std::vector<md::Points> currentLines = mdvtk::ToPolylines(current.data);
    if (restLines.empty())
    {
      vtkErrorMacro(<< rest.label << " has no polylines; action lines must be polyline cells");
      return 0;
    }
    if (restLines.size() != currentLines.size())
    {
      vtkErrorMacro(<< rest.label << " has " << restLines.size() << " polyline(s) but " << current.label << " has "
                    << currentLines.size() << "; the polylines of a block pair by order");
      return 0;
    }
    LineBuilder restBuilder, currentBuilder;
    std::vector<md::Points> partnerPositions;
    for (size_t l = 0; l < restLines.size(); ++l)
    {
      md::MatchedActionLines matched;
      int result = 1;
      if (!mdvtk::CallCore(
            this, "polyline " + std::to_string(l) + " of " + rest.label + " / " + current.label + ": ",
            [&] { matched = md::MatchActionLines(restLines[l], currentLines[l], this->Tolerance); }, result))
      {
        return result;
      }
      restBuilder.lines.push_back(matched.rest);
      restBuilder.parameters.push_back(matched.restParameters);
      restBuilder.inserted.push_back(matched.restInserted);
      currentBuilder.lines.push_back(matched.current);
      currentBuilder.parameters.push_back(matched.currentParameters);
      currentBuilder.inserted.push_back(matched.currentInserted);
      partnerPositions.push_back(matched.current);
    }
    vtkSmartPointer<vtkPolyData> restOut = restBuilder.Build(rest.data);
    vtkSmartPointer<vtkPolyData> currentOut = currentBuilder.Build(current.data);
    // CurrentPosition: the matched CP point of every RP point, in the same order.
    auto currentPosition = vtkSmartPointer<vtkDoubleArray>::New();
    currentPosition->SetName(mdvtk::CurrentPositionArrayName);
    currentPosition->SetNumberOfComponents(3);
    currentPosition->SetNumberOfTuples(restOut->GetNumberOfPoints());
    double* out = currentPosition->GetPointer(0);
    for (const md::Points& line : partnerPositions)
    {
      out = std::copy(line.data(), line.data() + line.size(), out);
    }
    restOut->GetPointData()->AddArray(currentPosition);
    // A path's own points (PathsOverBones) stay its own among the points matching inserted.
    const std::vector<md::Knots> knots = mdvtk::ToKnots(rest.data);
    if (!knots.empty())
    {
      vtkNew<vtkUnsignedCharArray> own;
      own->SetName(mdvtk::array::PathOwnPoint);
      own->SetNumberOfValues(restOut->GetNumberOfPoints());
      own->Fill(0);
      vtkIdType first = 0; // of line l among the output's points
      for (size_t l = 0; l < restBuilder.lines.size(); ++l)
      {
        for (const Eigen::Index k : md::MatchedKnots(knots[l], restBuilder.inserted[l]))
        {
          own->SetValue(first + static_cast<vtkIdType>(k), 1);
        }
        first += static_cast<vtkIdType>(restBuilder.lines[l].rows());
      }
      restOut->GetPointData()->AddArray(own);
    }
    restResults[b] = restOut;
    currentResults[partner[b]] = currentOut;
  }

  mdvtk::AssignLeaves(restInput, vtkDataObject::GetData(outputVector, 0), restResults, mdvtk::Role::ActionLine);
  mdvtk::AssignLeaves(currentInput, vtkDataObject::GetData(outputVector, 1), currentResults, mdvtk::Role::ActionLine);
  return 1;
}

void vtkActionLineMatching::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Tolerance: " << this->Tolerance << "\n";
}
