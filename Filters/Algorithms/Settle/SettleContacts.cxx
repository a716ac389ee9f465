// SPDX-License-Identifier: BSD-3-Clause
#include "Settle/SettleContacts.h"

#include "Geometry/MeshChecks.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace md
{

Eigen::Vector3d Where(const Term& t, const Points& points)
{
  if (!t.row)
  {
    return points.row(t.point).transpose();
  }
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& [point, weight] : *t.row)
  {
    sum += weight * points.row(point).transpose();
  }
  return sum;
}

double InverseBetween(const Term& a, const Term& b)
{
  if (a.muscle != b.muscle)
  {
    return 0.0;
  }
  if (!b.row)
  {
    return (*a.column)(b.point);
  }
  double sum = 0;
  for (const auto& [point, weight] : *b.row)
  {
    sum += weight * (*a.column)(point);
  }
  return sum;
}

Contact Linearise(size_t m, Eigen::Index i, size_t o, Eigen::Index triangle, const Eigen::Vector3d& p, bool inside,
  bool violated, const TriangleTree& tree, size_t bones, double offset)
{
  const TriangleMesh& mesh = tree.Mesh();
  auto corner = [&](int k) {
    return Eigen::Vector3d(mesh.points.row(mesh.triangles(triangle, k)).transpose());
  };
  const Eigen::Vector3d q = ClosestPointOnTriangle(p, corner(0), corner(1), corner(2));
  Contact c;
  c.muscle = m;
  c.point = i;
  c.obstacle = o;
  c.triangle = triangle;
  c.violated = violated;
  c.inside = inside;
  c.normal = OutwardNormal(p, q, inside, tree, triangle);
  c.terms.push_back({ m, i, 1.0 });
  if (o < bones)
  {
    c.target = c.normal.dot(q) + offset;
  }
  else
  {
    const Eigen::Vector3d weights = BarycentricCoordinates(mesh, triangle, q);
    for (int k = 0; k < 3; ++k)
    {
      c.terms.push_back({ o - bones, mesh.triangles(triangle, k), -weights(k) });
    }
    c.target = offset;
  }
  return c;
}

void ExcludeOpposedContacts(const std::vector<Contact>& contacts, size_t bones, const Eigen::MatrixXd& system,
  std::vector<char>& active, std::vector<double>& slack, double opposed)
{
  std::vector<Eigen::Index> betweenMuscles;
  for (size_t j = 0; j < slack.size(); ++j)
  {
    if (contacts[j].obstacle >= bones)
    {
      betweenMuscles.push_back(static_cast<Eigen::Index>(j));
    }
  }
  for (size_t a = 0; a < betweenMuscles.size(); ++a)
  {
    for (size_t b = 0; b < a; ++b)
    {
      const Eigen::Index j = betweenMuscles[a], l = betweenMuscles[b];
      const Contact &first = contacts[static_cast<size_t>(j)], &second = contacts[static_cast<size_t>(l)];
      if (first.inside != second.inside && system(j, l) < -opposed * std::sqrt(system(j, j) * system(l, l)))
      {
        const Eigen::Index outside = first.inside ? l : j;
        active[outside] = 0;
        slack[static_cast<size_t>(outside)] = std::numeric_limits<double>::infinity();
      }
    }
  }
}

