// SPDX-License-Identifier: BSD-3-Clause
#include "Intersections/SurfaceSettle.h"

#include "Deformation/NearestSegment.h"
#include "Deformation/VolumeConstrainedSolver.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/SurfaceRepair.h"
#include "Geometry/TriangleTree.h"
#include "Intersections/ActiveSet.h"

#include <Eigen/SparseCholesky>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <set>
#include <tuple>

namespace md
{
namespace
{
using Clock = std::chrono::steady_clock;

/// Barycentric coordinates of q (on the triangle's plane) in triangle t of `mesh`.
Eigen::Vector3d Barycentric(const TriangleMesh& mesh, Eigen::Index t, const Eigen::Vector3d& q)
{
  const Eigen::Vector3d a = mesh.points.row(mesh.triangles(t, 0)).transpose();
  const Eigen::Vector3d b = mesh.points.row(mesh.triangles(t, 1)).transpose();
  const Eigen::Vector3d c = mesh.points.row(mesh.triangles(t, 2)).transpose();
  const Eigen::Vector3d normal = (b - a).cross(c - a);
  const double area = normal.squaredNorm();
  if (!(area > 0))
  {
    return Eigen::Vector3d::Constant(1.0 / 3.0);
  }
  const double u = (c - b).cross(q - b).dot(normal) / area;
  const double v = (a - c).cross(q - c).dot(normal) / area;
  return { u, v, 1 - u - v };
}

using RowEntries = SurfaceEnergy::Row;

/// The rigid motion of `area`'s bone near the area from the rest pose to the pose `bones` are
/// in (fitted at its anchors); none where the bone is not among them (a pose without bones).
RigidTransform AttachmentMotion(const Attachment& area, const std::vector<FixedObstacle>& bones)
{
  if (area.boneIndex < 0 || area.boneIndex >= static_cast<Eigen::Index>(bones.size()) || area.anchors.empty())
  {
    return RigidTransform();
  }
  const Points& now = bones[static_cast<size_t>(area.boneIndex)].tree->Mesh().points;
  Points anchors(static_cast<Eigen::Index>(area.anchors.size()), 3);
  for (size_t k = 0; k < area.anchors.size(); ++k)
  {
    anchors.row(static_cast<Eigen::Index>(k)) = now.row(area.anchors[k]);
  }
  return FitRigidTransform(area.anchorsRest, anchors).transform;
}

/// The sample p (inside the surface) as a combination of surface points: along
/// each axis the chord through p meets the surface at h+ (distance d+) and h-
/// (d-), and p = (d- h+ + d+ h-) / (d+ + d-), each hit a combination of its
/// triangle's corners; the mean over the axes that have both hits. Empty when
/// no axis has.
RowEntries ChordRow(const TriangleTree& tree, const Eigen::Vector3d& p, double reach)
{
  const TriangleMesh& mesh = tree.Mesh();
  RowEntries entries;
  int chords = 0;
  for (int axis = 0; axis < 3; ++axis)
  {
    const Eigen::Vector3d way = reach * Eigen::Vector3d::Unit(axis);
    const auto ahead = tree.FirstHit(p, p + way), behind = tree.FirstHit(p, p - way);
    if (!ahead || !behind || !(ahead->t + behind->t > 0))
    {
      continue;
    }
    const double toAhead = ahead->t / (ahead->t + behind->t); // share of the hit behind
    for (const auto& [hit, share] : { std::pair{ *ahead, 1 - toAhead }, std::pair{ *behind, toAhead } })
    {
      const Eigen::Vector3d weights = Barycentric(mesh, hit.triangle, hit.point);
      for (int k = 0; k < 3; ++k)
      {
        entries.emplace_back(mesh.triangles(hit.triangle, k), share * weights(k));
      }
    }
    ++chords;
  }
  for (auto& entry : entries)
  {
    entry.second /= chords;
  }
  return entries;
}
}

SurfaceEnergy::SurfaceEnergy(const TriangleMesh& rest, const std::vector<MatchedLine>& restLines,
  const SettleParameters& parameters, const std::vector<Attachment>& attachments)
  : RestPoints(rest.points)
  , SamplesPerSegment(std::max(1, parameters.samplesPerSegment))
  , Attachments(attachments)
{
  const Eigen::Index n = rest.points.rows();
  std::vector<std::int64_t> representative;
  const TriangleMesh welded{ rest.points, WeldedTriangles(rest, representative) };
  this->Welded = welded.triangles;
  this->PointUsed = UsedMask(welded);
  this->Span = BoxDiagonal(UsedPoints(welded));
  this->FindLeaders(rest, representative);
  const Eigen::Index used = std::count(this->PointUsed.begin(), this->PointUsed.end(), 1);
  if (used == 0)
  {
    throw InputError("the surface has no triangles");
  }
  for (const Attachment& area : attachments)
  {
    if (std::any_of(area.points.begin(), area.points.end(), [n](Eigen::Index i) { return i < 0 || i >= n; }) ||
      static_cast<Eigen::Index>(area.anchors.size()) != area.anchorsRest.rows())
    {
      throw InputError("its attachment area on '" + area.bone + "' names points it does not have");
    }
  }
  // The volume and the inside of the muscle need a closed surface (the hull-based pass needs
  // one too: its hull cannot enclose an open one). Scans' few edges shared by four triangles
  // (two sheets touching) do no harm.
  const EdgeReport edges = CheckEdges(this->Welded);
  if (!edges.Closed())
  {
    throw InputError("its surface is open: " + std::to_string(edges.boundaryEdges) +
      " edges border a hole; close it (e.g. Fill Holes) before deforming it");
  }

  // The action-line samples inside the rest muscle, as sparse rows.
  Points samples, unused;
  SampleMatchedLines(restLines, this->SamplesPerSegment, samples, unused);
  const TriangleTree tree(welded);
  std::vector<RowEntries> sampleRows;
  for (Eigen::Index s = 0; s < samples.rows(); ++s)
  {
    const Eigen::Vector3d p = samples.row(s).transpose();
    if (!tree.InBounds(p) || !tree.Inside(p))
    {
      continue;
    }
    RowEntries row = ChordRow(tree, p, 2 * this->Span);
    if (!row.empty())
    {
      this->SampleIndex.push_back(s);
      this->SampleClearance.push_back(tree.ClosestPoint(p).distance);
      sampleRows.push_back(std::move(row));
    }
  }
  if (sampleRows.empty())
  {
    throw InputError("none of its action-line samples lies inside the muscle");
  }

  const SparseMatrix laplacian = CotangentLaplacian(welded, parameters.largestCotangent);
  this->Delta = laplacian * rest.points;
  const double balance = std::max(1.0, parameters.balancePoints);
  this->ShapeWeight = std::sqrt(static_cast<double>(used) / balance);
  this->FollowWeight = std::max(0.0, parameters.followWeight) * std::sqrt(balance / static_cast<double>(used));
  this->BlendWidth = std::max(0.0, parameters.blendWidth);
  this->AttachmentWeight = std::max(0.0, parameters.attachmentWeight) * this->ShapeWeight;

  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index i = 0; i < n; ++i)
  {
    if (!this->PointUsed[i])
    {
      this->Delta.row(i).setZero();
      continue;
    }
    for (SparseMatrix::InnerIterator it(laplacian, i); it; ++it)
    {
      entries.emplace_back(i, it.col(), this->ShapeWeight * it.value());
    }
  }
  const Eigen::Index sampleStart = n, followStart = n + this->SampleCount();
  for (size_t s = 0; s < sampleRows.size(); ++s)
  {
    for (const auto& [point, weight] : sampleRows[s])
    {
      entries.emplace_back(sampleStart + static_cast<Eigen::Index>(s), point, weight);
    }
  }
  this->SampleRows = std::move(sampleRows);
  int pieces = 0;
  const std::vector<int> piece = Components(this->Welded, n, pieces, &this->PointUsed);
  if (pieces > 1)
  {
    std::vector<char> driven(static_cast<size_t>(pieces), 0);
    for (const Row& row : this->SampleRows)
    {
      for (const auto& entry : row)
      {
        driven[static_cast<size_t>(piece[static_cast<size_t>(entry.first)])] = 1;
      }
    }
    for (Eigen::Index i = 0; i < n; ++i)
    {
      this->Undriven += piece[i] >= 0 && !driven[static_cast<size_t>(piece[i])] ? 1 : 0;
    }
  }
  this->FollowRowWeights = this->FollowWeights();
  for (Eigen::Index i = 0; i < n; ++i)
  {
    entries.emplace_back(followStart + i, i, this->FollowRowWeights[static_cast<size_t>(i)]);
  }
  this->Rows.resize(followStart + n, n);
  this->Rows.setFromTriplets(entries.begin(), entries.end());
  this->Normal = SparseMatrix(this->Rows.transpose() * this->Rows);
  this->Factor.compute(this->Normal);
  if (this->Factor.info() != Eigen::Success)
  {
    throw ComputationError("its full-mesh system could not be factorised");
  }
}

