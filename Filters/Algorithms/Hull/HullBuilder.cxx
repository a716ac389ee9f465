// SPDX-License-Identifier: BSD-3-Clause
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
HullBuilder::HullBuilder(const TriangleMesh& surface, const HullParameters& parameters)
  : Parameters(parameters)
{
  const auto n = static_cast<int>(surface.points.rows());
  this->P.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i)
  {
    this->P[i] = surface.points.row(i).transpose();
  }
  this->VertexAlive.assign(static_cast<size_t>(n), 1);
  this->Stamp.assign(static_cast<size_t>(n), 0);
  this->VF.resize(static_cast<size_t>(n));
  for (Eigen::Index t = 0; t < surface.triangles.rows(); ++t)
  {
    this->AddFace({ static_cast<int>(surface.triangles(t, 0)), static_cast<int>(surface.triangles(t, 1)),
      static_cast<int>(surface.triangles(t, 2)) });
  }
  this->LiveVertices = n;
  const Vec3 low = surface.points.colwise().minCoeff().transpose();
  const Vec3 high = surface.points.colwise().maxCoeff().transpose();
  this->Size = (high - low).norm();
  double edgeSum = 0;
  for (const Face& f : this->F)
  {
    edgeSum += (this->P[f[0]] - this->P[f[1]]).norm();
  }
  this->RebuildGrid(2.0 * edgeSum / static_cast<double>(this->F.size()));
  this->MarkFoldedFaces(surface);
  this->MinimumCosine = std::cos(parameters.maximumNormalDeviationDegrees * M_PI / 180.0);
  this->FoldCosine = std::cos(parameters.maximumFoldAngleDegrees * M_PI / 180.0);
  this->SliverCosine = std::cos(parameters.minimumAngleDegrees * M_PI / 180.0);
}

HullResult HullBuilder::Run(const Points* enclose)
{
  if (enclose && enclose->rows() == 0)
  {
    enclose = nullptr;
  }
  // Every edge costed once, in parallel, then pushed in a fixed order.
  std::vector<std::pair<int, int>> edges;
  for (int v = 0; v < static_cast<int>(this->P.size()); ++v)
  {
    for (int w : this->Neighbours(v))
    {
      if (v < w)
      {
        edges.emplace_back(v, w);
      }
    }
  }
  std::vector<std::optional<Candidate>> costed(edges.size());
  const auto count = static_cast<long>(edges.size());
#pragma omp parallel for schedule(static)
  for (long i = 0; i < count; ++i)
  {
    costed[i] = this->Evaluate(edges[i].first, edges[i].second);
  }
  for (size_t i = 0; i < edges.size(); ++i)
  {
    this->PushCosted(costed[i], edges[i].first, edges[i].second);
  }
  HullResult result;
  // Points to enclose that the surface leaves out become surface points
  // first, while the triangles are small; decimation keeps them inside.
  std::vector<Eigen::Index> outside = enclose ? this->Outside(*enclose) : std::vector<Eigen::Index>{};
  constexpr int rounds = 4;
  for (int round = 0; round <= rounds; ++round)
  {
    for (Eigen::Index i : outside)
    {
      result.pointsBumpedIn += this->BumpOut(enclose->row(i).transpose()) ? 1 : 0;
    }
    this->Decimate(result);
    if (!enclose || (round == 0 && outside.empty()))
    {
      break; // nothing was bumped: decimation encloses what the surface did
    }
    outside = this->Outside(*enclose);
    if (outside.empty())
    {
      break;
    }
  }
  result.pointsLeftOutside = static_cast<std::int64_t>(outside.size());
  result.reachedTarget = this->LiveVertices <= this->Parameters.targetNumberOfPoints;
  result.hull = this->Compact();
  return result;
}