ContactSearch::ContactSearch(const std::vector<TriangleMesh>& meshes, const std::vector<const SurfaceEnergy*>& energies,
  const std::vector<FixedObstacle>& bones, const std::vector<std::unique_ptr<TriangleTree>>& trees,
  const OverlapMasks* restOverlap, const HeldContacts& held, const std::vector<Points>& previous,
  const SettleParameters& parameters, std::vector<std::vector<char>>& wasInside,
  std::vector<std::vector<double>>& clearance, bool carriesContacts)
  : CarriesContacts(carriesContacts)
  , Meshes(meshes)
  , Energies(energies)
  , Bones(bones)
  , Trees(trees)
  , RestOverlap(restOverlap)
  , Held(held)
  , Previous(previous)
  , Parameters(parameters)
  , WasInside(wasInside)
  , Clearance(clearance)
{
  const size_t count = meshes.size(), obstacles = this->Obstacles();
  // How far each muscle's points moved since the last iteration, and the largest.
  this->Moved.resize(count);
  this->LargestMove.assign(count, 0.0);
  this->Found.resize(count);
  this->Pending.resize(count);
  this->InNow.resize(count);
  this->WasHeld.resize(count);
  for (size_t m = 0; m < count; ++m)
  {
    this->Moved[m] = (meshes[m].points - previous[m]).rowwise().norm();
    for (Eigen::Index i = 0; i < this->Moved[m].size(); ++i)
    {
      this->LargestMove[m] =
        energies[m]->Used()[i] ? std::max(this->LargestMove[m], this->Moved[m](i)) : this->LargestMove[m];
    }
    const auto points = static_cast<size_t>(meshes[m].points.rows());
    this->Found[m].resize(points);
    this->Pending[m].resize(points);
    this->InNow[m].assign(points * obstacles, 0);
    // Which of this muscle's pairs were held, looked up once rather than in the map at every pair.
    this->WasHeld[m].assign(points * obstacles, 0);
    for (auto entry = held.lower_bound({ m, 0, 0 }); entry != held.end() && std::get<0>(entry->first) == m; ++entry)
    {
      this->WasHeld[m][static_cast<size_t>(std::get<1>(entry->first)) * obstacles + std::get<2>(entry->first)] = 1;
    }
    for (Eigen::Index first = 0; first < meshes[m].points.rows(); first += kSearchBlock)
    {
      this->Blocks.emplace_back(m, first);
    }
  }
}

void ContactSearch::Run(int block)
{
  const auto [m, first] = this->Blocks[static_cast<size_t>(block)];
  const Eigen::Index end = std::min(first + kSearchBlock, this->Meshes[m].points.rows());
  for (Eigen::Index i = first; i < end; ++i)
  {
    this->TestPoint(m, i);
  }
}

std::vector<Contact> ContactSearch::Finish(std::vector<Contact>& pending)
{
  std::vector<Contact> contacts;
  for (size_t m = 0; m < this->Meshes.size(); ++m)
  {
    this->WasInside[m] = std::move(this->InNow[m]);
    for (auto& list : this->Found[m])
    {
      for (Contact& c : list)
      {
        contacts.push_back(std::move(c));
      }
    }
    for (auto& list : this->Pending[m])
    {
      for (Contact& c : list)
      {
        pending.push_back(std::move(c));
      }
    }
  }
  return contacts;
}