void SurfaceEnergy::FindLeaders(const TriangleMesh& rest, const std::vector<std::int64_t>& representative)
{
  const Eigen::Index n = rest.points.rows();
  const std::vector<char> usedBefore = UsedMask(rest);
  std::unordered_map<Eigen::Index, size_t> orphan; // points that only degenerate triangles used
  for (Eigen::Index i = 0; i < n; ++i)
  {
    if (this->PointUsed[i] || !usedBefore[i])
    {
      continue;
    }
    Follower follower;
    follower.point = i;
    const Eigen::Index twin = representative[static_cast<size_t>(i)];
    if (this->PointUsed[twin])
    {
      follower.leaders.push_back(twin);
    }
    else
    {
      orphan.emplace(i, this->Leaders.size());
    }
    this->Leaders.push_back(std::move(follower));
  }
  // An orphan follows the welded points of its triangles.
  for (Eigen::Index t = 0; t < rest.triangles.rows() && !orphan.empty(); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      const auto found = orphan.find(rest.triangles(t, k));
      if (found == orphan.end())
      {
        continue;
      }
      for (int l = 1; l < 3; ++l)
      {
        const Eigen::Index other = representative[static_cast<size_t>(rest.triangles(t, (k + l) % 3))];
        if (this->PointUsed[other])
        {
          this->Leaders[found->second].leaders.push_back(other);
        }
      }
    }
  }
  for (Follower& follower : this->Leaders)
  {
    std::vector<Eigen::Index>& leaders = follower.leaders;
    std::sort(leaders.begin(), leaders.end());
    leaders.erase(std::unique(leaders.begin(), leaders.end()), leaders.end());
    const Eigen::Index k = static_cast<Eigen::Index>(leaders.size());
    const Eigen::RowVector3d p = rest.points.row(follower.point);
    if (k == 0)
    {
      follower.offset = p; // nothing to follow: it stays
      continue;
    }
    // The affine combination of the leaders nearest to the point: least squares on the
    // leaders' differences from the first (the weights then sum to 1), the smallest such
    // weights where the leaders are not independent (collinear corners of a degenerate triangle).
    Eigen::MatrixXd differences(3, k - 1);
    for (Eigen::Index j = 1; j < k; ++j)
    {
      differences.col(j - 1) = (rest.points.row(leaders[j]) - rest.points.row(leaders[0])).transpose();
    }
    Eigen::VectorXd rest0 = Eigen::VectorXd::Zero(k - 1);
    if (k > 1)
    {
      rest0 = differences.completeOrthogonalDecomposition().solve(
        Eigen::Vector3d((p - rest.points.row(leaders[0])).transpose()));
    }
    follower.weights.assign(static_cast<size_t>(k), 0.0);
    follower.weights[0] = 1 - rest0.sum();
    for (Eigen::Index j = 1; j < k; ++j)
    {
      follower.weights[static_cast<size_t>(j)] = rest0(j - 1);
    }
    Eigen::RowVector3d combined = Eigen::RowVector3d::Zero();
    for (Eigen::Index j = 0; j < k; ++j)
    {
      combined += follower.weights[static_cast<size_t>(j)] * rest.points.row(leaders[j]);
    }
    follower.offset = p - combined;
  }
}

void SurfaceEnergy::CarryToUnwelded(Points& settled) const
{
  for (const Follower& follower : this->Leaders)
  {
    Eigen::RowVector3d place = follower.offset;
    for (size_t j = 0; j < follower.leaders.size(); ++j)
    {
      place += follower.weights[j] * settled.row(follower.leaders[j]);
    }
    settled.row(follower.point) = place;
  }
}

namespace
{
/// The muscles' indices, the one whose factor costs most to solve with first: a parallel loop
/// over the muscles that hands them out in this order (schedule dynamic) starts the longest
/// solve at once instead of leaving it to the end while the other core idles (the LHDL gluteus
/// maximus's factor has as many entries as the other three muscles' together).
std::vector<int> CostliestFirst(const std::vector<const SurfaceEnergy*>& energies)
{
  std::vector<int> order(energies.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
    [&](int a, int b) { return energies[a]->FactorEntries() > energies[b]->FactorEntries(); });
  return order;
}

/// Overwrites the rows of `y` (the factor's order) by (L D L^T)^-1 y, every column at once: the
/// columns share one pass over L, which is what the solve's time goes on. The forward pass skips
/// the rows still zero: for a unit vector it touches only the points the elimination reaches.
/// The row each column of L reads (forward) or writes (backward) is held in a local copy: through
/// `y` the compiler must store and load it again at every entry, as a row below could alias it.
/// The backward pass sums a row's terms in two interleaved halves: two independent chains of
/// additions keep the core busy where one waits on each addition (the LHDL gluteus maximus's
/// factor has 129 entries a column; four halves were no faster).
template<class Rows>
void SolveFactored(
  const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& lower, const Eigen::VectorXd& diagonal, Rows& y)
{
  using Row = Eigen::Matrix<double, 1, Rows::ColsAtCompileTime, Eigen::RowMajor>;
  const Eigen::Index n = lower.cols();
  const auto* start = lower.outerIndexPtr();
  const auto* row = lower.innerIndexPtr();
  const double* value = lower.valuePtr();
  for (Eigen::Index j = 0; j < n; ++j)
  {
    const Row yj = y.row(j);
    if ((yj.array() == 0.0).all())
    {
      continue;
    }
    for (auto k = start[j]; k < start[j + 1]; ++k)
    {
      y.row(row[k]) -= value[k] * yj;
    }
  }
  for (Eigen::Index j = 0; j < n; ++j)
  {
    y.row(j) *= 1.0 / diagonal(j);
  }
  for (Eigen::Index j = n - 1; j >= 0; --j)
  {
    Row even = y.row(j), odd = Row::Zero();
    auto k = start[j];
    for (; k + 1 < start[j + 1]; k += 2)
    {
      even -= value[k] * y.row(row[k]);
      odd -= value[k + 1] * y.row(row[k + 1]);
    }
    if (k < start[j + 1])
    {
      even -= value[k] * y.row(row[k]);
    }
    y.row(j) = even + odd;
  }
}
}

Points SurfaceEnergy::Solve(const Points& rhs) const
{
  const auto& order = this->Factor.permutationP().indices();
  Points y(rhs.rows(), 3);
  for (Eigen::Index i = 0; i < rhs.rows(); ++i)
  {
    y.row(order(i)) = rhs.row(i);
  }
  SolveFactored(this->Factor.matrixL().nestedExpression(), this->Factor.vectorD(), y);
  Points x(rhs.rows(), 3);
  for (Eigen::Index i = 0; i < rhs.rows(); ++i)
  {
    x.row(i) = y.row(order(i));
  }
  return x;
}

void SurfaceEnergy::Prepare(const std::vector<Eigen::Index>& keys) const
{
  PrepareAll({ this }, { keys });
}

std::vector<Eigen::Index> SurfaceEnergy::Missing(const std::vector<Eigen::Index>& keys) const
{
  std::vector<Eigen::Index> missing;
  for (const Eigen::Index p : keys)
  {
    if (this->Columns.find(p) == this->Columns.end())
    {
      missing.push_back(p);
    }
  }
  std::sort(missing.begin(), missing.end());
  missing.erase(std::unique(missing.begin(), missing.end()), missing.end());
  return missing;
}

void SurfaceEnergy::SolveColumns(const Eigen::Index* keys, size_t width, Eigen::VectorXd* solved) const
{
  // One pass over the factor for up to kBlock columns.
  using Block = Eigen::Matrix<double, Eigen::Dynamic, kBlock, Eigen::RowMajor>;
  const Eigen::Index n = this->Normal.rows();
  const auto& order = this->Factor.permutationP().indices();
  Block y = Block::Zero(n, kBlock);
  for (size_t k = 0; k < width; ++k)
  {
    const Eigen::Index key = keys[k];
    if (key >= 0)
    {
      y(order(key), static_cast<Eigen::Index>(k)) = 1.0;
    }
    else
    {
      for (const auto& [point, weight] : this->SampleRow(-1 - key))
      {
        y(order(point), static_cast<Eigen::Index>(k)) += weight;
      }
    }
  }
  SolveFactored(this->Factor.matrixL().nestedExpression(), this->Factor.vectorD(), y);
  for (size_t k = 0; k < width; ++k)
  {
    Eigen::VectorXd& column = solved[k];
    column.resize(n);
    for (Eigen::Index i = 0; i < n; ++i)
    {
      column(i) = y(order(i), static_cast<Eigen::Index>(k));
    }
  }
}

void SurfaceEnergy::PrepareAll(
  const std::vector<const SurfaceEnergy*>& energies, const std::vector<std::vector<Eigen::Index>>& keys)
{
  // Every muscle's missing columns in blocks, all blocks in one parallel loop: the muscles'
  // blocks keep both cores busy where one muscle alone has few.
  std::vector<std::vector<Eigen::Index>> missing(energies.size());
  std::vector<std::vector<Eigen::VectorXd>> solved(energies.size());
  std::vector<std::pair<size_t, size_t>> blocks; // (muscle, first column)
  for (const int muscle : CostliestFirst(energies))
  {
    const auto m = static_cast<size_t>(muscle);
    missing[m] = energies[m]->Missing(keys[m]);
    solved[m].resize(missing[m].size());
    for (size_t first = 0; first < missing[m].size(); first += kBlock)
    {
      blocks.emplace_back(m, first);
    }
  }
#pragma omp parallel for schedule(dynamic, 1)
  for (int b = 0; b < static_cast<int>(blocks.size()); ++b)
  {
    const auto [m, first] = blocks[static_cast<size_t>(b)];
    const size_t width = std::min<size_t>(kBlock, missing[m].size() - first);
    energies[m]->SolveColumns(missing[m].data() + first, width, solved[m].data() + first);
  }
  for (size_t m = 0; m < energies.size(); ++m)
  {
    for (size_t k = 0; k < missing[m].size(); ++k)
    {
      energies[m]->Columns.emplace(missing[m][k], std::move(solved[m][k]));
    }
  }
}

