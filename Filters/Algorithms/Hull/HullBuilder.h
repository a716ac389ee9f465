// SPDX-License-Identifier: BSD-3-Clause
// The progressive hull's builder (docs/DESIGN.md section 3): the hull grown to enclose the surface
// (HullBuilder.cxx) and decimated by edge collapses that keep every point inside it
// (HullCollapse.cxx). The Hull stage's own; ProgressiveHull.cxx builds on it.
#pragma once

#include "Geometry/TriangleGrid.h"
#include "Hull/ProgressiveHull.h"

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <queue>
#include <unordered_map>
#include <utility>
#include <vector>

namespace md::hull
{
using Vec3 = Eigen::Vector3d;
using Face = std::array<int, 3>;

/// Cosine of the smallest angle of a triangle is the largest of the three.
inline double LargestCosine(const Vec3& a, const Vec3& b, const Vec3& c)
{
  const Vec3 ab = (b - a).normalized(), bc = (c - b).normalized(), ca = (a - c).normalized();
  return std::max({ -ab.dot(ca), -bc.dot(ab), -ca.dot(bc) });
}

class HullBuilder
{
public:
  HullBuilder(const TriangleMesh& surface, const HullParameters& parameters);

  HullResult Run(const Points* enclose);

private:
  void Decimate(HullResult& result);

  /// Indices of the points outside the current hull (beyond a hair of its size).
  std::vector<Eigen::Index> Outside(const Points& points) const;

  /// Makes q a hull point, as incremental convex hulls do: a region of
  /// triangles facing q is replaced by a fan from q to the region's boundary.
  /// The smallest bump that does not cross the surface wins: the nearest
  /// facing triangle, the facing triangles within one and two rings of it
  /// (when a disk), the whole connected facing region, other single triangles.
  bool BumpOut(const Vec3& q);

  /// Replaces `region` by triangles from q to each boundary edge, unless one
  /// of them would cross the rest of the surface.
  bool FanOut(const Vec3& q, const std::vector<int>& region, const std::vector<std::pair<int, int>>& boundary);

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
  bool DiskBoundary(const std::vector<int>& region, std::vector<std::pair<int, int>>& loop) const;

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

  int AddFace(const Face& f);

  void KillFace(int id);

  std::vector<int> Neighbours(int v) const;

  // --- the grid of triangle bounding boxes, for self-intersection tests
  /// The live faces in the grid cells that the boxes of `faces` reach, each
  /// once (in NearbyBuffer; this->Visit marks them, instead of sorting).
  const std::vector<int>& FacesNear(const std::vector<Face>& faces);
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
  void InsertInGrid(int id);
  void RebuildGrid(double cellSize);
  /// Coarser cells once a tenth of the triangles span more than two cells.
  void MaintainGrid();

  /// Triangles crossing another triangle of the input (small folds of a scan).
  /// Their planes say nothing reliable about the outside, so the placement
  /// ignores them; collapses then replace the fold.
  void MarkFoldedFaces(const TriangleMesh& surface);

  // --- costing: least added volume, outside every plane around the edge
  void Push(int a, int b) { this->PushCosted(this->Evaluate(a, b), a, b); }

  void PushCosted(const std::optional<Candidate>& candidate, int a, int b);

  static std::uint64_t EdgeKey(int a, int b)
  {
    return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
  }

  /// The cost and position of collapsing edge a-b, if a position exists.
  /// Reads the mesh only, so edges can be costed in parallel.
  std::optional<Candidate> Evaluate(int a, int b) const;

  // --- the collapse itself, after every check
  /// Link condition: a and b share exactly the two neighbours across their edge (its two
  /// triangles in `shared`), and neither of those would be left with two triangles.
  bool LinkConditionHolds(int a, int b, std::vector<int>& shared) const;

  /// Every edge whose neighbourhood changed when `a` took its new place needs a new cost: the
  /// edges of a now (pushed in a fixed order); the other edges of its neighbours lazily, as
  /// placeholders at their last cost (or `cost`, this collapse's) that are costed when they come
  /// to the top, perhaps after more changes.
  void RequeueAround(int a, double cost);

  bool Collapse(int a, int b, const Vec3& position, double cost);

  bool NewFacesAcceptable(const std::vector<int>& changed, const std::vector<Face>& created,
    const std::vector<int>& shared, int a, const Vec3& oldA, std::vector<char>& inheritsCrossing);

  /// Did triangle f cross one of the triangles being replaced, before the
  /// collapse? Scanned surfaces can have small folds; a collapse may carry
  /// such a crossing on (the placement then tends to lift the surface above
  /// the fold) but never start a new one.
  bool CrossedBefore(int f, const std::vector<int>& changed, const std::vector<int>& shared, int a, const Vec3& oldA);

  TriangleMesh Compact() const;

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
