// SPDX-License-Identifier: BSD-3-Clause
#include "MDFibres.h"

#include "Anatomy/TendonExcursion.h"
#include "Geometry/MeshChecks.h"
#include "MDBlocks.h"
#include "MDConvert.h"

#include <vtkAlgorithm.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkIdTypeArray.h>
#include <vtkNew.h>
#include <vtkOutputWindow.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkTable.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

namespace mdvtk
{
namespace
{
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDegree = 3.14159265358979323846 / 180.0;

vtkDataArray* SingleNumber(vtkFieldData* data, const std::string& name)
{
  vtkDataArray* array = data ? data->GetArray(name.c_str()) : nullptr;
  return array && array->GetNumberOfTuples() == 1 && array->GetNumberOfComponents() == 1 ? array : nullptr;
}
}

std::vector<double> ReadCoordinates(vtkDataObject* bones, PoseCoordinates& names)
{
  vtkFieldData* data = bones ? bones->GetFieldData() : nullptr;
  if (names.names.empty() && data)
  {
    auto* rotational = vtkStringArray::SafeDownCast(data->GetAbstractArray(array::RotationalCoordinates));
    for (int a = 0; a < data->GetNumberOfArrays(); ++a)
    {
      const char* name = data->GetArrayName(a);
      if (!name || std::string(name) == array::Time || !SingleNumber(data, name))
      {
        continue;
      }
      names.names.emplace_back(name);
      names.rotational.push_back(rotational && rotational->LookupValue(name) >= 0 ? 1 : 0);
    }
  }
  std::vector<double> values;
  for (size_t c = 0; c < names.names.size(); ++c)
  {
    vtkDataArray* array = SingleNumber(data, names.names[c]);
    values.push_back(array ? array->GetTuple1(0) * (names.rotational[c] ? kDegree : 1.0) : kNaN);
  }
  return values;
}

std::vector<std::unique_ptr<md::MuscleFibres>> MakeFibres(vtkAlgorithm* filter, const std::string& filterName,
  int count, const std::vector<md::MotionDeformation::Muscle>& muscles,
  const std::vector<md::MotionDeformation::Bone>& bones, const std::vector<char>& failed)
{
  std::vector<std::unique_ptr<md::MuscleFibres>> fibres(muscles.size());
  if (count <= 0)
  {
    return fibres;
  }
  std::vector<const md::TriangleMesh*> obstacles;
  for (const md::MotionDeformation::Bone& bone : bones)
  {
    obstacles.push_back(&bone.rest);
  }
  md::FibreParameters parameters;
  parameters.count = count;
  std::string report = filterName + ", fibres:";
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    if (failed[m])
    {
      continue;
    }
    try
    {
      const md::FibreEnds ends = md::FindFibreEnds(muscles[m].rest, muscles[m].attachments, muscles[m].restLines);
      fibres[m] = std::make_unique<md::MuscleFibres>(muscles[m].rest, ends, parameters, obstacles);
      report += "\n  muscle '" + muscles[m].name + "': " + std::to_string(fibres[m]->Count()) + " fibres from " +
        ends.originSource + " to " + ends.insertionSource;
      for (const std::string& warning : fibres[m]->Warnings())
      {
        report += " (" + warning + ")";
      }
    }
    catch (const md::Error& e)
    {
      vtkOutputWindow::GetInstance()->DisplayWarningText((filterName + " (" + filter->GetClassName() + "): muscle '" +
        muscles[m].name + "' has no fibres: " + e.what() + "\n")
                                                           .c_str());
    }
  }
  vtkOutputWindow::GetInstance()->DisplayText((report + "\n").c_str());
  return fibres;
}

std::vector<std::string> LineNames(vtkPolyData* lines, const std::string& muscle, size_t count)
{
  auto* given =
    lines ? vtkStringArray::SafeDownCast(lines->GetCellData()->GetAbstractArray(array::ActionLineName)) : nullptr;
  const vtkIdType first = lines ? lines->GetNumberOfVerts() : 0;
  std::vector<std::string> names;
  for (size_t l = 0; l < count; ++l)
  {
    const vtkIdType cell = first + static_cast<vtkIdType>(l);
    if (given && cell < given->GetNumberOfValues() && !given->GetValue(cell).empty())
    {
      names.push_back(given->GetValue(cell));
    }
    else
    {
      names.push_back(count == 1 ? muscle : muscle + " line " + std::to_string(l + 1));
    }
  }
  return names;
}