const Eigen::VectorXd& SurfaceEnergy::InverseColumn(Eigen::Index key) const
{
  auto column = this->Columns.find(key);
  if (column == this->Columns.end())
  {
    this->Prepare({ key });
    column = this->Columns.find(key);
  }
  return column->second;
}

namespace
{
/// The direction out of an obstacle at `q`, its surface point (on `triangle`) nearest to `p`:
/// from q towards p when p is outside, from p towards q when p is inside, and the triangle's
/// normal when p lies on it.
Eigen::Vector3d Outwards(
  const Eigen::Vector3d& p, const Eigen::Vector3d& q, bool inside, const TriangleTree& tree, Eigen::Index triangle)
{
  const double distance = (p - q).norm();
  return distance > 0 ? Eigen::Vector3d((inside ? -1.0 : 1.0) * (p - q) / distance) : tree.Normal(triangle);
}

/// Where an action-line sample `p` pulls the muscle when the line runs through a bone or
/// nearer to it than `clearance` (the sample's depth inside its rest muscle): to the bone's
/// nearest surface point, `clearance` out along the outward direction, so that the muscle
/// around the sample fits outside the bone. Otherwise `p` itself; the two agree where the
/// sample is `clearance` from the bone, so the target moves continuously with the line.
Eigen::Vector3d OutsideBones(Eigen::Vector3d p, double clearance, const std::vector<FixedObstacle>& bones)
{
  for (const FixedObstacle& bone : bones)
  {
    const TriangleTree& tree = *bone.tree;
    const bool inside = tree.InBounds(p) && tree.Inside(p);
    const TriangleTree::Closest near = inside ? tree.ClosestPoint(p) : tree.ClosestPoint(p, clearance);
    if (near.triangle < 0)
    {
      continue;
    }
    p = near.point + clearance * Outwards(p, near.point, inside, tree, near.triangle);
  }
  return p;
}

/// How far p is inside the bone it is deepest in, negative (the signed distance from the bone's
/// surface), or 0 when it is inside none.
double DepthInBones(const Eigen::Vector3d& p, const std::vector<FixedObstacle>& bones)
{
  double depth = 0;
  for (const FixedObstacle& bone : bones)
  {
    const TriangleTree& tree = *bone.tree;
    if (tree.InBounds(p) && tree.Inside(p))
    {
      depth = std::min(depth, -tree.ClosestPoint(p).distance);
    }
  }
  return depth;
}
}

std::vector<double> SurfaceEnergy::SampleDepthsInBones(
  const std::vector<MatchedLine>& lines, const std::vector<FixedObstacle>& bones) const
{
  Points restSamples, currentSamples;
  SampleMatchedLines(lines, this->SamplesPerSegment, restSamples, currentSamples);
  std::vector<double> distances(this->SampleIndex.size());
  for (size_t s = 0; s < distances.size(); ++s)
  {
    distances[s] = DepthInBones(currentSamples.row(this->SampleIndex[s]).transpose(), bones);
  }
  return distances;
}

std::vector<SurfaceEnergy::LetGo> SurfaceEnergy::SamplesLetGo(const std::vector<MatchedLine>& lines,
  const std::vector<FixedObstacle>& bones, const std::vector<double>* restDepths) const
{
  Points restSamples, currentSamples;
  SampleMatchedLines(lines, this->SamplesPerSegment, restSamples, currentSamples);
  std::vector<LetGo> letGo;
  for (size_t s = 0; s < this->SampleIndex.size(); ++s)
  {
    const double inMuscle = this->SampleClearance[s]; // its depth in the rest muscle
    const Eigen::Vector3d p = currentSamples.row(this->SampleIndex[s]).transpose();
    // From the bone's surface, or from as deep as the sample was at rest (a line that ends in
    // the bone it is attached to), to its depth in the rest muscle further in.
    const double from = restDepths && s < restDepths->size() ? (*restDepths)[s] : 0.0;
    const double share = std::clamp((from - DepthInBones(p, bones)) / inMuscle, 0.0, 1.0);
    if (share > 1e-9)
    {
      letGo.push_back({ static_cast<Eigen::Index>(s), share, OutsideBones(p, inMuscle, bones) });
    }
  }
  return letGo;
}

std::vector<MatchedLine> StillLines(const std::vector<Points>& restLines, const std::vector<Knots>& knots)
{
  std::vector<MatchedLine> still;
  for (size_t l = 0; l < restLines.size(); ++l)
  {
    still.push_back({ restLines[l], restLines[l], l < knots.size() ? knots[l] : Knots() });
  }
  return still;
}

std::vector<MatchedLine> StillLines(const std::vector<MatchedLine>& lines)
{
  std::vector<MatchedLine> still;
  for (const MatchedLine& line : lines)
  {
    still.push_back({ line.rest, line.rest, line.knots });
  }
  return still;
}

std::vector<double> SurfaceEnergy::FollowWeights() const
{
  std::vector<double> weights(this->PointUsed.size());
  for (size_t i = 0; i < weights.size(); ++i)
  {
    weights[i] = this->PointUsed[i] ? this->FollowWeight : 1.0; // nothing else places an unused point
  }
  for (const Attachment& area : this->Attachments)
  {
    for (Eigen::Index i : area.points)
    {
      if (this->PointUsed[static_cast<size_t>(i)])
      {
        weights[static_cast<size_t>(i)] = this->AttachmentWeight;
      }
    }
  }
  return weights;
}

Points SurfaceEnergy::RightHandSide(
  const std::vector<MatchedLine>& lines, const std::vector<FixedObstacle>& bones) const
{
  const Eigen::Index n = this->RestPoints.rows();
  Points targets(this->Rows.rows(), 3);
  for (Eigen::Index i = 0; i < n; ++i)
  {
    const Eigen::Vector3d p = this->RestPoints.row(i).transpose();
    const BlendedSegments near(p, lines, this->BlendWidth * this->Span);
    targets.row(i) = this->ShapeWeight * (near.rotation * this->Delta.row(i).transpose()).transpose();
    targets.row(n + this->SampleCount() + i) = this->FollowRowWeights[static_cast<size_t>(i)] * near.follow.transpose();
  }
  for (const Attachment& area : this->Attachments)
  {
    // The bone's rigid motion near the area, from its rest pose to this one.
    const RigidTransform carried = AttachmentMotion(area, bones);
    for (Eigen::Index i : area.points)
    {
      if (this->PointUsed[static_cast<size_t>(i)])
      {
        targets.row(n + this->SampleCount() + i) =
          this->AttachmentWeight * carried.Apply(Eigen::Vector3d(this->RestPoints.row(i).transpose())).transpose();
      }
    }
  }
  Points restSamples, currentSamples;
  SampleMatchedLines(lines, this->SamplesPerSegment, restSamples, currentSamples);
  for (Eigen::Index s = 0; s < this->SampleCount(); ++s)
  {
    const size_t k = static_cast<size_t>(s);
    targets.row(n + s) =
      OutsideBones(currentSamples.row(this->SampleIndex[k]).transpose(), this->SampleClearance[k], bones).transpose();
  }
  return this->Rows.transpose() * targets;
}

