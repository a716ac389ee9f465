// SPDX-License-Identifier: BSD-3-Clause
// The progressive hull's edge collapses: each edge costed, the cheapest collapsed where the new
// faces keep every point inside, cross nothing and fold nothing.
#include "Hull/HullBuilder.h"

#include "Geometry/ConvexProjection.h"
#include "Geometry/LocalFrame.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/TriangleIntersection.h"
#include "Geometry/TriangleTree.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace md::hull
{
void HullBuilder::PushCosted(const std::optional<Candidate>& candidate, int a, int b)
{
  if (candidate)
  {
    this->Heap.push(*candidate);
    this->LastCost[EdgeKey(a, b)] = candidate->cost;
  }
  else
  {
    this->LastCost.erase(EdgeKey(a, b));
  }
}

std::optional<HullBuilder::Candidate> HullBuilder::Evaluate(int a, int b) const
{
  // Reused per thread: costing runs in parallel and allocates nothing.
  thread_local std::vector<int> star;
  thread_local std::vector<HalfSpace> halfSpaces;
  star.assign(this->VF[a].begin(), this->VF[a].end());
  for (int f : this->VF[b])
  {
    if (std::find(this->VF[a].begin(), this->VF[a].end(), f) == this->VF[a].end())
    {
      star.push_back(f);
    }
  }
  halfSpaces.clear();
  Vec3 objective = Vec3::Zero();
  const double margin = 1e-10 * this->Size; // rounding never puts the point below a plane
  for (int f : star)
  {
    if (this->Folded[f])
    {
      continue;
    }
    const Vec3 n = this->Normal(this->F[f]);
    objective += n;
    const double length = n.norm();
    if (length <= 0)
    {
      return std::nullopt;
    }
    const Vec3 unit = n / length;
    halfSpaces.push_back({ unit, unit.dot(this->P[this->F[f][0]]) + margin });
  }
  const Vec3 middle = 0.5 * (this->P[a] + this->P[b]);
  const double edge = (this->P[a] - this->P[b]).norm();
  const double objectiveLength = objective.norm();
  if (objectiveLength <= 0)
  {
    return std::nullopt;
  }
  std::optional<Vec3> start = FeasiblePointAlongRay(middle, objective / objectiveLength, halfSpaces);
  if (!start)
  {
    return std::nullopt;
  }
  // min objective.v + (w/2)|v - middle|^2 is the projection of
  // middle - objective/w; w small: the least volume, ties to the middle.
  const Vec3 target = middle - (1000.0 * edge / objectiveLength) * objective;
  std::optional<Vec3> position = ProjectOntoPolyhedron(target, halfSpaces, *start);
  if (!position)
  {
    return std::nullopt;
  }
  double added = 0;
  for (int f : star)
  {
    if (this->Folded[f])
    {
      continue;
    }
    const Vec3 n = this->Normal(this->F[f]);
    const double height = n.dot(*position - this->P[this->F[f][0]]);
    if (height < 0)
    {
      return std::nullopt; // numerically below a plane: never enclose less
    }
    added += height / 6.0;
  }
  return Candidate{ added, a, b, this->Stamp[a], this->Stamp[b], *position, false };
}

bool HullBuilder::LinkConditionHolds(int a, int b, std::vector<int>& shared) const
{
  for (int f : this->VF[a])
  {
    const Face& face = this->F[f];
    if (std::find(face.begin(), face.end(), b) != face.end())
    {
      shared.push_back(f);
    }
  }
  if (shared.size() != 2)
  {
    return false;
  }
  const std::vector<int> na = this->Neighbours(a), nb = this->Neighbours(b);
  std::vector<int> common;
  std::set_intersection(na.begin(), na.end(), nb.begin(), nb.end(), std::back_inserter(common));
  if (common.size() != 2)
  {
    return false;
  }
  for (int w : common)
  {
    if (this->VF[w].size() <= 3)
    {
      return false; // w would be left with two triangles
    }
  }
  return true;
}

void HullBuilder::RequeueAround(int a, double cost)
{
  std::vector<int> ring = this->Neighbours(a);
  ring.push_back(a);
  std::sort(ring.begin(), ring.end());
  for (int v : ring)
  {
    ++this->Stamp[v];
  }
  std::vector<std::pair<int, int>>& edges = this->EdgeBuffer;
  edges.clear();
  for (int w : this->Neighbours(a))
  {
    edges.emplace_back(std::min(a, w), std::max(a, w));
  }
  std::vector<std::optional<Candidate>>& costed = this->CandidateBuffer;
  costed.assign(edges.size(), std::nullopt);
  // Serially: a parallel loop per collapse for a handful of edges saved nothing (10.6 s against
  // 11.0 s on one thread for a 97k-point muscle) and, on a machine busy with other work, made
  // the build five times slower (threads spinning between ~100,000 tiny loops).
  const auto count = static_cast<long>(edges.size());
  for (long i = 0; i < count; ++i)
  {
    costed[i] = this->Evaluate(edges[i].first, edges[i].second);
  }
  for (size_t i = 0; i < edges.size(); ++i)
  {
    this->PushCosted(costed[i], edges[i].first, edges[i].second);
  }
  for (int v : ring)
  {
    if (v == a)
    {
      continue;
    }
    for (int w : this->Neighbours(v))
    {
      // Edges of a are costed above; an edge between two neighbours once.
      if (w == a || (std::binary_search(ring.begin(), ring.end(), w) && w < v))
      {
        continue;
      }
      auto last = this->LastCost.find(EdgeKey(v, w));
      const double guess = last != this->LastCost.end() ? std::max(last->second, cost) : cost;
      Candidate placeholder{ guess, std::min(v, w), std::max(v, w), 0, 0, Vec3::Zero(), true };
      placeholder.stampA = this->Stamp[placeholder.a];
      placeholder.stampB = this->Stamp[placeholder.b];
      this->Heap.push(placeholder);
    }
  }
}

bool HullBuilder::Collapse(int a, int b, const Vec3& position, double cost)
{
  std::vector<int> shared;
  if (!this->LinkConditionHolds(a, b, shared))
  {
    return false;
  }

  // The new triangles: every triangle of a or b but the two on the edge,
  // with a and b replaced by the new point.
  std::vector<int> changed;
  std::vector<Face> created;
  for (int v : { a, b })
  {
    for (int f : this->VF[v])
    {
      if (std::find(shared.begin(), shared.end(), f) != shared.end() ||
        std::find(changed.begin(), changed.end(), f) != changed.end())
      {
        continue;
      }
      Face face = this->F[f];
      std::replace(face.begin(), face.end(), b, a);
      changed.push_back(f);
      created.push_back(face);
    }
  }
  const Vec3 saved = this->P[a];
  this->P[a] = position;
  std::vector<char> inheritsCrossing(created.size(), 0);
  if (!this->NewFacesAcceptable(changed, created, shared, a, saved, inheritsCrossing))
  {
    this->P[a] = saved;
    return false;
  }
  // Commit.
  for (int f : shared)
  {
    this->KillFace(f);
  }
  for (int f : changed)
  {
    this->KillFace(f);
  }
  this->VertexAlive[b] = 0;
  this->VF[b].clear();
  --this->LiveVertices;
  for (size_t i = 0; i < created.size(); ++i)
  {
    const int id = this->AddFace(created[i]);
    this->Folded[id] = inheritsCrossing[i];
  }
  this->MaintainGrid();
  this->RequeueAround(a, cost);
  return true;
}

bool HullBuilder::NewFacesAcceptable(const std::vector<int>& changed, const std::vector<Face>& created,
  const std::vector<int>& shared, int a, const Vec3& oldA, std::vector<char>& inheritsCrossing)
{
  // Old geometry of the changed faces, for the normal and sliver checks.
  const Vec3 newA = this->P[a];
  std::vector<Vec3> newNormals(created.size());
  for (size_t i = 0; i < created.size(); ++i)
  {
    const Face& face = created[i];
    const Vec3 n = this->Normal(face);
    if (n.norm() <= 1e-14 * this->Size * this->Size)
    {
      return false;
    }
    newNormals[i] = n.normalized();
    // Old triangle (before the move of a and the merge of b).
    this->P[a] = oldA;
    const Face& before = this->F[changed[i]];
    const Vec3 oldNormal = this->Normal(before).normalized();
    const double oldCosine = LargestCosine(this->P[before[0]], this->P[before[1]], this->P[before[2]]);
    this->P[a] = newA;
    if (!this->Folded[changed[i]] && newNormals[i].dot(oldNormal) < this->MinimumCosine)
    {
      return false;
    }
    const double newCosine = LargestCosine(this->P[face[0]], this->P[face[1]], this->P[face[2]]);
    if (newCosine > this->SliverCosine && newCosine > oldCosine)
    {
      return false;
    }
  }
  // Folds: each new triangle against its neighbours, new or untouched.
  for (size_t i = 0; i < created.size(); ++i)
  {
    const Face& face = created[i];
    for (int k = 0; k < 3; ++k)
    {
      const int x = face[k], y = face[(k + 1) % 3];
      // The triangle across edge x-y: another new one, or an untouched one.
      bool found = false;
      for (size_t j = 0; j < created.size() && !found; ++j)
      {
        if (j != i && std::find(created[j].begin(), created[j].end(), x) != created[j].end() &&
          std::find(created[j].begin(), created[j].end(), y) != created[j].end())
        {
          found = true;
          if (newNormals[i].dot(newNormals[j]) < this->FoldCosine)
          {
            return false;
          }
        }
      }
      if (found || x == a || y == a)
      {
        continue;
      }
      for (int f : this->VF[x])
      {
        const Face& other = this->F[f];
        if (std::find(changed.begin(), changed.end(), f) != changed.end() ||
          std::find(shared.begin(), shared.end(), f) != shared.end() ||
          std::find(other.begin(), other.end(), y) == other.end())
        {
          continue;
        }
        if (!this->Folded[f] && newNormals[i].dot(this->Normal(other).normalized()) < this->FoldCosine)
        {
          return false;
        }
      }
    }
  }
  // Self-intersection: the new triangles against everything near them.
  const std::vector<int>& nearby = this->FacesNear(created);
  for (const std::vector<int>* replaced : { &changed, &shared })
  {
    for (int f : *replaced)
    {
      this->ReplacedMark[f] = this->Visit;
    }
  }
  for (size_t i = 0; i < created.size(); ++i)
  {
    Face face = created[i];
    const std::array<Vec3, 3> x{ this->P[face[0]], this->P[face[1]], this->P[face[2]] };
    Vec3 low, high;
    this->Bounds(face, low, high);
    for (int f : nearby)
    {
      if (!this->FaceAlive[f] || this->ReplacedMark[f] == this->Visit)
      {
        continue;
      }
      const Face& other = this->F[f];
      if (this->BoxesApart(f, low, high))
      {
        continue;
      }
      const std::array<Vec3, 3> y{ this->P[other[0]], this->P[other[1]], this->P[other[2]] };
      if (TrianglesIntersect(x, face, y, other))
      {
        if (!this->CrossedBefore(f, changed, shared, a, oldA))
        {
          return false;
        }
        inheritsCrossing[i] = 1;
      }
    }
    for (size_t j = i + 1; j < created.size(); ++j)
    {
      const std::array<Vec3, 3> y{ this->P[created[j][0]], this->P[created[j][1]], this->P[created[j][2]] };
      if (TrianglesIntersect(x, face, y, created[j]))
      {
        return false;
      }
    }
  }
  return true;
}

bool HullBuilder::CrossedBefore(
  int f, const std::vector<int>& changed, const std::vector<int>& shared, int a, const Vec3& oldA)
{
  const Vec3 newA = this->P[a];
  this->P[a] = oldA;
  const Face& other = this->F[f];
  const std::array<Vec3, 3> y{ this->P[other[0]], this->P[other[1]], this->P[other[2]] };
  bool crossed = false;
  for (const std::vector<int>* replaced : { &changed, &shared })
  {
    for (int g : *replaced)
    {
      const Face& old = this->F[g];
      const std::array<Vec3, 3> x{ this->P[old[0]], this->P[old[1]], this->P[old[2]] };
      crossed = crossed || TrianglesIntersect(x, old, y, other);
    }
  }
  this->P[a] = newA;
  return crossed;
}
}