std::vector<md::TriangleTree> FibreObstacleTrees(
  const std::vector<md::MotionDeformation::Bone>& bones, const std::vector<std::unique_ptr<md::MuscleFibres>>& fibres)
{
  std::vector<md::TriangleTree> trees;
  if (std::none_of(fibres.begin(), fibres.end(), [](const auto& f) { return !!f; }))
  {
    return trees;
  }
  for (const md::MotionDeformation::Bone& bone : bones)
  {
    trees.emplace_back(bone.rest);
    trees.back().BuildDistanceGrid(); // the fibres' test for a point inside a bone
  }
  return trees;
}

md::FibreObstacle BoneWhereItIs(
  const md::TriangleTree& restTree, std::unique_ptr<md::TriangleTree>& moved, const md::Points& now)
{
  const md::Points& rest = restTree.Mesh().points;
  if (const auto rigid = md::RigidMotionOf(rest, now, md::kRigidObstacleShare * md::BoxDiagonal(rest)))
  {
    return { &restTree, *rigid };
  }
  if (!moved)
  {
    moved = std::make_unique<md::TriangleTree>(restTree);
  }
  moved->Refit(now);
  return { moved.get(), md::RigidTransform() };
}

vtkSmartPointer<vtkPolyData> FibrePolylines(const md::Points& points, int perFibre, const std::vector<double>& lengths)
{
  auto polylines = vtkSmartPointer<vtkPolyData>::New();
  polylines->SetPoints(ToVtkPoints(points));
  // Written through raw pointers: ParaView's VTK is built unoptimised, and a call a point shows.
  const auto fibres = static_cast<vtkIdType>(lengths.size());
  vtkNew<vtkIdTypeArray> offsets, connectivity;
  offsets->SetNumberOfTuples(fibres + 1);
  connectivity->SetNumberOfTuples(fibres * perFibre);
  vtkIdType* offset = offsets->GetPointer(0);
  vtkIdType* point = connectivity->GetPointer(0);
  vtkNew<vtkDoubleArray> length;
  length->SetName(array::FibreLength);
  length->SetNumberOfTuples(fibres);
  for (vtkIdType f = 0; f <= fibres; ++f)
  {
    offset[f] = f * perFibre;
  }
  std::iota(point, point + fibres * perFibre, vtkIdType(0));
  std::copy(lengths.begin(), lengths.end(), length->GetPointer(0));
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  polylines->SetLines(cells);
  polylines->GetCellData()->AddArray(length);
  polylines->GetCellData()->SetActiveScalars(array::FibreLength);
  return polylines;
}