void HullBuilder::Decimate(HullResult& result)
{
  std::uint32_t pops = 0;
  while (this->LiveVertices > this->Parameters.targetNumberOfPoints && !this->Heap.empty())
  {
    if ((++pops & 1023u) == 0 && this->Parameters.cancelled && this->Parameters.cancelled())
    {
      throw Cancelled();
    }
    const Candidate top = this->Heap.top();
    this->Heap.pop();
    if (!this->VertexAlive[top.a] || !this->VertexAlive[top.b] || this->Stamp[top.a] != top.stampA ||
      this->Stamp[top.b] != top.stampB)
    {
      continue; // stale: its neighbourhood changed since it was costed
    }
    if (top.placeholder)
    {
      this->Push(top.a, top.b); // cost it now, against the mesh as it is
      continue;
    }
    if (!this->Collapse(top.a, top.b, top.position, top.cost))
    {
      ++result.rejectedCollapses;
      continue; // re-costed when its neighbourhood next changes
    }
    ++result.collapses;
  }
}

std::vector<Eigen::Index> HullBuilder::Outside(const Points& points) const
{
  const TriangleMesh hull = this->Compact();
  const double tolerance = kOnSurfaceShare * this->Size;
  std::vector<char> isOutside(static_cast<size_t>(points.rows()), 0);
  const auto n = static_cast<long>(points.rows());
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i)
  {
    const Eigen::Vector3d p = points.row(i).transpose();
    if (WindingNumber(hull.points, hull.triangles, p) > 0.5)
    {
      continue;
    }
    double nearest = std::numeric_limits<double>::max();
    for (Eigen::Index t = 0; t < hull.triangles.rows(); ++t)
    {
      nearest = std::min(nearest,
        PointTriangleDistance(p, hull.points.row(hull.triangles(t, 0)).transpose(),
          hull.points.row(hull.triangles(t, 1)).transpose(), hull.points.row(hull.triangles(t, 2)).transpose()));
    }
    isOutside[i] = nearest > tolerance ? 1 : 0;
  }
  std::vector<Eigen::Index> outside;
  for (Eigen::Index i = 0; i < points.rows(); ++i)
  {
    if (isOutside[i])
    {
      outside.push_back(i);
    }
  }
  return outside;
}

bool HullBuilder::BumpOut(const Vec3& q)
{
  auto faces = [&](const Face& face) {
    return this->Normal(face).dot(q - this->P[face[0]]) > 0;
  };
  std::vector<std::pair<double, int>> facing;
  for (int f = 0; f < static_cast<int>(this->F.size()); ++f)
  {
    if (this->FaceAlive[f] && faces(this->F[f]))
    {
      const Face& face = this->F[f];
      facing.emplace_back(PointTriangleDistance(q, this->P[face[0]], this->P[face[1]], this->P[face[2]]), f);
    }
  }
  std::sort(facing.begin(), facing.end());
  if (facing.empty())
  {
    return false;
  }
  auto single = [&](int f) {
    const Face& face = this->F[f];
    return this->FanOut(q, { f }, { { face[0], face[1] }, { face[1], face[2] }, { face[2], face[0] } });
  };
  for (int rings : { 2, 1 })
  {
    const std::vector<int> region = this->FacingRegion(facing.front().second, faces, rings);
    std::vector<std::pair<int, int>> boundary;
    if (region.size() > 1 && this->DiskBoundary(region, boundary) && this->FanOut(q, region, boundary))
    {
      return true;
    }
  }
  if (single(facing.front().second))
  {
    return true;
  }
  constexpr size_t singleTries = 8;
  for (size_t i = 1; i < facing.size() && i < singleTries; ++i)
  {
    if (single(facing[i].second))
    {
      return true;
    }
  }
  return false;
}