namespace
{
/// An iteration that moves a point by this fraction of its muscle's size has gone beyond the
/// linearisations' reach. One or two such moves happen and are undone by the next iteration
/// (a contact linearised at a bad start); a settle that keeps making them (contacts of two
/// moving surfaces feeding each other) has diverged and stops.
constexpr double kFarMove = 0.5;
constexpr int kFarMovesToStop = 3;
/// A move of more than this many times its muscle's size is no linearisation's overshoot but a
/// dual system that has lost its conditioning (measured: 1e5 mm at one iteration of the LHDL
/// hip's adduction -40 degrees in one step, whose next iteration found 3259 contacts and took
/// 6 s): the settle has diverged at once.
constexpr double kBlownUp = 2;

/// The points a block of the settle's update holds (SettleMuscles): 512 rows of x are 12 kB.
constexpr Eigen::Index kPushBlock = 512;

/// How far (a fraction of the muscle's size) the contact search looks beyond the offset for a
/// point that is outside an obstacle, so that it need not test that point again until it, or the
/// obstacle, has moved that far (ContactSearch's `clearance`).
constexpr double kClearanceReach = 0.03;
/// The rounding of a distance to an obstacle, a fraction of the muscle's size: a clearance less
/// this is still one (ContactSearch, ProvenOutsideBones).
constexpr double kClearanceRounding = 1e-9;
/// How many times an iteration's step is solved again with the watched contacts it would break
/// (SettleParameters::contactLookahead).
constexpr int kJoiningRounds = 10;
/// Two muscle-muscle contact rows whose cosine in the dual system's metric is below minus this
/// bound the same gap from opposite sides (ExcludeOpposedContacts): exactly, as where a point
/// inside and its partner outside name each other; nearly, where watched contacts held from
/// earlier iterations meet points inside. An iteration that blows up (a point moved by more than
/// kBlownUp of its muscle's size) is solved again leaving out the nearly opposed rows as well
/// and watching nothing: two spindles crossed at 45 degrees blew up at their ninth iteration
/// (a move of 3.85 times a spindle's size) and, solved again, settled apart.
constexpr double kExactlyOpposed = 1 - 1e-9;
constexpr double kNearlyOpposed = 0.9;

/// A step whose every point moves less than this fraction of its muscle's size, in the direction
/// of the last step, is a creep (SteadyStep).
constexpr double kCreepMove = 1e-5;
/// The slowest creep SteadyStep extends for: a step is made at most 1 / (1 - 0.999) = 1000
/// times longer.
constexpr double kSlowestCreep = 0.999;
/// The least ratio of a step to the last (projected on it) that counts as a creep, and how
/// closely its direction must keep the last's (cosine).
constexpr double kFastestCreep = 0.5;
constexpr double kCreepAlignment = 0.99;

/// A settle longer than this many iterations is no ordinary one: ShapeStep damps its cycles
/// from here on. The LHDL hip's motions settle every step in 5 to 24 iterations, so none of
/// their steps is damped. The phantom at 50 degrees in 16 steps has a step that swings without
/// end: damped from the 30th iteration it settles with 2 triangles of the gluteus maximus turned
/// over, where halved (SettleToPose), as it is with damping from the 40th to the 80th, it turns
/// none over.
constexpr int kOrdinaryIterations = 50;
/// A settle whose iterations have run out with its contacts those of the iteration before and
/// no point moving more than this fraction of its muscle's size is nearly settled and goes on
/// for as many iterations again: gait2392's crowded calf muscles (gastrocnemii and soleus) ended
/// settles of 100 iterations so, moving by 2e-7 to 1e-6 of their size an iteration and by 7 %
/// less at each, in steps at 90 and 120 degrees to the last. Split in halves instead, such a
/// settle took two to four more (decision record 0008).
constexpr double kNearlySettled = 1e-5;
/// How many iterations back a repeated contact set is looked for, and the share of its step a
/// repeating iteration takes (ShapeStep).
constexpr size_t kRecentContactSets = 4;
constexpr double kCycleStep = 0.5;

/// Changes the step from `meshes`' points to `next` (all muscles together) where the plain
/// iteration converges slowly, so that where the settle stops does not depend on how long it
/// took to get there. The linearised contacts leave their surfaces' curvature out, so the
/// iteration converges linearly by the factor lambda, this step's projection on the last:
/// - It swings (lambda < 0) where that curvature is strong against a muscle's stiffness (two
///   muscles in contact, one held by few action-line rows), to and fro with a growing or
///   shrinking swing.
/// - It creeps (lambda near 1, the step's direction kept) where a muscle slides along a curved
///   contact: at flexion 60 degrees in 8 steps the LHDL iliacus and psoas moved by 1e-7 of
///   their size each iteration with lambda = 0.999, round the tolerance, so that rounding noise
///   decided whether a step converged after 11 iterations, 53, or not in 100, and was then
///   halved to an answer 0.65 mm away; the point they crept towards was still about 1e-4 of
///   their size beyond where the tolerance stopped them.
/// Either way the step is scaled by 1 / (1 - lambda), the step that would land on the fixed
/// point if the factor held (Aitken's): a swing is shortened, and a creep (every point's move
/// below kCreepMove of its muscle's size, per `sizes`, lambda from kFastestCreep up to 1, its
/// direction within kCreepAlignment) extended, for lambda beyond kSlowestCreep as for it.
/// Steps that grow (lambda >= 1) lead to no fixed point and are taken as they are: the muscles
/// are leaving an equilibrium, and a step made 1000 times longer went where rounding said (LHDL
/// hip_adduction frame 13: the iliacus and psoas slid by steps growing 1.3 times an iteration,
/// the extended step moved them by 0.9 mm, and 1e-7 of input noise moved their answer by
/// 0.12 mm; taken as they are, by 0.0006 mm).
/// `lastSteps` is read and replaced by the step taken, and emptied after an extension (whose
/// next step is the correction, no measure of the factor). Without `extendCreeps` only swings
/// are shortened.
void SteadyStep(const std::vector<TriangleMesh>& meshes, std::vector<Points>& next, std::vector<Points>& lastSteps,
  const std::vector<double>& sizes, bool extendCreeps)
{
  const size_t count = meshes.size();
  std::vector<Points> steps(count);
  double along = 0, last = 0, now = 0;
  bool small = true;
  for (size_t m = 0; m < count; ++m)
  {
    steps[m] = next[m] - meshes[m].points;
    small = small && steps[m].cwiseAbs().maxCoeff() <= kCreepMove * sizes[m];
    now += steps[m].squaredNorm();
    if (lastSteps.size() == count)
    {
      along += (steps[m].array() * lastSteps[m].array()).sum();
      last += lastSteps[m].squaredNorm();
    }
  }
  const double lambda = last > 0 ? along / last : 0.0;
  const bool creeps = extendCreeps && small && lambda >= kFastestCreep && lambda < 1 &&
    along * along >= kCreepAlignment * kCreepAlignment * last * now;
  if (lambda < 0 || creeps)
  {
    const double factor = 1 / (1 - std::min(lambda, kSlowestCreep));
    for (size_t m = 0; m < count; ++m)
    {
      steps[m] *= factor;
      next[m] = meshes[m].points + steps[m];
    }
  }
  if (creeps)
  {
    lastSteps.clear();
    return;
  }
  lastSteps = std::move(steps);
}

/// One part of a constraint's combination: `coefficient` times point `point` of muscle
/// `muscle`, or, with `point` a sample's key (SurfaceEnergy::SampleKey), times that action-line
/// sample's row (the combination of points that gives the sample).
struct Term
{
  size_t muscle;
  Eigen::Index point;
  double coefficient;
  const Eigen::VectorXd* column = nullptr; // the energy's inverse at `point`, once known
  const SurfaceEnergy::Row* row = nullptr; // the sample's row when `point` is a sample's key
};

/// The term's point (or sample) in `points`, without its coefficient.
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

/// The term `b`'s point (or sample) in the inverse's column of term `a`: a . K^-1 b.
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

/// A contact linearised at the current points: normal . (sum of the terms'
/// points) >= target, with the normal the direction from the muscle's point
/// to the point of one triangle of the obstacle nearest to it (outwards). A
/// point is outside an obstacle by the offset when it is that far from every
/// triangle, so a contact is kept per triangle: a point in a valley of a bone
/// is held by both its sides at once. Against a bone the sum is the muscle's
/// point alone; against another muscle it is the muscle's point less the
/// triangle's point (its corners, barycentric), so that both give way.
struct Contact
{
  size_t muscle = 0;
  Eigen::Index point = 0;
  size_t obstacle = 0; // bones first, then muscles
  Eigen::Index triangle = 0;
  std::vector<Term> terms;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double target = 0;
  bool violated = false; // inside the obstacle or nearer than the offset now
  bool inside = false;   // inside the obstacle now
};

using PointKey = std::tuple<size_t, Eigen::Index, size_t>;          // muscle, point, obstacle
using HeldContacts = std::map<PointKey, std::vector<Eigen::Index>>; // their triangles

/// The contact of p (point i of muscle m, `inside` obstacle o or not, its
/// constraint `violated` or not) with `triangle` of the obstacle, linearised
/// at the current points.
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
  c.normal = Outwards(p, q, inside, tree, triangle);
  c.terms.push_back({ m, i, 1.0 });
  if (o < bones)
  {
    c.target = c.normal.dot(q) + offset;
  }
  else
  {
    const Eigen::Vector3d weights = Barycentric(mesh, triangle, q);
    for (int k = 0; k < 3; ++k)
    {
      c.terms.push_back({ o - bones, mesh.triangles(triangle, k), -weights(k) });
    }
    c.target = offset;
  }
  return c;
}

/// Where two muscles' surfaces cross, a point p of one can be inside the other while the point v
/// of the other nearest it is outside the first (near it, or held from the last iteration): the
/// two contacts then bound the same gap from opposite sides (p must pass v, v must stay ahead of
/// p), a linearisation with no solution. Its multipliers grow without bound and the active set
/// cycles (measured: LHDL adduction 40 degrees in one pass, on one of three perturbed inputs, a
/// move of 6e5 times a muscle's size). The penetration is what must be resolved: the contact of
/// the point outside is left out of this iteration (`active` off, `slack` infinite so that it
/// does not join). Two rows are opposed when their cosine in the dual system's metric is below
/// -`opposed`: kExactlyOpposed, or kNearlyOpposed for an iteration that blew up without it.
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

