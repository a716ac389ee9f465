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
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkTable.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
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
      if (!name || std::string(name) == array::Time || std::string(name) == array::MomentArmStep ||
        !SingleNumber(data, name))
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

std::vector<std::pair<std::string, SteppedLengths>> SteppedPosesOf(
  vtkDataObject* bones, vtkPolyData* bone, const PoseCoordinates& coordinates)
{
  std::vector<std::pair<std::string, SteppedLengths>> poses;
  vtkDataArray* step = SingleNumber(bones ? bones->GetFieldData() : nullptr, array::MomentArmStep);
  if (!step || !bone || step->GetTuple1(0) <= 0.0)
  {
    return poses;
  }
  vtkPointData* data = bone->GetPointData();
  for (int a = 0; a < data->GetNumberOfArrays(); ++a)
  {
    const std::string pose = PoseOfPointsAt(data->GetArrayName(a) ? data->GetArrayName(a) : "");
    if (pose.size() < 2)
    {
      continue; // not a stepped pose: "<coordinate>+" or "<coordinate>-"
    }
    const char sign = pose.back();
    if (sign != '+' && sign != '-')
    {
      continue;
    }
    SteppedLengths stepped;
    const auto c = std::find(coordinates.names.begin(), coordinates.names.end(), pose.substr(0, pose.size() - 1));
    stepped.coordinate = c == coordinates.names.end() ? -1 : static_cast<int>(c - coordinates.names.begin());
    stepped.step = (sign == '+' ? 1.0 : -1.0) * step->GetTuple1(0) * kDegree;
    poses.emplace_back(pose, std::move(stepped));
  }
  return poses;
}

namespace
{
/// Each muscle's `count` fibres (FibreKeeper::KeepOrMake says what), in the muscles' order.
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
  // Each muscle's fibres on their own (a core each), reported in the muscles' order.
  std::vector<md::FibreEnds> ends(muscles.size());
  std::vector<std::string> errors(muscles.size());
  std::vector<std::exception_ptr> unexpected(muscles.size()); // raised again after the loop, as before
#pragma omp parallel for schedule(dynamic, 1)
  for (int m = 0; m < static_cast<int>(muscles.size()); ++m)
  {
    if (failed[size_t(m)])
    {
      continue;
    }
    try
    {
      const md::MotionDeformation::Muscle& muscle = muscles[size_t(m)];
      ends[size_t(m)] = md::FindFibreEnds(muscle.rest, muscle.attachments, muscle.restLines);
      fibres[size_t(m)] = std::make_unique<md::MuscleFibres>(muscle.rest, ends[size_t(m)], parameters, obstacles);
    }
    catch (const md::Error& e)
    {
      errors[size_t(m)] = e.what();
    }
    catch (...)
    {
      unexpected[size_t(m)] = std::current_exception();
    }
  }
  for (const std::exception_ptr& raised : unexpected)
  {
    if (raised)
    {
      std::rethrow_exception(raised);
    }
  }
  std::string report = filterName + ", fibres:";
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    if (!errors[m].empty())
    {
      vtkOutputWindow::GetInstance()->DisplayWarningText((filterName + " (" + filter->GetClassName() + "): muscle '" +
        muscles[m].name + "' has no fibres: " + errors[m] + "\n")
                                                           .c_str());
    }
    if (!fibres[m])
    {
      continue;
    }
    report += "\n  muscle '" + muscles[m].name + "': " + std::to_string(fibres[m]->Count()) + " fibres from " +
      ends[m].originSource + " to " + ends[m].insertionSource;
    for (const std::string& warning : fibres[m]->Warnings())
    {
      report += " (" + warning + ")";
    }
  }
  vtkOutputWindow::GetInstance()->DisplayText((report + "\n").c_str());
  return fibres;
}

/// The rest trees of `bones`, each with its distance grid, that the fibres keep out of; none
/// when no muscle has fibres.
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

bool SameLines(const std::vector<md::Points>& a, const std::vector<md::Points>& b)
{
  return std::equal(a.begin(), a.end(), b.begin(), b.end(),
    [](const md::Points& x, const md::Points& y) { return x.rows() == y.rows() && x == y; });
}

bool SameMuscle(const md::MotionDeformation::Muscle& a, const md::MotionDeformation::Muscle& b)
{
  return a.name == b.name && md::SameMesh(a.rest, b.rest) && SameLines(a.restLines, b.restLines) &&
    a.attachments == b.attachments && a.restKnots == b.restKnots;
}
} // namespace

