// SPDX-License-Identifier: BSD-3-Clause
#include "Anatomy/AttachmentAreas.h"

#include "Common/Names.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/TriangleTree.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <tuple>

namespace md
{
namespace
{
std::string Trimmed(const std::string& text)
{
  const size_t first = text.find_first_not_of(" \t\r\"");
  const size_t last = text.find_last_not_of(" \t\r\"");
  return first == std::string::npos ? "" : text.substr(first, last - first + 1);
}

std::vector<std::string> Fields(const std::string& line)
{
  std::vector<std::string> fields;
  std::stringstream stream(line);
  std::string field;
  while (std::getline(stream, field, ','))
  {
    fields.push_back(Trimmed(field));
  }
  return fields;
}

/// The index of the first of `names` among `header`, -1 when none.
int ColumnOf(const std::vector<std::string>& header, std::initializer_list<const char*> names)
{
  for (const char* name : names)
  {
    const auto found = std::find(header.begin(), header.end(), name);
    if (found != header.end())
    {
      return static_cast<int>(found - header.begin());
    }
  }
  return -1;
}

double Median(std::vector<double> values)
{
  if (values.empty())
  {
    return 0.0;
  }
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

/// The distance of `p` from the surface of `tree` (0 inside it).
double DistanceFrom(const TriangleTree& tree, const Eigen::Vector3d& p)
{
  return tree.InBounds(p) && tree.Inside(p) ? 0.0 : tree.ClosestPoint(p).distance;
}

/// Each of `points`' DistanceFrom `tree`.
std::vector<double> Distances(const TriangleTree& tree, const Points& points)
{
  std::vector<double> distances;
  for (Eigen::Index i = 0; i < points.rows(); ++i)
  {
    distances.push_back(DistanceFrom(tree, points.row(i).transpose()));
  }
  return distances;
}

/// The one of `trees` nearest to `points` (the least median distance), and that distance.
std::pair<int, double> Nearest(const std::vector<TriangleTree>& trees, const Points& points)
{
  std::pair<int, double> nearest{ -1, std::numeric_limits<double>::infinity() };
  for (size_t k = 0; k < trees.size(); ++k)
  {
    const double d = Median(Distances(trees[k], points));
    if (d < nearest.second)
    {
      nearest = { static_cast<int>(k), d };
    }
  }
  return nearest;
}

/// `name` in lower case without a file extension ("Femur_r.vtk" -> "femur_r"): blocks read from
/// files are often named after them.
std::string Plain(const std::string& name)
{
  return Lower(WithoutExtension(name));
}

/// The index among `names` of the name equal to `name` (ignoring case and file extensions), -1
/// when none.
int Named(const std::vector<std::string>& names, const std::string& name)
{
  for (size_t k = 0; k < names.size(); ++k)
  {
    if (Plain(names[k]) == Plain(name))
    {
      return static_cast<int>(k);
    }
  }
  return -1;
}

/// The points of `bone` nearest to `marks` (at least `count`, and each mark's nearest): the
/// bone's rigid motion there carries the area.
void Anchor(const TriangleMesh& bone, const Points& marks, int count, Attachment& area)
{
  const Eigen::Index n = bone.points.rows();
  std::vector<std::pair<double, Eigen::Index>> nearest(static_cast<size_t>(n));
  std::vector<Eigen::Index> chosen;
  for (Eigen::Index j = 0; j < marks.rows(); ++j)
  {
    Eigen::Index best = 0;
    (bone.points.rowwise() - marks.row(j)).rowwise().squaredNorm().minCoeff(&best);
    chosen.push_back(best);
  }
  for (Eigen::Index i = 0; i < n; ++i)
  {
    nearest[static_cast<size_t>(i)] = { (marks.rowwise() - bone.points.row(i)).rowwise().squaredNorm().minCoeff(), i };
  }
  const size_t take = std::min(nearest.size(), static_cast<size_t>(std::max(count, 4)));
  std::partial_sort(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(take), nearest.end());
  for (size_t k = 0; k < take; ++k)
  {
    chosen.push_back(nearest[k].second);
  }
  std::sort(chosen.begin(), chosen.end());
  chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
  area.anchors = chosen;
  area.anchorsRest.resize(static_cast<Eigen::Index>(chosen.size()), 3);
  for (size_t k = 0; k < chosen.size(); ++k)
  {
    area.anchorsRest.row(static_cast<Eigen::Index>(k)) = bone.points.row(chosen[k]);
  }
}

/// The muscle's points within `reach[j]` of mark j, for any j.
std::vector<Eigen::Index> PointsNear(const TriangleMesh& muscle, const Points& marks, const std::vector<double>& reach)
{
  std::vector<Eigen::Index> points;
  for (Eigen::Index i = 0; i < muscle.points.rows(); ++i)
  {
    for (Eigen::Index j = 0; j < marks.rows(); ++j)
    {
      if ((muscle.points.row(i) - marks.row(j)).norm() <= reach[static_cast<size_t>(j)])
      {
        points.push_back(i);
        break;
      }
    }
  }
  return points;
}

std::string Distance(double value)
{
  std::ostringstream text;
  text.precision(value < 10 ? 2 : 3);
  text << value;
  return text.str();
}
}

std::vector<LandmarkSet> ParseLandmarkTable(const std::string& text, const std::string& source)
{
  std::stringstream stream(text);
  std::string line;
  int lineNumber = 0;
  std::vector<std::string> header;
  while (header.empty() && std::getline(stream, line))
  {
    ++lineNumber;
    if (!Trimmed(line).empty())
    {
      header = Fields(Lower(line));
    }
  }
  const int muscle = ColumnOf(header, { "muscle", "muscle_group" }), bone = ColumnOf(header, { "bone", "attached_to" }),
            area = ColumnOf(header, { "area", "cloud" }), x = ColumnOf(header, { "x", "x_mm" }),
            y = ColumnOf(header, { "y", "y_mm" }), z = ColumnOf(header, { "z", "z_mm" });
  if (muscle < 0 || bone < 0 || x < 0 || y < 0 || z < 0)
  {
    throw InputError("landmark table '" + source +
      "': its first row must name the columns muscle (or muscle_group), bone (or attached_to), x, y and z "
      "(or x_mm, y_mm, z_mm)");
  }
  const int widest = std::max({ muscle, bone, area, x, y, z });
  std::vector<LandmarkSet> sets;
  std::map<std::string, size_t> setOf;
  std::vector<std::vector<Eigen::Vector3d>> marks;
  while (std::getline(stream, line))
  {
    ++lineNumber;
    if (Trimmed(line).empty())
    {
      continue;
    }
    const std::vector<std::string> fields = Fields(line);
    const std::string where = "landmark table '" + source + "', line " + std::to_string(lineNumber);
    if (static_cast<int>(fields.size()) <= widest)
    {
      throw InputError(where + ": " + std::to_string(fields.size()) + " values where the header names " +
        std::to_string(header.size()));
    }
    Eigen::Vector3d p;
    for (int k = 0; k < 3; ++k)
    {
      const std::string& value = fields[static_cast<size_t>(k == 0 ? x : k == 1 ? y : z)];
      char* end = nullptr;
      p[k] = std::strtod(value.c_str(), &end);
      if (value.empty() || *end != '\0' || !std::isfinite(p[k]))
      {
        throw InputError(where + ": '" + value + "' is not a finite number");
      }
    }
    const std::string key = fields[static_cast<size_t>(muscle)] + "\n" +
      (area >= 0 ? fields[static_cast<size_t>(area)] : "") + "\n" + fields[static_cast<size_t>(bone)];
    auto found = setOf.find(key);
    if (found == setOf.end())
    {
      found = setOf.emplace(key, sets.size()).first;
      sets.push_back({ fields[static_cast<size_t>(muscle)], fields[static_cast<size_t>(bone)],
        area >= 0 ? fields[static_cast<size_t>(area)] : "", Points() });
      marks.emplace_back();
    }
    marks[found->second].push_back(p);
  }
  for (size_t s = 0; s < sets.size(); ++s)
  {
    sets[s].points.resize(static_cast<Eigen::Index>(marks[s].size()), 3);
    for (size_t k = 0; k < marks[s].size(); ++k)
    {
      sets[s].points.row(static_cast<Eigen::Index>(k)) = marks[s][k].transpose();
    }
  }
  return sets;
}

FoundAttachments FindAttachments(const std::vector<std::string>& muscleNames, const std::vector<TriangleMesh>& muscles,
  const std::vector<std::vector<Points>>& restLines, const std::vector<std::string>& boneNames,
  const std::vector<TriangleMesh>& bones, const std::vector<LandmarkSet>& landmarks, bool fromLineEnds,
  const AttachmentParameters& parameters)
{
  FoundAttachments found;
  found.areas.resize(muscles.size());
  if (muscles.empty() || bones.empty())
  {
    return found;
  }
  std::vector<TriangleTree> muscleTrees, boneTrees;
  std::vector<double> sizes;
  for (const TriangleMesh& m : muscles)
  {
    muscleTrees.emplace_back(m);
    sizes.push_back(BoxDiagonal(m.points));
  }
  for (const TriangleMesh& b : bones)
  {
    boneTrees.emplace_back(b);
  }
  // The muscle of each named group: by name, else the nearest to all its landmarks together.
  std::map<std::string, int> muscleOfGroup;
  std::vector<std::string> described(muscles.size());
  for (const LandmarkSet& set : landmarks)
  {
    if (muscleOfGroup.count(set.muscle))
    {
      continue;
    }
    int m = Named(muscleNames, set.muscle);
    if (m < 0)
    {
      std::vector<Eigen::Vector3d> group; // every landmark naming this muscle
      for (const LandmarkSet& other : landmarks)
      {
        for (Eigen::Index j = 0; other.muscle == set.muscle && j < other.points.rows(); ++j)
        {
          group.push_back(other.points.row(j).transpose());
        }
      }
      Points all(static_cast<Eigen::Index>(group.size()), 3);
      for (size_t j = 0; j < group.size(); ++j)
      {
        all.row(static_cast<Eigen::Index>(j)) = group[j].transpose();
      }
      double nearest = 0;
      std::tie(m, nearest) = Nearest(muscleTrees, all);
      found.messages.push_back("landmarks '" + set.muscle + "' belong to muscle '" + muscleNames[m] +
        "', the nearest to them (at a median distance of " + Distance(parameters.messageUnit * nearest) +
        " from its surface)");
    }
    muscleOfGroup[set.muscle] = m;
  }
  for (const LandmarkSet& set : landmarks)
  {
    const size_t m = static_cast<size_t>(muscleOfGroup[set.muscle]);
    const std::string label = set.area.empty() ? set.muscle + " on " + set.bone : set.area;
    if (set.points.rows() == 0)
    {
      continue;
    }
    const std::vector<double> fromMuscle = Distances(muscleTrees[m], set.points);
    if (Median(fromMuscle) > parameters.farthestLandmarks * sizes[m])
    {
      found.warnings.push_back("landmarks '" + label + "' lie " +
        Distance(parameters.messageUnit * Median(fromMuscle)) + " from muscle '" + muscleNames[m] +
        "' (median), beyond a quarter of its size: they mark no part of its "
        "surface and are not used");
      continue;
    }
    int b = Named(boneNames, set.bone);
    std::string boneHow;
    if (b < 0)
    {
      double nearest = 0;
      std::tie(b, nearest) = Nearest(boneTrees, set.points);
      boneHow = " ('" + set.bone + "' names no bone: the nearest, at a median distance of " +
        Distance(parameters.messageUnit * nearest) + ")";
    }
    // The landmarks' spacing: how far apart the marks of the area's outline are.
    std::vector<double> spacing;
    for (Eigen::Index j = 0; j < set.points.rows(); ++j)
    {
      double nearest = std::numeric_limits<double>::infinity();
      for (Eigen::Index k = 0; k < set.points.rows(); ++k)
      {
        if (k != j)
        {
          nearest = std::min(nearest, (set.points.row(j) - set.points.row(k)).norm());
        }
      }
      spacing.push_back(nearest);
    }
    const double gap = set.points.rows() > 1 ? Median(spacing) : parameters.lineEndRadius * sizes[m];
    std::vector<double> reach;
    for (double d : fromMuscle)
    {
      reach.push_back(d + gap);
    }
    Attachment area;
    area.bone = boneNames[static_cast<size_t>(b)];
    area.boneIndex = b;
    area.points = PointsNear(muscles[m], set.points, reach);
    area.source = "landmarks '" + label + "'";
    Anchor(bones[static_cast<size_t>(b)], set.points, parameters.anchorCount, area);
    described[m] += (described[m].empty() ? "" : ", ") + area.source + " on '" + area.bone + "'" + boneHow + " (" +
      std::to_string(area.points.size()) + " points)";
    found.areas[m].push_back(std::move(area));
  }
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    if (!found.areas[m].empty() || !fromLineEnds)
    {
      continue;
    }
    // No landmarks: each action line's two ends, where a bone is near.
    for (size_t l = 0; l < restLines[m].size(); ++l)
    {
      const Points& line = restLines[m][l];
      for (Eigen::Index end : { Eigen::Index(0), line.rows() - 1 })
      {
        if (line.rows() < 2)
        {
          continue;
        }
        const Points mark = line.row(end);
        const auto [b, nearest] = Nearest(boneTrees, mark);
        if (b < 0 || nearest > parameters.farthestBone * sizes[m])
        {
          continue;
        }
        Attachment area;
        area.bone = boneNames[static_cast<size_t>(b)];
        area.boneIndex = b;
        // The surface next to the bone there: near the line's end and near the bone.
        const std::vector<Eigen::Index> near = PointsNear(muscles[m], mark,
          { DistanceFrom(muscleTrees[m], mark.row(0).transpose()) + parameters.lineEndRadius * sizes[m] });
        const double gap = parameters.boneGap * sizes[m];
        for (Eigen::Index i : near)
        {
          if (DistanceFrom(boneTrees[static_cast<size_t>(b)], muscles[m].points.row(i).transpose()) <= gap)
          {
            area.points.push_back(i);
          }
        }
        area.source =
          std::string(end == 0 ? "the first" : "the last") + " point of action line " + std::to_string(l + 1);
        if (area.points.empty())
        {
          continue;
        }
        Anchor(bones[static_cast<size_t>(b)], mark, parameters.anchorCount, area);
        described[m] += (described[m].empty() ? "" : ", ") + area.source + " on '" + area.bone + "' (" +
          std::to_string(area.points.size()) + " points)";
        found.areas[m].push_back(std::move(area));
      }
    }
  }
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    found.messages.push_back("muscle '" + muscleNames[m] + "': " +
      (described[m].empty() ? std::string("no attachment area (it moves with its action lines only)")
                            : "attached by " + described[m]));
  }
  return found;
}
}