/// Every contact to consider at the points `meshes` hold: of each point inside an obstacle, or
/// outside it nearer than the offset, or `held` at the last iteration, one per triangle (the
/// triangle it went in through since `previous`, or its nearest, and those it was held by).
/// `wasInside` (per muscle, point * obstacles + obstacle) is read and updated to the points now.
/// `clearance` (the same layout; zeros at the first iteration) keeps, for a point found outside
/// an obstacle and farther than the offset, how much farther it is (as far as kClearanceReach
/// looks), less every move since of the point and of the obstacle (a bone does not move within a
/// settle, a muscle by its largest point's move): while that stays positive the point is still
/// outside and not near, which the full test would find too, so it is not tested again. The
/// contacts found are exactly those of testing every point.
/// The search runs in blocks of points (Run, any order, in parallel), so that a parallel loop can
/// hand them out beside other work; Finish gathers the contacts in the points' order.
class ContactSearch
{
public:
  ContactSearch(const std::vector<TriangleMesh>& meshes, const std::vector<const SurfaceEnergy*>& energies,
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

  int NumberOfBlocks() const { return static_cast<int>(this->Blocks.size()); }

  /// Tests the points of block `block` against every obstacle.
  void Run(int block)
  {
    const auto [m, first] = this->Blocks[static_cast<size_t>(block)];
    const Eigen::Index end = std::min(first + kSearchBlock, this->Meshes[m].points.rows());
    for (Eigen::Index i = first; i < end; ++i)
    {
      this->TestPoint(m, i);
    }
  }

  /// The contacts found, muscle by muscle and point by point; `wasInside` updated.
  /// `pending`: the watched contacts (near, not broken, not held), in the same order.
  std::vector<Contact> Finish(std::vector<Contact>& pending)
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

private:
  /// Points a block of the search holds.
  static constexpr Eigen::Index kSearchBlock = 256;

  size_t Obstacles() const { return this->Bones.size() + this->Meshes.size(); }

  const TriangleTree& Obstacle(size_t o) const
  {
    return o < this->Bones.size() ? *this->Bones[o].tree : *this->Trees[o - this->Bones.size()];
  }

  void TestPoint(size_t m, Eigen::Index i)
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

  /// A settle of a motion that carries its contacts from frame to frame (SettleMotion::carryContacts).
  bool CarriesContacts = false;
  const std::vector<TriangleMesh>& Meshes;
  const std::vector<const SurfaceEnergy*>& Energies;
  const std::vector<FixedObstacle>& Bones;
  const std::vector<std::unique_ptr<TriangleTree>>& Trees;
  const OverlapMasks* RestOverlap;
  const HeldContacts& Held;
  const std::vector<Points>& Previous;
  const SettleParameters& Parameters;
  std::vector<std::vector<char>>& WasInside;
  std::vector<std::vector<double>>& Clearance;
  std::vector<Eigen::VectorXd> Moved;
  std::vector<double> LargestMove;
  std::vector<std::vector<std::vector<Contact>>> Found;   ///< [muscle][point]
  std::vector<std::vector<std::vector<Contact>>> Pending; ///< [muscle][point]
  std::vector<std::vector<char>> InNow, WasHeld;          ///< [muscle][point * obstacles + obstacle]
  std::vector<std::pair<size_t, Eigen::Index>> Blocks;    ///< (muscle, first point)
};

/// Per muscle, for each point and bone (point * bones + bone), how much farther than the offset
/// the last contact search (its `clearance`, ContactSearch's layout, found at the points
/// `previous`) proves the point from the bone at the points `meshes` now hold: its clearance less
/// its move since and the rounding (positive: what the next search would skip). Bones do not
/// move within a settle.
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

bool KeptSurfaceEnergy::Holds(const TriangleMesh& muscle, const std::vector<MatchedLine>& lines,
  const SettleParameters& parameters, const std::vector<Attachment>& areas) const
{
  return this->energy && SameMesh(this->surface, muscle) && this->settle.SameEnergyAs(parameters) &&
    this->attachments == areas &&
    std::equal(this->restLines.begin(), this->restLines.end(), lines.begin(), lines.end(),
      [](const MatchedLine& a, const MatchedLine& b) {
        return a.rest.rows() == b.rest.rows() && a.rest == b.rest && a.knots == b.knots;
      });
}

void KeptSurfaceEnergy::Keep(std::shared_ptr<const SurfaceEnergy> built, const TriangleMesh& muscle,
  const std::vector<MatchedLine>& lines, const SettleParameters& parameters, const std::vector<Attachment>& areas)
{
  this->attachments = areas;
  this->energy = std::move(built);
  this->surface = muscle;
  this->restLines = lines;
  this->settle = parameters;
}

LineSamplesInside LineSamplesInBones(
  const std::vector<std::vector<MatchedLine>>& lines, const std::vector<FixedObstacle>& bones, int samplesPerSegment)
{
  LineSamplesInside inside(lines.size());
  for (size_t m = 0; m < lines.size(); ++m)
  {
    for (const MatchedLine& line : lines[m])
    {
      Points restSamples, samples;
      SampleMatchedLines({ line }, samplesPerSegment, restSamples, samples);
      std::vector<std::vector<char>> perBone;
      for (const FixedObstacle& bone : bones)
      {
        std::vector<char> in(static_cast<size_t>(samples.rows()), 0);
        for (Eigen::Index k = 0; k < samples.rows(); ++k)
        {
          const Eigen::Vector3d p = samples.row(k).transpose();
          in[static_cast<size_t>(k)] = bone.tree->InBounds(p) && bone.tree->Inside(p);
        }
        perBone.push_back(std::move(in));
      }
      inside[m].push_back(std::move(perBone));
    }
  }
  return inside;
}

std::vector<std::string> LinesThroughBones(const std::vector<std::string>& names,
  const std::vector<std::vector<MatchedLine>>& lines, const std::vector<FixedObstacle>& bones,
  const LineSamplesInside* atRest, int samplesPerSegment)
{
  const LineSamplesInside inside = LineSamplesInBones(lines, bones, samplesPerSegment);
  std::vector<std::string> warnings;
  for (size_t m = 0; m < lines.size(); ++m)
  {
    for (size_t b = 0; b < bones.size(); ++b)
    {
      bool crosses = false;
      for (size_t l = 0; l < inside[m].size() && !crosses; ++l)
      {
        const std::vector<char>& now = inside[m][l][b];
        const auto firstOut = std::find(now.begin(), now.end(), 0);
        const auto lastOut = std::find(now.rbegin(), now.rend(), 0).base(); // one past it
        for (auto s = firstOut; s < lastOut && !crosses; ++s)
        {
          crosses = *s && !(atRest && (*atRest)[m][l][b][static_cast<size_t>(s - now.begin())]);
        }
      }
      if (crosses)
      {
        warnings.push_back("an action line of muscle '" + names[m] + "' crosses bone '" + bones[b].name +
          "': solved on the muscle's surface, the line is let go inside the bone and the muscle lies against "
          "the bone, which can bend a thin muscle round it; check the muscle, give the line a via point, or "
          "solve on the hull (DeformationMesh Hull)");
      }
    }
  }
  return warnings;
}

SettleMotion StartMotion(const std::vector<TriangleMesh>& muscles, const std::vector<const SurfaceEnergy*>& energies,
  const std::vector<std::vector<MatchedLine>>& restLines, const std::vector<FixedObstacle>& restBones)
{
  SettleMotion motion;
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    motion.points.push_back(muscles[m].points);
    motion.restDepths.push_back(energies[m]->SampleDepthsInBones(restLines[m], restBones));
  }
  motion.free = FreeMinima(energies, restLines, restBones);
  auto reference = std::make_shared<std::vector<Points>>();
  for (const FixedObstacle& bone : restBones)
  {
    reference->push_back(bone.tree->Mesh().points);
  }
  motion.boneReference = std::move(reference);
  return motion;
}

std::vector<std::vector<char>> ProvenOutsideBones(const std::vector<std::vector<double>>& boneClearance)
{
  std::vector<std::vector<char>> outside(boneClearance.size());
  for (size_t m = 0; m < boneClearance.size(); ++m)
  {
    outside[m].resize(boneClearance[m].size());
    std::transform(boneClearance[m].begin(), boneClearance[m].end(), outside[m].begin(),
      [](double c) { return static_cast<char>(c > 0); });
  }
  return outside;
}

std::vector<RigidFit> PlaceBones(
  const std::shared_ptr<const std::vector<Points>>& reference, const std::vector<FixedObstacle>& bones)
{
  if (!reference || reference->size() != bones.size())
  {
    return {};
  }
  for (size_t b = 0; b < bones.size(); ++b)
  {
    if ((*reference)[b].rows() != bones[b].tree->Mesh().points.rows() || (*reference)[b].rows() == 0)
    {
      return {};
    }
  }
  std::vector<RigidFit> placements(bones.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (int b = 0; b < static_cast<int>(bones.size()); ++b)
  {
    placements[b] = FitRigidTransform((*reference)[b], bones[b].tree->Mesh().points);
  }
  return placements;
}

std::vector<std::vector<double>> BoneClearancesNow(
  const SettleMotion& motion, const std::vector<TriangleMesh>& muscles, const std::vector<RigidFit>& placements)
{
  const size_t count = muscles.size(), bones = placements.size(), obstacles = bones + count;
  if (bones == 0 || motion.bonePlacements.size() != bones || motion.boneClearance.size() != count ||
    motion.points.size() != count)
  {
    return {};
  }
  for (size_t m = 0; m < count; ++m)
  {
    if (motion.points[m].rows() != muscles[m].points.rows() ||
      motion.boneClearance[m].size() != static_cast<size_t>(muscles[m].points.rows()) * bones)
    {
      return {};
    }
  }
  std::vector<std::vector<double>> now(count);
  for (size_t m = 0; m < count; ++m)
  {
    const Points& then = motion.points[m];
    const Points& points = muscles[m].points;
    now[m].assign(static_cast<size_t>(points.rows()) * obstacles, 0.0);
    for (size_t b = 0; b < bones; ++b)
    {
      const RigidTransform fromThen = Inverse(motion.bonePlacements[b].transform);
      const RigidTransform fromNow = Inverse(placements[b].transform);
      const double residuals = motion.bonePlacements[b].maxResidual + placements[b].maxResidual;
      for (Eigen::Index i = 0; i < points.rows(); ++i)
      {
        const double clearance = motion.boneClearance[m][static_cast<size_t>(i) * bones + b];
        if (!(clearance > 0))
        {
          continue;
        }
        const Eigen::Vector3d here = points.row(i).transpose(), there = then.row(i).transpose();
        const double moved = (fromNow.Apply(here) - fromThen.Apply(there)).norm();
        now[m][static_cast<size_t>(i) * obstacles + b] = std::max(0.0, clearance - moved - residuals);
      }
    }
  }
  return now;
}

std::vector<Points> FreeMinima(const std::vector<const SurfaceEnergy*>& energies,
  const std::vector<std::vector<MatchedLine>>& lines, const std::vector<FixedObstacle>& bones)
{
  std::vector<Points> free(energies.size());
  const std::vector<int> order = CostliestFirst(energies);
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < static_cast<int>(energies.size()); ++k)
  {
    const int m = order[static_cast<size_t>(k)];
    free[m] = energies[m]->Solve(energies[m]->RightHandSide(lines[m], bones));
  }
  return free;
}

