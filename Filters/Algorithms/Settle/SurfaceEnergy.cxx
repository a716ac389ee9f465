// SPDX-License-Identifier: BSD-3-Clause
#include "Settle/SurfaceEnergy.h"

#include "Deformation/NearestSegment.h"
#include "Deformation/VolumeConstrainedSolver.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/RigidMotion.h"
#include "Geometry/SurfaceRepair.h"
#include "Geometry/TriangleTree.h"

#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>

namespace md
{
namespace
{
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
      const Eigen::Vector3d weights = BarycentricCoordinates(mesh, hit.triangle, hit.point);
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

std::vector<int> CostliestFirst(const std::vector<const SurfaceEnergy*>& energies)
{
  std::vector<int> order(energies.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
    [&](int a, int b) { return energies[a]->FactorEntries() > energies[b]->FactorEntries(); });
  return order;
}

namespace
{
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
    p = near.point + clearance * OutwardNormal(p, near.point, inside, tree, near.triangle);
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
}
