// SPDX-License-Identifier: BSD-3-Clause
#include "Hull/ProgressiveHull.h"

#include "Geometry/ConvexProjection.h"
#include "Geometry/LocalFrame.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/TriangleGrid.h"
#include "Geometry/TriangleIntersection.h"
#include "Geometry/TriangleTree.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <queue>
#include <unordered_map>

namespace md
{
namespace
{
using Vec3 = Eigen::Vector3d;
using Face = std::array<int, 3>;

/// Cosine of the smallest angle of a triangle is the largest of the three.
double LargestCosine(const Vec3& a, const Vec3& b, const Vec3& c)
{
  const Vec3 ab = (b - a).normalized(), bc = (c - b).normalized(), ca = (a - c).normalized();
  return std::max({ -ab.dot(ca), -bc.dot(ab), -ca.dot(bc) });
}

class HullBuilder
{
public:
  HullBuilder(const TriangleMesh& surface, const HullParameters& parameters)
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

  HullResult Run(const Points* enclose)
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

private:
  void Decimate(HullResult& result)
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

  /// Indices of the points outside the current hull (beyond a hair of its size).
  std::vector<Eigen::Index> Outside(const Points& points) const
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

  /// Makes q a hull point, as incremental convex hulls do: a region of
  /// triangles facing q is replaced by a fan from q to the region's boundary.
  /// The smallest bump that does not cross the surface wins: the nearest
  /// facing triangle, the facing triangles within one and two rings of it
  /// (when a disk), the whole connected facing region, other single triangles.
  bool BumpOut(const Vec3& q)
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

  /// Replaces `region` by triangles from q to each boundary edge, unless one
  /// of them would cross the rest of the surface.
  bool FanOut(const Vec3& q, const std::vector<int>& region, const std::vector<std::pair<int, int>>& boundary)
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

  /// Triangles satisfying `faces`, connected through edges to `seed`, within
  /// `rings` steps of it (all of them when rings < 0).
  template<typename Predicate>
  std::vector<int> FacingRegion(int seed, Predicate&& faces, int rings) const
  {
    std::vector<int> region{ seed };
    size_t ringStart = 0;
    for (int ring = 0; rings < 0 || ring < rings; ++ring)
    {
      const size_t ringEnd = region.size();
      for (size_t i = ringStart; i < ringEnd; ++i)
      {
        const Face& face = this->F[region[i]];
        for (int k = 0; k < 3; ++k)
        {
          const int x = face[k], y = face[(k + 1) % 3];
          for (int g : this->VF[x])
          {
            const Face& other = this->F[g];
            if (std::find(other.begin(), other.end(), y) != other.end() &&
              std::find(region.begin(), region.end(), g) == region.end() && faces(other))
            {
              region.push_back(g);
            }
          }
        }
      }
      if (region.size() == ringEnd)
      {
        break;
      }
      ringStart = ringEnd;
    }
    return region;
  }

  /// The boundary of a region of triangles as one loop of directed edges, in
  /// order, when the region is a disk.
  bool DiskBoundary(const std::vector<int>& region, std::vector<std::pair<int, int>>& loop) const
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

  struct Candidate
  {
    double cost;
    int a, b;
    unsigned stampA, stampB;
    Vec3 position;
    bool placeholder = false; // cost a guess: evaluate when popped
    bool operator<(const Candidate& other) const { return this->cost > other.cost; } // min-heap
  };

  Vec3 Normal(const Face& f) const // twice the area, outwards
  {
    return (this->P[f[1]] - this->P[f[0]]).cross(this->P[f[2]] - this->P[f[0]]);
  }

  int AddFace(const Face& f)
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

  void KillFace(int id)
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

  std::vector<int> Neighbours(int v) const
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

  // --- the grid of triangle bounding boxes, for self-intersection tests
  /// The live faces in the grid cells that the boxes of `faces` reach, each
  /// once (in NearbyBuffer; this->Visit marks them, instead of sorting).
  const std::vector<int>& FacesNear(const std::vector<Face>& faces)
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
  /// Whether face f's bounding box and the box [low, high] are apart.
  bool BoxesApart(int f, const Vec3& low, const Vec3& high) const
  {
    return (this->FaceLow[f].array() > high.array()).any() || (this->FaceHigh[f].array() < low.array()).any();
  }
  void Bounds(const Face& f, Vec3& low, Vec3& high) const
  {
    low = this->P[f[0]].cwiseMin(this->P[f[1]]).cwiseMin(this->P[f[2]]);
    high = this->P[f[0]].cwiseMax(this->P[f[1]]).cwiseMax(this->P[f[2]]);
  }
  void InsertInGrid(int id)
  {
    const Vec3& low = this->FaceLow[id];
    const Vec3& high = this->FaceHigh[id];
    if ((high - low).maxCoeff() > 2 * this->Grid.CellSize())
    {
      ++this->OversizedFaces;
    }
    this->Grid.Insert(id, low, high);
  }
  void RebuildGrid(double cellSize)
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
  /// Coarser cells once a tenth of the triangles span more than two cells.
  void MaintainGrid()
  {
    if (this->OversizedFaces * 10 > 2 * this->LiveVertices)
    {
      this->RebuildGrid(2 * this->Grid.CellSize());
    }
  }