double LargestStartMove(
  const SettleMotion& motion, const std::vector<const SurfaceEnergy*>& energies, const std::vector<Points>& freeMinima)
{
  const size_t count = energies.size();
  if (motion.free.size() != count || freeMinima.size() != count)
  {
    return 0;
  }
  double largest = 0;
  for (size_t m = 0; m < count; ++m)
  {
    largest = std::max(largest, (freeMinima[m] - motion.free[m]).rowwise().norm().maxCoeff() / energies[m]->Size());
  }
  return largest;
}

int SettleParts(double startMove, const SettleParameters& parameters, bool carriesContacts)
{
  constexpr int kMostParts = 64;
  const double largest = carriesContacts && parameters.largestCarriedMove > 0
    ? std::min(parameters.largestStartMove, parameters.largestCarriedMove)
    : parameters.largestStartMove;
  if (!(largest > 0))
  {
    return 1;
  }
  return static_cast<int>(std::clamp(std::ceil(startMove / largest), 1.0, double(kMostParts)));
}

namespace
{
/// The samples let go in a pose (their rows' energy taken partly or wholly away), each as an
/// equality of the dual system per axis, a . x - y / share = target, whose multiplier y takes
/// that share of the row's pull back out.
struct LetGoRows
{
  std::vector<Contact> rows;
  std::vector<double> shares; ///< each row's share
};

LetGoRows LetGoRowsOf(const std::vector<const SurfaceEnergy*>& energies,
  const std::vector<std::vector<MatchedLine>>& lines, const std::vector<FixedObstacle>& bones,
  const SettleMotion* motion)
{
  const size_t count = energies.size();
  LetGoRows letGo;
  for (size_t m = 0; m < count; ++m)
  {
    const std::vector<double>* rest = motion && motion->restDepths.size() == count ? &motion->restDepths[m] : nullptr;
    for (const SurfaceEnergy::LetGo& sample : energies[m]->SamplesLetGo(lines[m], bones, rest))
    {
      for (int axis = 0; axis < 3; ++axis)
      {
        Contact row;
        row.muscle = m;
        row.normal = Eigen::Vector3d::Unit(axis);
        row.target = sample.target(axis);
        row.terms.push_back(
          { m, SurfaceEnergy::SampleKey(sample.sample), 1.0, nullptr, &energies[m]->SampleRow(sample.sample) });
        letGo.rows.push_back(std::move(row));
        letGo.shares.push_back(sample.share);
      }
    }
  }
  return letGo;
}

/// The volumes linearised at the current points: per muscle V(x), its gradient g, the
/// direction K^-1 g and the right-hand side of g . x_new = V - V(x) + g . x.
struct VolumeRows
{
  std::vector<double> now;
  std::vector<Points> gradients;
  std::vector<Points> along;
  std::vector<double> right;
};

/// One iteration's linearisation: per muscle the minimum without contact and volume (`free`)
/// and the volume's rows; the samples let go; the muscles, costliest solve first.
struct Linearised
{
  const std::vector<const SurfaceEnergy*>& energies;
  const std::vector<Points>& free;
  const VolumeRows& volumes;
  const LetGoRows& letGo;
  const std::vector<int>& costliestFirst;
};

/// The dual system S y = rhs over `contacts` (the first `nc` inequalities, then the let-go
/// equalities) and one volume row per muscle: S_jl = a_j . K^-1 a_l. Points each contact's terms
/// at the energy's inverse columns, prepared here.
Eigen::MatrixXd DualSystem(const Linearised& in, std::vector<Contact>& contacts, Eigen::Index nc, Eigen::VectorXd& rhs)
{
  const size_t count = in.energies.size();
  const Eigen::Index volumeStart = static_cast<Eigen::Index>(contacts.size());
  // The inverse's columns at every point a contact names.
  std::vector<std::vector<Eigen::Index>> needed(count);
  for (const Contact& c : contacts)
  {
    for (const Term& t : c.terms)
    {
      needed[t.muscle].push_back(t.point);
    }
  }
  const Eigen::Index size = volumeStart + static_cast<Eigen::Index>(count);
  rhs.resize(size);
  for (size_t m = 0; m < count; ++m)
  {
    rhs(volumeStart + static_cast<Eigen::Index>(m)) = in.volumes.right[m];
  }
  SurfaceEnergy::PrepareAll(in.energies, needed);
  for (Contact& c : contacts)
  {
    for (Term& t : c.terms)
    {
      t.column = &in.energies[t.muscle]->InverseColumn(t.point);
    }
  }
  Eigen::MatrixXd system = Eigen::MatrixXd::Zero(size, size);
  for (Eigen::Index j = 0; j < volumeStart; ++j)
  {
    const Contact& a = contacts[static_cast<size_t>(j)];
    double value = 0;
    for (const Term& t : a.terms)
    {
      value += t.coefficient * a.normal.dot(Where(t, in.free[t.muscle]));
      system(j, volumeStart + static_cast<Eigen::Index>(t.muscle)) +=
        t.coefficient * a.normal.dot(Where(t, in.volumes.along[t.muscle]));
    }
    rhs(j) = a.target - value;
    for (Eigen::Index l = 0; l <= j; ++l)
    {
      const Contact& b = contacts[static_cast<size_t>(l)];
      double sum = 0;
      for (const Term& s : a.terms)
      {
        for (const Term& t : b.terms)
        {
          sum += s.coefficient * t.coefficient * InverseBetween(s, t);
        }
      }
      system(j, l) = system(l, j) = sum * a.normal.dot(b.normal);
    }
  }
  for (Eigen::Index j = nc; j < volumeStart; ++j)
  {
    system(j, j) -= 1 / in.letGo.shares[static_cast<size_t>(j - nc)];
  }
  for (size_t m = 0; m < count; ++m)
  {
    const Eigen::Index v = volumeStart + static_cast<Eigen::Index>(m);
    system.row(v).head(volumeStart) = system.col(v).head(volumeStart).transpose();
    system(v, v) = (in.volumes.gradients[m].array() * in.volumes.along[m].array()).sum();
  }
  return system;
}

/// One active row's push on a muscle's points: its multiplier times its coefficient, along the
/// inverse's column at its point, in the row's direction.
struct Push
{
  double size;
  const Eigen::VectorXd* column;
  Eigen::Vector3d normal;
};

/// The new points x = free + mu K^-1 g + the pushes, over blocks of points (of every muscle, in
/// one parallel loop): a block's rows stay in the first-level cache while every push goes over
/// them, where a push at a time over all the points went to the second level. Each point takes
/// the pushes in the rows' order: the same sums as StepUnderContacts' pointAt.
std::vector<Points> ApplyPushes(
  const Linearised& in, const Eigen::VectorXd& volumeMultipliers, const std::vector<std::vector<Push>>& pushes)
{
  const size_t count = in.energies.size();
  std::vector<Points> next(count);
  std::vector<std::pair<size_t, Eigen::Index>> blocks; // (muscle, first point)
  for (const int muscle : in.costliestFirst)
  {
    const auto m = static_cast<size_t>(muscle);
    next[m].resize(in.free[m].rows(), 3);
    for (Eigen::Index first = 0; first < in.free[m].rows(); first += kPushBlock)
    {
      blocks.emplace_back(m, first);
    }
  }
#pragma omp parallel for schedule(dynamic, 1)
  for (int b = 0; b < static_cast<int>(blocks.size()); ++b)
  {
    const auto [m, first] = blocks[static_cast<size_t>(b)];
    Points& x = next[m];
    const Eigen::Index end = std::min(first + kPushBlock, x.rows());
    const double volume = volumeMultipliers(static_cast<Eigen::Index>(m));
    for (Eigen::Index i = first; i < end; ++i)
    {
      x.row(i) = in.free[m].row(i) + volume * in.volumes.along[m].row(i);
    }
    for (const Push& push : pushes[m])
    {
      for (Eigen::Index i = first; i < end; ++i)
      {
        x.row(i) += (push.size * (*push.column)(i)) * push.normal.transpose();
      }
    }
  }
  return next;
}

/// What one iteration's step gives: every muscle's new points, the contacts that held them
/// (their triangles) and how many of each muscle's points were held.
struct Step
{
  std::vector<Points> points;
  HeldContacts held;
  std::vector<std::int64_t> inContact;
};

/// The step of one iteration: the quadratic energy's minimum under the linearised contacts
/// `primary` (and the let-go rows and the volumes), by the active set started from the contacts
/// `held` at the last iteration. A watched contact (`pending`, near but not yet broken) joins
/// if the step would break it, and the step is solved again with it (kJoiningRounds at most):
/// the step is then that of the quadratic energy under every constraint within the lookahead,
/// which moves continuously with the points, where a point just beyond the offset would
/// otherwise go in unhindered and be pushed out at the next iteration (the path, and with
/// several equilibria the answer, jumping with rounding). A step that blows up (moves a point
/// by kBlownUp of its muscle's size) is solved again as found, with the nearly opposed rows left
/// out and nothing watched.
Step StepUnderContacts(const Linearised& in, std::vector<Contact> primary, std::vector<Contact> pending,
  const HeldContacts& held, const std::vector<TriangleMesh>& meshes, size_t bones, const SettleParameters& parameters)
{
  const size_t count = in.energies.size();
  // How far a point may break a contact that does not hold it before the contact joins: an
  // inactive one the active set (SolveActiveSet), a watched one the step.
  auto joiningSlack = [&](const Contact& c) {
    return 1e-3 * parameters.tolerance * in.energies[c.muscle]->Size();
  };
  const size_t found = primary.size(); // the contacts before any watched one joined
  bool strict = false;                 // solved again after blowing up (kNearlyOpposed)
  for (int rounds = 0;;)
  {
    std::vector<Contact> contacts = primary;
    const Eigen::Index nc = static_cast<Eigen::Index>(contacts.size());
    contacts.insert(contacts.end(), in.letGo.rows.begin(), in.letGo.rows.end());
    const Eigen::Index volumeStart = static_cast<Eigen::Index>(contacts.size());
    Eigen::VectorXd rhs;
    const Eigen::MatrixXd system = DualSystem(in, contacts, nc, rhs);

    // The active set: the multipliers of the active contacts and volumes, the inactive
    // contacts' points where they would go; a contact whose multiplier pulls lets go, one whose
    // point would be inside joins.
    std::vector<char> active(static_cast<size_t>(system.rows()), 1);
    for (Eigen::Index j = 0; j < nc; ++j)
    {
      const Contact& c = contacts[static_cast<size_t>(j)];
      const auto before = held.find({ c.muscle, c.point, c.obstacle });
      active[j] = c.violated ||
        (before != held.end() &&
          std::find(before->second.begin(), before->second.end(), c.triangle) != before->second.end());
    }
    std::vector<double> slack(static_cast<size_t>(nc));
    for (Eigen::Index j = 0; j < nc; ++j)
    {
      slack[j] = joiningSlack(contacts[static_cast<size_t>(j)]);
    }
    ExcludeOpposedContacts(contacts, bones, system, active, slack, strict ? kNearlyOpposed : kExactlyOpposed);
    const Eigen::VectorXd multipliers = SolveActiveSet(system, rhs, slack, active);
    const Eigen::VectorXd volumeMultipliers = multipliers.tail(static_cast<Eigen::Index>(count));

    Step step;
    step.inContact.assign(count, 0);
    std::vector<std::vector<Push>> pushes(count); // each muscle's, in the rows' order
    for (Eigen::Index j = 0; j < volumeStart; ++j)
    {
      if (!active[j])
      {
        continue;
      }
      const Contact& c = contacts[static_cast<size_t>(j)];
      if (j < nc)
      {
        step.held[{ c.muscle, c.point, c.obstacle }].push_back(c.triangle);
        ++step.inContact[c.muscle];
      }
      for (const Term& t : c.terms)
      {
        pushes[t.muscle].push_back({ multipliers(j) * t.coefficient, t.column, c.normal });
      }
    }
    // Where the step takes point i of muscle m: ApplyPushes at one point, the same sums.
    auto pointAt = [&](size_t m, Eigen::Index i) {
      Eigen::RowVector3d x =
        in.free[m].row(i) + volumeMultipliers(static_cast<Eigen::Index>(m)) * in.volumes.along[m].row(i);
      for (const Push& push : pushes[m])
      {
        x += (push.size * (*push.column)(i)) * push.normal.transpose();
      }
      return Eigen::Vector3d(x.transpose());
    };
    std::vector<Contact> stillPending;
    const size_t joinedBefore = primary.size();
    for (Contact& c : pending)
    {
      double value = 0;
      for (const Term& t : c.terms)
      {
        value += t.coefficient * c.normal.dot(pointAt(t.muscle, t.point));
      }
      (value - c.target < -joiningSlack(c) ? primary : stillPending).push_back(std::move(c));
    }
    pending = std::move(stillPending);
    if (primary.size() > joinedBefore && ++rounds < kJoiningRounds)
    {
      continue;
    }
    step.points = ApplyPushes(in, volumeMultipliers, pushes);
    bool blownUp = false;
    for (size_t m = 0; m < count && !strict; ++m)
    {
      blownUp =
        blownUp || (step.points[m] - meshes[m].points).cwiseAbs().maxCoeff() > kBlownUp * in.energies[m]->Size();
    }
    if (blownUp)
    {
      primary.resize(found);
      pending.clear();
      strict = true;
      continue;
    }
    return step;
  }
}

/// Records in `motion` where the settle ended (`muscles`, `free`, the bones' clearances and
/// placements) and, where it carries contacts, the contacts that held the muscles there; a
/// settle that `diverged` leaves no clearances, placements or contacts.
void RecordInMotion(SettleMotion& motion, const std::vector<TriangleMesh>& muscles, std::vector<Points> free,
  std::vector<std::vector<double>> boneClearance, const std::vector<RigidFit>& placements, const HeldContacts& held,
  bool diverged)
{
  motion.points.clear();
  for (const TriangleMesh& muscle : muscles)
  {
    motion.points.push_back(muscle.points);
  }
  motion.free = std::move(free);
  motion.boneClearance = std::move(boneClearance);
  motion.bonePlacements = diverged ? std::vector<RigidFit>() : placements;
  motion.held.clear();
  if (motion.carryContacts && !diverged) // a diverged settle's contacts hold nothing
  {
    for (const auto& [key, triangles] : held)
    {
      for (const Eigen::Index t : triangles)
      {
        motion.held.push_back({ static_cast<Eigen::Index>(std::get<0>(key)), std::get<1>(key),
          static_cast<Eigen::Index>(std::get<2>(key)), t });
      }
    }
  }
}

/// The step an iteration takes, from `meshes`' points to `next`, given its contacts `held` and
/// whether they are the last iteration's (`sameContacts`). With the same contacts, SteadyStep.
/// While they change, the plain step for kOrdinaryIterations; past those the contacts of crowded
/// muscles (generated ones, Rajagopal 2016's soleus and medial gastrocnemius) can cycle, a point
/// moving back and forth by millimetres, so the settle's swings are shortened as SteadyStep
/// shortens them (creeps are not extended: the contacts are still changing), and a step whose
/// contacts are a set held at one of the last kRecentContactSets iterations takes kCycleStep of
/// itself, so that the cycle's linearisations meet between its sets. `lastSteps` as SteadyStep's;
/// `recentHeld` the last sets, `held` added from kRecentContactSets iterations before
/// kOrdinaryIterations on.
void ShapeStep(const std::vector<TriangleMesh>& meshes, std::vector<Points>& next, const HeldContacts& held,
  bool sameContacts, int iteration, const std::vector<double>& sizes, std::vector<Points>& lastSteps,
  std::vector<HeldContacts>& recentHeld)
{
  if (sameContacts || iteration >= kOrdinaryIterations)
  {
    SteadyStep(meshes, next, lastSteps, sizes, sameContacts);
    if (!sameContacts && std::find(recentHeld.begin(), recentHeld.end(), held) != recentHeld.end())
    {
      for (size_t m = 0; m < meshes.size(); ++m) // SteadyStep without creeps keeps every step in lastSteps
      {
        next[m] = meshes[m].points + kCycleStep * (next[m] - meshes[m].points);
        lastSteps[m] = next[m] - meshes[m].points;
      }
    }
  }
  else
  {
    lastSteps.clear();
  }
  if (iteration + static_cast<int>(kRecentContactSets) < kOrdinaryIterations)
  {
    return; // not looked at before kOrdinaryIterations: an ordinary settle copies no contact set
  }
  recentHeld.push_back(held);
  if (recentHeld.size() > kRecentContactSets)
  {
    recentHeld.erase(recentHeld.begin());
  }
}

/// Where a settle is between iterations, on the muscles' welded surfaces.
struct SettleState
{
  std::vector<TriangleMesh> meshes; ///< the welded surfaces (the energies' triangles)
  std::vector<double> targets;      ///< the volume each must hold
  std::vector<std::unique_ptr<TriangleTree>> trees;
  HeldContacts held; ///< the contacts active at the last iteration (the last settle's at the first)
  /// ContactSearch's: which obstacles each point was inside at the last iteration, and how far
  /// it is proven outside each.
  std::vector<std::vector<char>> wasInside;
  std::vector<std::vector<double>> clearance;
  std::vector<Points> previous; ///< the points at the last iteration
};

/// The settle's start: with `motion`, where the last settle ended moved as the unconstrained
/// minimum moved (from its `free` to `free`; written to `muscles`' points), with its contacts
/// where it carries them and the clearances it proved, made good for the bones' `placements`.
SettleState StartSettle(std::vector<TriangleMesh>& muscles, const std::vector<const SurfaceEnergy*>& energies,
  const std::vector<double>& volumes, size_t bones, const std::vector<Points>& free, const SettleMotion* motion,
  const std::vector<RigidFit>& placements)
{
  const size_t count = muscles.size();
  const size_t obstacles = bones + count;
  if (motion && motion->points.size() == count)
  {
    for (size_t m = 0; m < count; ++m)
    {
      muscles[m].points = motion->points[m] + (free[m] - motion->free[m]);
      // The points the welded surface does not use go with it, so that the volume the welding
      // takes away below is that of this start (left where the last step put them, the rest
      // pose at the first, they took up to 3e-6 of the LHDL iliacus's volume in one pass).
      energies[m]->CarryToUnwelded(muscles[m].points);
    }
  }
  // Settled on the welded surfaces, written back at the end. The volume each must hold is the
  // muscle's less the difference the welding makes at the start (nothing for exact duplicates,
  // rounding for split ones).
  SettleState s;
  s.meshes.resize(count);
  s.targets.resize(count);
  for (size_t m = 0; m < count; ++m)
  {
    s.meshes[m] = { muscles[m].points, energies[m]->Surface() };
    s.targets[m] = volumes[m] - EnclosedVolume(muscles[m].points, muscles[m].triangles) +
      EnclosedVolume(s.meshes[m].points, s.meshes[m].triangles);
  }
  s.trees.resize(count);
  if (motion && motion->carryContacts)
  {
    for (const auto& [m, point, obstacle, triangle] : motion->held)
    {
      s.held[{ static_cast<size_t>(m), point, static_cast<size_t>(obstacle) }].push_back(triangle);
    }
  }
  // At the start every point is taken as inside every obstacle, so that a point inside at the
  // start goes out the nearest way. What the last settle proved of the points' distances from
  // the bones is carried here.
  std::vector<std::vector<double>> carried =
    motion ? BoneClearancesNow(*motion, s.meshes, placements) : std::vector<std::vector<double>>();
  s.wasInside.resize(count);
  s.clearance.resize(count);
  s.previous.resize(count);
  for (size_t m = 0; m < count; ++m)
  {
    s.wasInside[m].assign(static_cast<size_t>(s.meshes[m].points.rows()) * obstacles, 1);
    if (carried.size() == count)
    {
      s.clearance[m] = std::move(carried[m]);
    }
    else
    {
      s.clearance[m].assign(static_cast<size_t>(s.meshes[m].points.rows()) * obstacles, 0.0);
    }
    s.previous[m] = s.meshes[m].points;
  }
  return s;
}

/// One iteration's linearisation at the points `s` holds (their trees refitted there): the
/// contacts (every point inside an obstacle or nearer than the offset, and those held before;
/// returned, the watched ones in `pending`) and the volumes, independent of each other, in one
/// parallel loop: the gluteus maximus's solve takes one core while the other does the other
/// muscles' and the contact search (each in the same arithmetic as alone).
std::vector<Contact> LineariseAt(SettleState& s, const std::vector<const SurfaceEnergy*>& energies,
  const std::vector<FixedObstacle>& bones, const OverlapMasks* restOverlap, const SettleParameters& parameters,
  bool carriesContacts, const std::vector<Points>& free, const std::vector<int>& costliestFirst, VolumeRows& volumes,
  std::vector<Contact>& pending)
{
  const size_t count = s.meshes.size();
#pragma omp parallel for schedule(dynamic, 1)
  for (int m = 0; m < static_cast<int>(count); ++m)
  {
    if (s.trees[m])
    {
      s.trees[m]->Refit(s.meshes[m].points);
    }
    else
    {
      s.trees[m] = std::make_unique<TriangleTree>(s.meshes[m]);
    }
  }
  ContactSearch search(s.meshes, energies, bones, s.trees, restOverlap, s.held, s.previous, parameters, s.wasInside,
    s.clearance, carriesContacts);
  volumes.gradients.assign(count, Points());
  volumes.along.assign(count, Points());
  volumes.now.assign(count, 0.0);
  volumes.right.assign(count, 0.0);
  const int tasks = static_cast<int>(count) + search.NumberOfBlocks();
#pragma omp parallel for schedule(dynamic, 1)
  for (int task = 0; task < tasks; ++task)
  {
    if (task >= static_cast<int>(count))
    {
      search.Run(task - static_cast<int>(count));
      continue;
    }
    const size_t m = static_cast<size_t>(costliestFirst[static_cast<size_t>(task)]);
    const Points& x = s.meshes[m].points;
    volumes.now[m] = EnclosedVolume(x, s.meshes[m].triangles, &volumes.gradients[m]);
    volumes.along[m] = energies[m]->Solve(volumes.gradients[m]);
    volumes.right[m] = s.targets[m] - volumes.now[m] + (volumes.gradients[m].array() * x.array()).sum() -
      (volumes.gradients[m].array() * free[m].array()).sum();
  }
  return search.Finish(pending);
}
}