std::shared_ptr<const MadeFibres> FibreKeeper::KeepOrMake(vtkAlgorithm* filter, const std::string& filterName,
  int count, const std::vector<md::MotionDeformation::Muscle>& muscles,
  const std::vector<md::MotionDeformation::Bone>& bones, const std::vector<char>& failed)
{
  const std::shared_ptr<const MadeFibres>& kept = this->kept;
  if (kept && kept->count == count && kept->failed == failed &&
    std::equal(muscles.begin(), muscles.end(), kept->muscles.begin(), kept->muscles.end(), SameMuscle) &&
    std::equal(bones.begin(), bones.end(), kept->bones.begin(), kept->bones.end(),
      [](const auto& a, const auto& b) { return a.name == b.name && md::SameMesh(a.rest, b.rest); }))
  {
    return kept;
  }
  auto made = std::make_shared<MadeFibres>();
  made->ofMuscle = MakeFibres(filter, filterName, count, muscles, bones, failed);
  made->boneTrees = FibreObstacleTrees(bones, made->ofMuscle);
  made->count = count;
  made->muscles = muscles;
  made->bones = bones;
  made->failed = failed;
  this->kept = made;
  ++this->builds;
  return made;
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
  // How each frame's moment arm about each moving coordinate is found: the central difference of
  // its stepped poses where it has both, else md::MomentArmsAlongMotion's difference between frames.
  const std::vector<md::ExcursionDifference> differences = md::ExcursionDifferences(q);
  struct Source
  {
    int plus = -1, minus = -1; // FrameLengths::stepped
  };
  std::vector<std::vector<Source>> sources(frames.size(), std::vector<Source>(moving.size()));
  bool anyStepped = false, anyDifference = false;
  for (size_t k = 0; k < frames.size(); ++k)
  {
    for (size_t s = 0; s < frames[k].stepped.size(); ++s)
    {
      const SteppedLengths& at = frames[k].stepped[s];
      const auto i = std::find(moving.begin(), moving.end(), static_cast<size_t>(at.coordinate));
      if (at.coordinate >= 0 && i != moving.end())
      {
        (at.step > 0 ? sources[k][size_t(i - moving.begin())].plus : sources[k][size_t(i - moving.begin())].minus) =
          static_cast<int>(s);
      }
    }
  }
  // The moment arm at frame k about moving coordinate i of the length `of` gives at a frame or a
  // stepped pose (both have fibreLengths and lineLengths).
  const auto armAt = [&](size_t k, size_t i, const auto& of) {
    const Source& source = sources[k][i];
    if (source.plus >= 0 && source.minus >= 0)
    {
      const SteppedLengths &plus = frames[k].stepped[size_t(source.plus)],
                           &minus = frames[k].stepped[size_t(source.minus)];
      return -(of(plus) - of(minus)) / (plus.step - minus.step);
    }
    const md::ExcursionDifference& d = differences[k];
    return d.coordinate == static_cast<int>(i) ? d.Of(of(frames[d.from]), of(frames[d.to])) : kNaN;
  };
  for (size_t k = 0; k < frames.size(); ++k)
  {
    for (size_t i = 0; i < moving.size(); ++i)
    {
      const bool stepped = sources[k][i].plus >= 0 && sources[k][i].minus >= 0;
      anyStepped = anyStepped || stepped;
      anyDifference = anyDifference || (!stepped && differences[k].coordinate == static_cast<int>(i));
    }
  }
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
      for (size_t i = 0; i < moving.size(); ++i)
      {
        const std::string about = muscle + ", " + coordinates.names[moving[i]] + ")";
        vtkDoubleArray* armSpread[3] = { column("FibreMomentArm(" + about), column("FibreMomentArmMin(" + about),
          column("FibreMomentArmMax(" + about) };
        std::vector<double> values;
        for (size_t k = 0; k < frames.size(); ++k)
        {
          values.clear();
          for (size_t f = 0; f < fibres; ++f)
          {
            const double arm = armAt(k, i, [&](const auto& at) {
              return m < at.fibreLengths.size() && f < at.fibreLengths[m].size() ? at.fibreLengths[m][f] : kNaN;
            });
            if (!std::isnan(arm))
            {
              values.push_back(arm);
            }
          }
          if (values.empty())
          {
            continue; // NaN: no moment arm at this frame
          }
          const md::Spread s = md::SpreadOf(values);
          armSpread[0]->SetValue(static_cast<vtkIdType>(k), s.median);
          armSpread[1]->SetValue(static_cast<vtkIdType>(k), s.low);
          armSpread[2]->SetValue(static_cast<vtkIdType>(k), s.high);
        }
      }
    }
    for (size_t l = 0; m < lineNames.size() && l < lineNames[m].size(); ++l)
    {
      const std::string& line = lineNames[m][l];
      const auto lengthOf = [&](const auto& at) {
        return m < at.lineLengths.size() && l < at.lineLengths[m].size() ? at.lineLengths[m][l] : kNaN;
      };
      vtkDoubleArray* length = column("Length(" + line + ")");
      for (size_t k = 0; k < frames.size(); ++k)
      {
        length->SetValue(static_cast<vtkIdType>(k), lengthOf(frames[k]));
      }
      for (size_t i = 0; i < moving.size(); ++i)
      {
        vtkDoubleArray* arm = column("MomentArm(" + line + ", " + coordinates.names[moving[i]] + ")");
        for (size_t k = 0; k < frames.size(); ++k)
        {
          arm->SetValue(static_cast<vtkIdType>(k), armAt(k, i, lengthOf));
        }
      }
    }
  }
  vtkNew<vtkStringArray> from;
  from->SetName("MomentArmsFrom");
  from->InsertNextValue(anyStepped
      ? (anyDifference ? "stepped poses, else differences between frames" : "stepped poses")
      : "differences between frames");
  table->GetFieldData()->AddArray(from);
}
}
