// SPDX-License-Identifier: BSD-3-Clause
// Helpers for the VTK filter tests.
#pragma once

#include "Geometry/MeshChecks.h"
#include "MDConvert.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCompositeDataSet.h>
#include <vtkDoubleArray.h>
#include <vtkInformation.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkNew.h>
#include <vtkOutputWindow.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringOutputWindow.h>

#include <gtest/gtest.h>

#include <string>
#include <vector>

/// Collects everything VTK reports (errors, warnings) while it lives.
class CapturedMessages
{
public:
  CapturedMessages()
    : Previous(vtkOutputWindow::GetInstance())
  {
    vtkOutputWindow::SetInstance(this->Window);
  }
  ~CapturedMessages() { vtkOutputWindow::SetInstance(this->Previous); }
  std::string Text() { return this->Window->GetOutput(); }
  bool Contains(const std::string& s) { return this->Text().find(s) != std::string::npos; }

private:
  vtkSmartPointer<vtkOutputWindow> Previous;
  vtkNew<vtkStringOutputWindow> Window;
};

/// A polydata of polylines, one per entry of `lines` (each a flat x,y,z list).
inline vtkSmartPointer<vtkPolyData> MakePolylines(const std::vector<std::vector<double>>& lines)
{
  auto polyData = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  vtkNew<vtkCellArray> cells;
  for (const auto& line : lines)
  {
    cells->InsertNextCell(static_cast<int>(line.size() / 3));
    for (size_t k = 0; k < line.size(); k += 3)
    {
      cells->InsertCellPoint(points->InsertNextPoint(line[k], line[k + 1], line[k + 2]));
    }
  }
  polyData->SetPoints(points);
  polyData->SetLines(cells);
  return polyData;
}

inline vtkSmartPointer<vtkMultiBlockDataSet> MakeBlocks(
  const std::vector<std::pair<std::string, vtkSmartPointer<vtkPolyData>>>& blocks)
{
  auto tree = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  for (const auto& block : blocks)
  {
    const unsigned int index = tree->GetNumberOfBlocks();
    tree->SetBlock(index, block.second);
    tree->GetMetaData(index)->Set(vtkCompositeDataSet::NAME(), block.first.c_str());
  }
  return tree;
}

inline std::string BlockName(vtkMultiBlockDataSet* tree, unsigned int index)
{
  return tree->GetMetaData(index)->Get(vtkCompositeDataSet::NAME());
}

/// A deformation filter's Fibres output against its Muscles: a block per muscle, named alike,
/// each `count` polylines with a positive FibreLength, every point inside its muscle (the winding
/// number). `where` names the frame or step in a failure.
inline void ExpectFibresInsideTheirMuscles(
  vtkMultiBlockDataSet* fibres, vtkMultiBlockDataSet* muscles, int count, const std::string& where)
{
  ASSERT_NE(fibres, nullptr) << where;
  ASSERT_EQ(fibres->GetNumberOfBlocks(), muscles->GetNumberOfBlocks()) << where;
  for (unsigned int b = 0; b < fibres->GetNumberOfBlocks(); ++b)
  {
    auto* lines = vtkPolyData::SafeDownCast(fibres->GetBlock(b));
    ASSERT_NE(lines, nullptr) << where;
    EXPECT_EQ(BlockName(fibres, b), BlockName(muscles, b)) << where;
    EXPECT_EQ(lines->GetNumberOfLines(), count) << where;
    vtkDataArray* lengths = lines->GetCellData()->GetArray("FibreLength");
    ASSERT_NE(lengths, nullptr) << where;
    EXPECT_GT(lengths->GetRange()[0], 0.0) << where;
    md::TriangleMesh surface;
    mdvtk::ReadTriangles(vtkPolyData::SafeDownCast(muscles->GetBlock(b)), surface);
    EXPECT_EQ(md::CountOutside(surface, mdvtk::ToPoints(lines->GetPoints()), 0.0), 0)
      << BlockName(fibres, b) << ", " << where;
  }
}