void ContactSearch::TestPoint(size_t m, Eigen::Index i)
{
  const SurfaceEnergy& energy = *this->Energies[m];
  if (!energy.Used()[i])
  {
    return;
  }
  const size_t bones = this->Bones.size(), obstacles = this->Obstacles();
  const double offset = this->Parameters.contactOffset * energy.Size();
  const double lookahead = this->Parameters.contactLookahead * energy.Size(); // beyond the offset
  const double reach = kClearanceReach * energy.Size();
  const double margin = kClearanceRounding * energy.Size();
  std::vector<double>& clear = this->Clearance[m];
  const Eigen::Vector3d p = this->Meshes[m].points.row(i).transpose();
  for (size_t o = 0; o < obstacles; ++o)
  {
    if ((o >= bones && o - bones == m) || InOverlap(this->RestOverlap, m, o, i))
    {
      continue;
    }
    const size_t flag = static_cast<size_t>(i) * obstacles + o;
    clear[flag] -= this->Moved[m](i) + (o < bones ? 0.0 : this->LargestMove[o - bones]) + margin;
    const bool wasHeld = this->WasHeld[m][flag];
    if (clear[flag] > lookahead && !wasHeld)
    {
      continue; // still outside and neither near nor watched (inNow stays 0)
    }
    const auto before = wasHeld ? this->Held.find({ m, i, o }) : this->Held.end();
    const TriangleTree& tree = this->Obstacle(o);
    // A positive clearance proves the point outside and beyond the offset: only its nearest
    // triangle is needed, for the watched contact.
    const bool inside = clear[flag] <= 0 && tree.InBounds(p) && tree.Inside(p);
    // Outside, a point closer than the offset breaks its constraint too. One search as far
    // as the clearance looks finds the nearest triangle within the offset as well (the same
    // one: the search visits the nearer triangles in the same order).
    const TriangleTree::Closest within = inside ? TriangleTree::Closest() : tree.ClosestPoint(p, reach);
    const bool nearer = within.triangle >= 0 && within.distance * within.distance < offset * offset;
    const double watch = offset + lookahead;
    const bool watched = within.triangle >= 0 && within.distance * within.distance < watch * watch;
    if (!inside && !nearer && !watched && before == this->Held.end())
    {
      clear[flag] = (within.triangle < 0 ? reach : within.distance) - offset - margin;
      continue;
    }
    const bool violated = inside || nearer;
    // A watched point keeps its clearance: the next search need not test it for inside.
    clear[flag] = violated ? 0.0 : (within.triangle < 0 ? reach : within.distance) - offset - margin;
    // A point that went in during the last iteration is held by the triangle it went in
    // through: the nearest may be on the far side of a thin bone. Through a motion (contacts
    // carried), one inside a bone that held it goes out through the triangles that held it, not
    // by its nearest: a frame's start takes a point pressed on a slightly convex ridge of a scan
    // inside near the ridge's bisector, where rounding chooses the nearest face, and the face it
    // went out through chose between two equilibria, one on either side (LHDL hip_flexion frame
    // 23: the gluteus maximus 0.128 mm apart under 1e-7 of input noise). Only there: the one pass
    // from the rest pose, its points deep in the bones, then moved by 19 mm under noise at
    // flexion 60 degrees; inside muscles, which change shape under the triangles that held a
    // point, two crossed spindles stopped with points inside each other; and at a frame's start
    // only, hip_flexion frame 35 moved by 0.73 mm on another seed (docs/DESIGN.md section 7).
    std::optional<TriangleTree::Hit> wayIn;
    if (inside && !this->WasInside[m][flag])
    {
      wayIn = tree.FirstHit(this->Previous[m].row(i).transpose(), p);
    }
    this->InNow[m][flag] = inside;
    std::vector<Eigen::Index> triangles;
    if (wayIn)
    {
      triangles.push_back(wayIn->triangle);
    }
    else if (!inside || before == this->Held.end() || o >= bones || !this->CarriesContacts)
    {
      triangles.push_back(within.triangle >= 0 ? within.triangle : tree.ClosestPoint(p).triangle);
    }
    if (before != this->Held.end())
    {
      triangles.insert(triangles.end(), before->second.begin(), before->second.end());
    }
    std::sort(triangles.begin(), triangles.end());
    triangles.erase(std::unique(triangles.begin(), triangles.end()), triangles.end());
    // Broken or held contacts enter the step; the others are watched (Pending).
    auto& list = (violated || before != this->Held.end() ? this->Found : this->Pending)[m][static_cast<size_t>(i)];
    for (const Eigen::Index t : triangles)
    {
      list.push_back(Linearise(m, i, o, t, p, inside, violated, tree, bones, offset));
    }
  }
}

std::vector<std::vector<double>> BoneClearancesAtEnd(const std::vector<TriangleMesh>& meshes,
  const std::vector<Points>& previous, const std::vector<const SurfaceEnergy*>& energies, size_t bones,
  const std::vector<std::vector<double>>& clearance)
{
  const size_t count = meshes.size(), obstacles = bones + count;
  std::vector<std::vector<double>> left(count);
  for (size_t m = 0; m < count; ++m)
  {
    const Eigen::Index n = meshes[m].points.rows();
    const double margin = kClearanceRounding * energies[m]->Size();
    left[m].assign(static_cast<size_t>(n) * bones, 0.0);
    for (Eigen::Index i = 0; i < n; ++i)
    {
      if (!energies[m]->Used()[i])
      {
        continue; // a duplicate the welded surface does not use: never searched
      }
      const double moved = (meshes[m].points.row(i) - previous[m].row(i)).norm();
      for (size_t o = 0; o < bones; ++o)
      {
        left[m][static_cast<size_t>(i) * bones + o] =
          std::max(0.0, clearance[m][static_cast<size_t>(i) * obstacles + o] - moved - margin);
      }
    }
  }
  return left;
}
}