  /// Triangles crossing another triangle of the input (small folds of a scan).
  /// Their planes say nothing reliable about the outside, so the placement
  /// ignores them; collapses then replace the fold.
  void MarkFoldedFaces(const TriangleMesh& surface)
  {
    this->Folded.assign(this->F.size(), 0);
    for (const auto& [s, t] : FindSelfIntersections(surface.points, surface.triangles))
    {
      this->Folded[s] = this->Folded[t] = 1;
    }
  }

  // --- costing: least added volume, outside every plane around the edge
  void Push(int a, int b)
  {
    this->PushCosted(this->Evaluate(a, b), a, b);
  }

  void PushCosted(const std::optional<Candidate>& candidate, int a, int b)
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

  static std::uint64_t EdgeKey(int a, int b)
  {
    return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
  }

  /// The cost and position of collapsing edge a-b, if a position exists.
  /// Reads the mesh only, so edges can be costed in parallel.
  std::optional<Candidate> Evaluate(int a, int b) const
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

  // --- the collapse itself, after every check
  /// Link condition: a and b share exactly the two neighbours across their edge (its two
  /// triangles in `shared`), and neither of those would be left with two triangles.
  bool LinkConditionHolds(int a, int b, std::vector<int>& shared) const
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

  /// Every edge whose neighbourhood changed when `a` took its new place needs a new cost: the
  /// edges of a now (pushed in a fixed order); the other edges of its neighbours lazily, as
  /// placeholders at their last cost (or `cost`, this collapse's) that are costed when they come
  /// to the top, perhaps after more changes.
  void RequeueAround(int a, double cost)
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

  bool Collapse(int a, int b, const Vec3& position, double cost)
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