void WriteMomentArms(const std::vector<FrameLengths>& frames, const PoseCoordinates& coordinates,
  const std::vector<std::string>& muscleNames, const std::vector<std::vector<std::string>>& lineNames, vtkTable* table)
{
  const auto column = [&](const std::string& name) {
    vtkNew<vtkDoubleArray> array;
    array->SetName(name.c_str());
    array->SetNumberOfTuples(static_cast<vtkIdType>(frames.size()));
    array->Fill(kNaN);
    table->AddColumn(array);
    return array.Get();
  };
  // The rotational coordinates that move over the frames.
  std::vector<size_t> moving;
  for (size_t c = 0; c < coordinates.names.size(); ++c)
  {
    const bool moves = std::any_of(frames.begin(), frames.end(), [&](const FrameLengths& f) {
      return c < f.coordinates.size() &&
        std::abs(f.coordinates[c] - frames.front().coordinates[c]) > md::kCoordinateMoves;
    });
    if (coordinates.rotational[c] && moves)
    {
      moving.push_back(c);
    }
  }
  vtkDoubleArray* time = column(array::Time);
  std::vector<std::vector<double>> q(frames.size()); // [frame][moving coordinate], radians
  for (size_t k = 0; k < frames.size(); ++k)
  {
    time->SetValue(static_cast<vtkIdType>(k), frames[k].time);
    for (size_t c : moving)
    {
      q[k].push_back(c < frames[k].coordinates.size() ? frames[k].coordinates[c] : kNaN);
    }
  }
  for (size_t i = 0; i < moving.size(); ++i)
  {
    vtkDoubleArray* values = column(coordinates.names[moving[i]]);
    for (size_t k = 0; k < frames.size(); ++k)
    {
      values->SetValue(static_cast<vtkIdType>(k), q[k][i] / kDegree);
    }
  }
  // Which frames each frame's moment arm differences, and about which coordinate: found once for
  // every length (md::MomentArmsAlongMotion's).
  const std::vector<md::ExcursionDifference> differences = md::ExcursionDifferences(q);
  for (size_t m = 0; m < muscleNames.size(); ++m)
  {
    const std::string& muscle = muscleNames[m];
    const size_t fibres = frames.empty() || m >= frames[0].fibreLengths.size() ? 0 : frames[0].fibreLengths[m].size();
    if (fibres > 0)
    {
      vtkDoubleArray* spread[3] = { column("FibreLength(" + muscle + ")"), column("FibreLengthMin(" + muscle + ")"),
        column("FibreLengthMax(" + muscle + ")") };
      for (size_t k = 0; k < frames.size(); ++k)
      {
        const md::Spread s = md::SpreadOf(frames[k].fibreLengths[m]);
        spread[0]->SetValue(static_cast<vtkIdType>(k), s.median);
        spread[1]->SetValue(static_cast<vtkIdType>(k), s.low);
        spread[2]->SetValue(static_cast<vtkIdType>(k), s.high);
      }
      std::vector<std::array<vtkDoubleArray*, 3>> armSpread; // [moving coordinate]: median, low, high
      for (size_t c : moving)
      {
        const std::string about = muscle + ", " + coordinates.names[c] + ")";
        armSpread.push_back({ column("FibreMomentArm(" + about), column("FibreMomentArmMin(" + about),
          column("FibreMomentArmMax(" + about) });
      }
      std::vector<double> values;
      for (size_t k = 0; k < frames.size(); ++k)
      {
        const md::ExcursionDifference& d = differences[k];
        if (d.coordinate < 0)
        {
          continue; // NaN: no moment arm at this frame
        }
        values.clear();
        for (size_t f = 0; f < fibres; ++f)
        {
          const double arm = d.Of(frames[d.from].fibreLengths[m][f], frames[d.to].fibreLengths[m][f]);
          if (!std::isnan(arm))
          {
            values.push_back(arm);
          }
        }
        const md::Spread s = md::SpreadOf(values);
        const std::array<vtkDoubleArray*, 3>& to = armSpread[size_t(d.coordinate)];
        to[0]->SetValue(static_cast<vtkIdType>(k), s.median);
        to[1]->SetValue(static_cast<vtkIdType>(k), s.low);
        to[2]->SetValue(static_cast<vtkIdType>(k), s.high);
      }
    }
    for (size_t l = 0; m < lineNames.size() && l < lineNames[m].size(); ++l)
    {
      const std::string& line = lineNames[m][l];
      vtkDoubleArray* length = column("Length(" + line + ")");
      std::vector<double> lengths;
      for (size_t k = 0; k < frames.size(); ++k)
      {
        lengths.push_back(l < frames[k].lineLengths[m].size() ? frames[k].lineLengths[m][l] : kNaN);
        length->SetValue(static_cast<vtkIdType>(k), lengths.back());
      }
      std::vector<vtkDoubleArray*> arm;
      for (size_t c : moving)
      {
        arm.push_back(column("MomentArm(" + line + ", " + coordinates.names[c] + ")"));
      }
      for (size_t k = 0; k < frames.size(); ++k)
      {
        if (differences[k].coordinate >= 0)
        {
          arm[size_t(differences[k].coordinate)]->SetValue(static_cast<vtkIdType>(k), differences[k].Of(lengths));
        }
      }
    }
  }
}
}