bool HullBuilder::FanOut(
  const Vec3& q, const std::vector<int>& region, const std::vector<std::pair<int, int>>& boundary)
{
  const int v = static_cast<int>(this->P.size());
  this->P.push_back(q);
  std::vector<Face> created;
  for (const auto& [x, y] : boundary)
  {
    created.push_back({ x, y, v });
  }
  const std::vector<int>& nearby = this->FacesNear(created);
  for (const Face& face : created)
  {
    const std::array<Vec3, 3> corners{ this->P[face[0]], this->P[face[1]], this->P[face[2]] };
    Vec3 low, high;
    this->Bounds(face, low, high);
    for (int f : nearby)
    {
      const Face& other = this->F[f];
      if (this->FaceAlive[f] && !this->BoxesApart(f, low, high) &&
        std::find(region.begin(), region.end(), f) == region.end() &&
        TrianglesIntersect(corners, face, { this->P[other[0]], this->P[other[1]], this->P[other[2]] }, other))
      {
        this->P.pop_back();
        return false;
      }
    }
  }
  this->VertexAlive.push_back(1);
  this->Stamp.push_back(0);
  this->VF.emplace_back();
  ++this->LiveVertices;
  std::vector<int> touched;
  for (int f : region)
  {
    for (int w : this->F[f])
    {
      touched.push_back(w);
    }
    this->KillFace(f);
  }
  for (const Face& face : created)
  {
    this->AddFace(face);
  }
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  for (int w : touched)
  {
    if (this->VF[w].empty() && this->VertexAlive[w])
    {
      this->VertexAlive[w] = 0; // inside the fan now
      --this->LiveVertices;
    }
  }
  touched.push_back(v);
  this->MaintainGrid();
  for (int w : touched)
  {
    ++this->Stamp[w];
  }
  for (int w : touched)
  {
    if (this->VertexAlive[w])
    {
      for (int x : this->Neighbours(w))
      {
        this->Push(std::min(w, x), std::max(w, x));
      }
    }
  }
  return true;
}

bool HullBuilder::DiskBoundary(const std::vector<int>& region, std::vector<std::pair<int, int>>& loop) const
{
  std::unordered_map<std::uint64_t, int> directed; // edges walked by the region's triangles
  auto key = [](int x, int y) {
    return (static_cast<std::uint64_t>(x) << 32) | static_cast<std::uint32_t>(y);
  };
  std::vector<int> points;
  for (int f : region)
  {
    for (int k = 0; k < 3; ++k)
    {
      directed[key(this->F[f][k], this->F[f][(k + 1) % 3])] = 1;
      points.push_back(this->F[f][k]);
    }
  }
  std::unordered_map<int, int> next;
  int edges = 0;
  for (const auto& [k, unused] : directed)
  {
    const int x = static_cast<int>(k >> 32), y = static_cast<int>(k & 0xffffffffu);
    if (!directed.count(key(y, x)))
    {
      if (next.count(x))
      {
        return false; // a point on the boundary twice: not a disk
      }
      next[x] = y;
      ++edges;
    }
  }
  if (edges < 3)
  {
    return false;
  }
  loop.clear();
  const int start = next.begin()->first;
  int at = start;
  do
  {
    auto found = next.find(at);
    if (found == next.end())
    {
      return false;
    }
    loop.emplace_back(at, found->second);
    at = found->second;
  }
  while (at != start && static_cast<int>(loop.size()) <= edges);
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end()), points.end());
  const int interior = static_cast<int>(points.size()) - edges;
  // One loop through every boundary edge, and Euler's formula of a disk.
  const int regionEdges = (3 * static_cast<int>(region.size()) + edges) / 2;
  return static_cast<int>(loop.size()) == edges &&
    static_cast<int>(points.size()) - regionEdges + static_cast<int>(region.size()) == 1 && interior >= 0;
}

int HullBuilder::AddFace(const Face& f)
{
  const int id = static_cast<int>(this->F.size());
  this->F.push_back(f);
  this->FaceAlive.push_back(1);
  Vec3 low, high;
  this->Bounds(f, low, high);
  this->FaceLow.push_back(low);
  this->FaceHigh.push_back(high);
  this->ReplacedMark.push_back(0);
  if (!this->Folded.empty())
  {
    this->Folded.push_back(0);
  }
  for (int v : f)
  {
    this->VF[v].push_back(id);
  }
  if (this->Grid.CellSize() > 0)
  {
    this->InsertInGrid(id);
  }
  return id;
}