  bool NewFacesAcceptable(const std::vector<int>& changed, const std::vector<Face>& created,
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

  /// Did triangle f cross one of the triangles being replaced, before the
  /// collapse? Scanned surfaces can have small folds; a collapse may carry
  /// such a crossing on (the placement then tends to lift the surface above
  /// the fold) but never start a new one.
  bool CrossedBefore(int f, const std::vector<int>& changed, const std::vector<int>& shared, int a, const Vec3& oldA)
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

  TriangleMesh Compact() const
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

  const HullParameters Parameters;
  std::vector<Vec3> P;
  std::vector<Face> F;
  std::vector<char> FaceAlive;
  std::vector<char> Folded;                              // input triangles that cross another (indexed by face id)
  std::vector<std::pair<int, int>> EdgeBuffer;           // edges to re-cost after a collapse
  std::vector<std::optional<Candidate>> CandidateBuffer; // their costs
  std::unordered_map<std::uint64_t, double> LastCost;    // latest cost of each edge
  std::vector<int> NearbyBuffer;                         // reused by NewFacesAcceptable
  std::vector<unsigned> VisitedFace;                     // last Visit that gathered each face
  std::vector<unsigned> ReplacedMark;                    // Visit in which a face is being replaced
  std::vector<Vec3> FaceLow, FaceHigh;                   // bounding boxes (faces never change)
  unsigned Visit = 0;
  std::vector<char> VertexAlive;
  std::vector<unsigned> Stamp;
  std::vector<std::vector<int>> VF;
  int LiveVertices = 0;
  double Size = 0;
  int OversizedFaces = 0;   // live or dead, since the last rebuild
  TriangleGrid Grid{ 0.0 }; // cell size 0 until the constructor sizes it
  std::priority_queue<Candidate> Heap;
  double MinimumCosine = 0, FoldCosine = 0, SliverCosine = 0;
};
}

HullResult BuildProgressiveHull(const TriangleMesh& surface, const HullParameters& parameters, const Points* enclose)
{
  if (surface.points.rows() < 4 || surface.triangles.rows() < 4)
  {
    throw InputError("the surface is empty or has fewer than 4 points");
  }
  if (parameters.targetNumberOfPoints < 4)
  {
    throw InputError("the target number of hull points must be at least 4");
  }
  if (parameters.targetNumberOfPoints > surface.points.rows())
  {
    throw InputError("the target of " + std::to_string(parameters.targetNumberOfPoints) +
      " hull points is larger than the surface's " + std::to_string(surface.points.rows()) + " points");
  }
  HullBuilder builder(surface, parameters);
  return builder.Run(enclose);
}

MuscleHull BuildMuscleHull(const TriangleMesh& muscle, const HullParameters& parameters)
{
  // In the muscle's local frame: the repair's merging, the placement's margins and the checks'
  // tolerances then mean the same wherever the muscle sits and whatever its units.
  const LocalFrame frame = LocalFrame::Around({ &muscle.points });
  TriangleMesh local = muscle;
  frame.ToLocal(local.points);
  MuscleHull built;
  built.clean = RepairClosedSurface(local, built.report);
  built.result = BuildProgressiveHull(built.clean, parameters, &built.report.pointsToEnclose);
  // A hull that is no closed manifold, or leaves muscle points outside, would map the muscle
  // wrongly (mean value coordinates extrapolate): refuse it rather than hand it on.
  const TriangleMesh& hull = built.result.hull;
  const EdgeReport edges = CheckEdges(hull.triangles);
  if (!edges.IsClosedOrientedManifold() || !(SignedVolume(hull.points, hull.triangles) > 0))
  {
    throw InputError("its hull came out as no closed, outward-oriented manifold surface (" +
      std::to_string(edges.boundaryEdges) + " open, " + std::to_string(edges.nonManifoldEdges) + " non-manifold and " +
      std::to_string(edges.inconsistentEdges) +
      " inconsistently oriented edges): the surface is too noisy or too thin for a hull; smooth or remesh it");
  }
  const std::int64_t outside = CountPointsOutsideHull(hull, local);
  if (outside > 0)
  {
    throw InputError("its hull leaves " + std::to_string(outside) +
      " of its points outside: the surface is too noisy for a hull; smooth or remesh it");
  }
  built.hullVolume = frame.VolumeToWorld(SignedVolume(hull.points, hull.triangles));
  built.cleanVolume = frame.VolumeToWorld(SignedVolume(built.clean.points, built.clean.triangles));
  frame.ToWorld(built.clean.points);
  frame.ToWorld(built.result.hull.points);
  frame.ToWorld(built.report.pointsToEnclose);
  return built;
}

std::int64_t CountPointsOutsideHull(const TriangleMesh& hull, const TriangleMesh& muscle, double slack)
{
  const Points used = UsedPoints(muscle);
  const double size = (used.colwise().maxCoeff() - used.colwise().minCoeff()).norm();
  // Ray parity through a tree sorts out the points well inside fast; the others (on or near the
  // hull, where it touches the muscle, or outside) are settled exactly by the winding number and
  // the distance to the hull, O(triangles) each.
  const TriangleTree tree(hull);
  const auto n = static_cast<long>(used.rows());
  std::vector<char> suspect(static_cast<size_t>(n), 0);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i)
  {
    suspect[static_cast<size_t>(i)] = tree.Inside(used.row(i).transpose()) ? 0 : 1;
  }
  Points suspects(std::count(suspect.begin(), suspect.end(), 1), 3);
  Eigen::Index k = 0;
  for (long i = 0; i < n; ++i)
  {
    if (suspect[static_cast<size_t>(i)])
    {
      suspects.row(k++) = used.row(i);
    }
  }
  return CountOutside(hull, suspects, kOnSurfaceShare * size + slack);
}

void CheckGivenHull(const TriangleMesh& hull, const std::string& hullName, const TriangleMesh& muscle,
  const std::string& muscleName, double slack)
{
  if (!CheckEdges(hull.triangles).IsClosedOrientedManifold() || SignedVolume(hull.points, hull.triangles) <= 0)
  {
    throw InputError(hullName + " is not a closed, outward-oriented manifold surface: build it with HullDecimation");
  }
  const std::int64_t outside = CountPointsOutsideHull(hull, muscle, slack);
  if (outside > 0)
  {
    throw InputError(hullName + " does not enclose " + muscleName + ": " + std::to_string(outside) + " of " +
      std::to_string(UsedPoints(muscle).rows()) +
      " muscle points are outside it, where mean value coordinates extrapolate; build the hull with HullDecimation "
      "or leave Hull empty");
  }
}
}