std::vector<SettleReport> SettleMuscles(std::vector<TriangleMesh>& muscles,
  const std::vector<const SurfaceEnergy*>& energies, const std::vector<std::vector<MatchedLine>>& lines,
  const std::vector<double>& volumes, const std::vector<FixedObstacle>& bones, const OverlapMasks* restOverlap,
  const SettleParameters& parameters, SettleMotion* motion, const std::function<void(double)>& progress,
  std::vector<Points> freeMinima)
{
  // Sequential quadratic programming: at each iteration the volume and the obstacles' surfaces
  // are linearised at the current points, and the quadratic energy is minimised exactly under
  // those linear constraints. With the energy's matrix K fixed, the minimum is
  //   x = K^-1 (b + sum_j lambda_j a_j + mu g),
  // and the multipliers solve a small system S (S_jl = a_j . K^-1 a_l, ActiveSet.h) on the active
  // contacts: a contact is active while its multiplier pushes (lambda > 0), and one not active
  // joins when its point would be inside (a primal-dual active set). S needs K^-1 only at the
  // points in contact: columns of the inverse, kept by the energy for the whole motion.
  const auto start = Clock::now();
  const size_t count = muscles.size();
  // The minimum without contact and volume.
  std::vector<Points> free = freeMinima.size() == count ? std::move(freeMinima) : FreeMinima(energies, lines, bones);
  const LetGoRows letGo = LetGoRowsOf(energies, lines, bones, motion);
  // The bones where they are now (to make good the clearances the last settle proved).
  const std::vector<RigidFit> placements = motion ? PlaceBones(motion->boneReference, bones) : std::vector<RigidFit>();
  SettleState s = StartSettle(muscles, energies, volumes, bones.size(), free, motion, placements);
  std::vector<SettleReport> reports(count);
  std::vector<Points> lastSteps;        // each muscle's last move, for SteadyStep
  std::vector<HeldContacts> recentHeld; // the last kRecentContactSets iterations' contacts
  std::vector<double> sizes(count);
  for (size_t m = 0; m < count; ++m)
  {
    sizes[m] = energies[m]->Size();
  }
  const std::vector<int> costliestFirst = CostliestFirst(energies);
  bool settled = false, diverging = false;
  int farMoves = 0;
  int iteration = 0;
  int lastIteration = parameters.maximumIterations;
  for (; iteration < lastIteration && !settled && !diverging; ++iteration)
  {
    VolumeRows volumeRows;
    std::vector<Contact> pending;
    std::vector<Contact> primary = LineariseAt(s, energies, bones, restOverlap, parameters,
      motion && motion->carryContacts, free, costliestFirst, volumeRows, pending);
    const Linearised linearised{ energies, free, volumeRows, letGo, costliestFirst };
    Step step =
      StepUnderContacts(linearised, std::move(primary), std::move(pending), s.held, s.meshes, bones.size(), parameters);
    std::vector<Points>& next = step.points;
    for (size_t m = 0; m < count; ++m)
    {
      if (!next[m].allFinite())
      {
        throw OfMuscle(ComputationError("the full-mesh deformation of a muscle diverged"), m);
      }
    }
    // Settled when the contacts are the last iteration's, no point moves more than the
    // tolerance and every volume is within 1e-9 of its target; diverging after kFarMovesToStop
    // far moves.
    settled = step.held == s.held;
    bool nearlySettled = settled; // the contacts held and every move within kNearlySettled
    ShapeStep(s.meshes, next, step.held, settled, iteration, sizes, lastSteps, recentHeld);
    for (size_t m = 0; m < count; ++m)
    {
      const double change = (next[m] - s.meshes[m].points).cwiseAbs().maxCoeff();
      farMoves += change > kFarMove * sizes[m] ? 1 : 0;
      farMoves += change > kBlownUp * sizes[m] ? kFarMovesToStop : 0;
      nearlySettled = nearlySettled && change <= kNearlySettled * sizes[m];
      if (change > parameters.tolerance * sizes[m] ||
        std::abs(volumeRows.now[m] - s.targets[m]) > 1e-9 * std::abs(s.targets[m]))
      {
        settled = false;
      }
      s.previous[m] = std::move(s.meshes[m].points);
      s.meshes[m].points = std::move(next[m]);
      reports[m].pointsInContact = step.inContact[m];
    }
    s.held = std::move(step.held);
    diverging = farMoves >= kFarMovesToStop;
    if (progress)
    {
      progress(std::min(1.0, static_cast<double>(iteration + 1) / std::max(1, parameters.maximumIterations)));
    }
    if (iteration + 1 == parameters.maximumIterations && nearlySettled) // nearly there: on to as many again
    {
      lastIteration = 2 * parameters.maximumIterations;
    }
  }
  // How far each point is proven outside each bone where the settle ends (for the static
  // resolution after it and for the next settle).
  std::vector<std::vector<double>> boneClearance = diverging
    ? std::vector<std::vector<double>>()
    : BoneClearancesAtEnd(s.meshes, s.previous, energies, bones.size(), s.clearance);
  // A settle that diverged leaves the muscles where they started rather than at an iterate that
  // means nothing; one that ran out of iterations keeps its last.
  for (size_t m = 0; m < count && !diverging; ++m)
  {
    energies[m]->CarryToUnwelded(s.meshes[m].points);
    muscles[m].points = std::move(s.meshes[m].points);
  }
  if (motion)
  {
    RecordInMotion(*motion, muscles, std::move(free), std::move(boneClearance), placements, s.held, diverging);
  }
  // The muscles are settled together: the time is shared.
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  for (SettleReport& report : reports)
  {
    report.iterations = iteration;
    report.converged = settled;
    report.seconds = seconds / static_cast<double>(std::max<size_t>(1, count));
  }
  return reports;
}
}