void HullBuilder::KillFace(int id)
{
  this->FaceAlive[id] = 0;
  for (int v : this->F[id])
  {
    auto& faces = this->VF[v];
    faces.erase(std::remove(faces.begin(), faces.end(), id), faces.end());
  }
  // Out of the grid at once, so that cells list live triangles only.
  this->Grid.Remove(id, this->FaceLow[id], this->FaceHigh[id]);
}

std::vector<int> HullBuilder::Neighbours(int v) const
{
  std::vector<int> out;
  for (int f : this->VF[v])
  {
    for (int w : this->F[f])
    {
      if (w != v)
      {
        out.push_back(w);
      }
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

const std::vector<int>& HullBuilder::FacesNear(const std::vector<Face>& faces)
{
  std::vector<int>& nearby = this->NearbyBuffer;
  nearby.clear();
  ++this->Visit;
  this->VisitedFace.resize(this->F.size(), 0);
  const Vec3 pad = Vec3::Constant(kOnSurfaceShare * this->Size);
  for (const Face& face : faces)
  {
    Vec3 low, high;
    this->Bounds(face, low, high);
    this->Grid.ForEachCellIn(low - pad, high + pad, [&](const std::vector<int>& cell) {
      for (int f : cell)
      {
        if (this->VisitedFace[f] != this->Visit && this->FaceAlive[f])
        {
          this->VisitedFace[f] = this->Visit;
          nearby.push_back(f);
        }
      }
    });
  }
  return nearby;
}

void HullBuilder::InsertInGrid(int id)
{
  const Vec3& low = this->FaceLow[id];
  const Vec3& high = this->FaceHigh[id];
  if ((high - low).maxCoeff() > 2 * this->Grid.CellSize())
  {
    ++this->OversizedFaces;
  }
  this->Grid.Insert(id, low, high);
}

void HullBuilder::RebuildGrid(double cellSize)
{
  this->Grid.Reset(cellSize);
  this->OversizedFaces = 0;
  for (int id = 0; id < static_cast<int>(this->F.size()); ++id)
  {
    if (this->FaceAlive[id])
    {
      this->InsertInGrid(id);
    }
  }
}

void HullBuilder::MaintainGrid()
{
  if (this->OversizedFaces * 10 > 2 * this->LiveVertices)
  {
    this->RebuildGrid(2 * this->Grid.CellSize());
  }
}

void HullBuilder::MarkFoldedFaces(const TriangleMesh& surface)
{
  this->Folded.assign(this->F.size(), 0);
  for (const auto& [s, t] : FindSelfIntersections(surface.points, surface.triangles))
  {
    this->Folded[s] = this->Folded[t] = 1;
  }
}

TriangleMesh HullBuilder::Compact() const
{
  std::vector<int> index(this->P.size(), -1);
  int next = 0;
  for (size_t v = 0; v < this->P.size(); ++v)
  {
    if (this->VertexAlive[v] && !this->VF[v].empty())
    {
      index[v] = next++;
    }
  }
  TriangleMesh out;
  out.points.resize(next, 3);
  for (size_t v = 0; v < this->P.size(); ++v)
  {
    if (index[v] >= 0)
    {
      out.points.row(index[v]) = this->P[v].transpose();
    }
  }
  std::vector<Face> faces;
  for (size_t f = 0; f < this->F.size(); ++f)
  {
    if (this->FaceAlive[f])
    {
      faces.push_back({ index[this->F[f][0]], index[this->F[f][1]], index[this->F[f][2]] });
    }
  }
  out.triangles.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f)
  {
    for (int k = 0; k < 3; ++k)
    {
      out.triangles(static_cast<Eigen::Index>(f), k) = faces[f][k];
    }
  }
  return out;
}
}
