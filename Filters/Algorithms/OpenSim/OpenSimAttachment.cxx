// SPDX-License-Identifier: BSD-3-Clause
#include "OpenSim/OpenSimAttachment.h"

#include "Geometry/TriangleTree.h"

#include <algorithm>
#include <cctype>
#include <memory>
#include <sstream>

namespace md::osim
{
namespace
{
std::string Trim(const std::string& s)
{
  const size_t begin = s.find_first_not_of(" \t\r\n");
  return begin == std::string::npos ? "" : s.substr(begin, s.find_last_not_of(" \t\r\n") - begin + 1);
}
}

std::vector<std::pair<std::string, std::vector<std::string>>> ParseAssignments(const std::string& text)
{
  std::vector<std::pair<std::string, std::vector<std::string>>> result;
  std::string normalised = text;
  std::replace(normalised.begin(), normalised.end(), '\n', ';');
  std::stringstream items(normalised);
  std::string item;
  while (std::getline(items, item, ';'))
  {
    item = Trim(item);
    if (item.empty())
    {
      continue;
    }
    const size_t equals = item.find('=');
    if (equals == std::string::npos)
    {
      throw InputError("'" + item + "' is not of the form name=value");
    }
    std::string values = item.substr(equals + 1);
    std::replace(values.begin(), values.end(), ',', ' ');
    std::stringstream words(values);
    std::vector<std::string> list;
    std::string word;
    while (words >> word)
    {
      list.push_back(word);
    }
    result.emplace_back(Trim(item.substr(0, equals)), list);
  }
  return result;
}

int BodyOfSurface(const std::string& surfaceName, const std::vector<std::string>& bodyNames,
  const std::vector<std::pair<std::string, std::vector<std::string>>>& assignments)
{
  const std::string stem = WithoutExtension(surfaceName);
  auto find = [&](const std::string& body) {
    const auto it = std::find(bodyNames.begin(), bodyNames.end(), body);
    return it == bodyNames.end() ? -1 : static_cast<int>(it - bodyNames.begin());
  };
  for (const auto& [name, values] : assignments)
  {
    if ((name == surfaceName || name == stem) && !values.empty())
    {
      const int body = find(values[0]);
      if (body < 0)
      {
        throw InputError("'" + name + "=" + values[0] + "': the model has no body '" + values[0] + "'");
      }
      return body;
    }
  }
  if (const int body = find(stem); body >= 0)
  {
    return body;
  }
  int best = -1;
  for (size_t b = 0; b < bodyNames.size(); ++b)
  {
    const std::string& body = bodyNames[b];
    if (!body.empty() && stem.size() > body.size() && stem.compare(0, body.size(), body) == 0 &&
      !std::isalnum(static_cast<unsigned char>(stem[body.size()])) &&
      (best < 0 || body.size() > bodyNames[best].size()))
    {
      best = static_cast<int>(b);
    }
  }
  return best;
}

namespace
{
/// The length of the segment from `a` to `b` inside the closed surface of `tree`: the segment
/// cut where it crosses the surface, each piece inside or not by its midpoint.
double LengthInside(const TriangleTree& tree, const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
  const double length = (b - a).norm();
  if (!(length > 0))
  {
    return 0.0;
  }
  std::vector<double> cuts = { 0.0 };
  // Past each hit by a hair, so that the next search starts beyond it; a bounded number of
  // searches (a segment crosses a muscle a few times).
  const double hair = 1e-9;
  for (int search = 0; search < 10000 && cuts.back() < 1.0; ++search)
  {
    const Eigen::Vector3d from = a + (cuts.back() + hair) * (b - a);
    const std::optional<TriangleTree::Hit> hit = tree.FirstHit(from, b);
    if (!hit)
    {
      break;
    }
    cuts.push_back(std::min(1.0, cuts.back() + hair + hit->t * (1.0 - cuts.back() - hair)));
  }
  cuts.push_back(1.0);
  double inside = 0.0;
  for (size_t k = 0; k + 1 < cuts.size(); ++k)
  {
    if (cuts[k + 1] > cuts[k] && tree.Inside(a + 0.5 * (cuts[k] + cuts[k + 1]) * (b - a)))
    {
      inside += (cuts[k + 1] - cuts[k]) * length;
    }
  }
  return inside;
}
}

PathGrouping GroupPaths(const std::vector<TriangleMesh>& muscles, const std::vector<std::string>& muscleNames,
  const std::vector<Points>& paths, const std::vector<std::string>& pathNames,
  const std::vector<std::pair<std::string, std::vector<std::string>>>& assignments, double minimumShare)
{
  PathGrouping grouping;
  grouping.muscleOfPath.assign(paths.size(), -1);
  grouping.insideFraction.assign(paths.size(), 0.0);
  grouping.assignedByUser.assign(paths.size(), false);
  for (const auto& [muscle, pathList] : assignments)
  {
    const auto m = std::find(muscleNames.begin(), muscleNames.end(), muscle);
    const std::string& wanted = muscle; // (a lambda may not capture a structured binding in C++17)
    const auto stem = std::find_if(muscleNames.begin(), muscleNames.end(),
      [&](const std::string& name) { return WithoutExtension(name) == wanted; });
    if (m == muscleNames.end() && stem == muscleNames.end())
    {
      throw InputError("'" + muscle + "' is not one of the muscles");
    }
    const int muscleIndex = static_cast<int>((m != muscleNames.end() ? m : stem) - muscleNames.begin());
    for (const std::string& path : pathList)
    {
      const auto p = std::find(pathNames.begin(), pathNames.end(), path);
      if (p == pathNames.end())
      {
        throw InputError("'" + path + "' (given for muscle '" + muscle + "') is not one of the paths");
      }
      grouping.muscleOfPath[p - pathNames.begin()] = muscleIndex;
      grouping.assignedByUser[p - pathNames.begin()] = true;
    }
  }
  std::vector<std::unique_ptr<TriangleTree>> trees;
  for (const TriangleMesh& mesh : muscles)
  {
    trees.push_back(std::make_unique<TriangleTree>(mesh));
  }
  for (size_t p = 0; p < paths.size(); ++p)
  {
    const Points& line = paths[p];
    std::vector<double> inside(muscles.size(), 0.0);
    double total = 0.0;
    for (Eigen::Index s = 0; s + 1 < line.rows(); ++s)
    {
      const Eigen::Vector3d a = line.row(s).transpose(), b = line.row(s + 1).transpose();
      total += (b - a).norm();
      for (size_t m = 0; m < muscles.size(); ++m)
      {
        inside[m] += LengthInside(*trees[m], a, b);
      }
    }
    if (grouping.assignedByUser[p])
    {
      grouping.insideFraction[p] = total > 0 ? inside[grouping.muscleOfPath[p]] / total : 0.0;
      continue;
    }
    const auto best = std::max_element(inside.begin(), inside.end());
    if (best != inside.end() && total > 0 && *best / total >= minimumShare)
    {
      grouping.muscleOfPath[p] = static_cast<int>(best - inside.begin());
      grouping.insideFraction[p] = *best / total;
    }
  }
  return grouping;
}
}
