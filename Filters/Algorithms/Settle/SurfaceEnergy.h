// SPDX-License-Identifier: BSD-3-Clause
// The energy the settle minimises on a muscle's own surface (docs/DESIGN.md section 7): the
// Kellnhofer & Kohout deformation's rows (rotated Laplacian coordinates, action-line rows) posed
// on every point of the full mesh, with the follow rows and the attachment areas' rows; its normal
// matrix factorised once per muscle for a whole motion, and the inverse's columns the contacts
// need, kept.
#pragma once

#include "Common/Attachment.h"
#include "Deformation/MuscleDeformer.h"
#include "Deformation/VolumeConstrainedSolver.h"
#include "Intersections/StaticIntersections.h"
#include "Settle/SettleParameters.h"

#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace md
{
/// The rest-pose parts of one muscle's full-mesh energy, built once and kept
/// for every step of a motion: the shape rows (the cotangent Laplacian of the
/// rest surface and its Laplacian coordinates), the action-line rows (each
/// action-line sample inside the rest muscle written as a fixed combination of
/// the surface points where chords through it along the three axes meet the
/// surface: a sparse row that reproduces the sample exactly in the rest pose),
/// the follow rows (for the points of an attachment area: the rows holding them where their bone
/// carries them), their normal matrix and its factorisation. Not safe to
/// share between threads (its cache of the inverse's columns).
class SurfaceEnergy
{
public:
  /// `restLines`: the muscle's action lines in the rest pose as a motion that goes nowhere
  /// (StillLines: the same points and own points as every pose's lines). Throws InputError
  /// when no sample of the lines lies inside the muscle. `attachments`: the areas that move
  /// with their bones.
  SurfaceEnergy(const TriangleMesh& rest, const std::vector<MatchedLine>& restLines, const SettleParameters& parameters,
    const std::vector<Attachment>& attachments = {});

  /// Rows^T targets for the pose that `lines` (rest -> current) describe:
  /// the right-hand side of the normal equations without contact. Where a
  /// line runs through one of `bones` (in that pose), or so near it that the
  /// muscle around it could not fit, its samples pull the muscle to the
  /// nearest place outside the bone where it fits (each sample as far out as
  /// it lies deep inside the rest muscle), not into the bone: the contact
  /// would otherwise have to fight the lines, and the muscle wraps round the
  /// bone's end instead of lying against it. An attachment area's points are pulled to where its
  /// bone (`bones[boneIndex]`, its rigid motion fitted at the area's anchors) carries them.
  Points RightHandSide(const std::vector<MatchedLine>& lines, const std::vector<FixedObstacle>& bones = {}) const;
  /// One action-line sample's row as a combination of surface points (point, weight).
  using Row = std::vector<std::pair<std::int64_t, double>>;
  /// A sample whose row is let go, in part, in one pose: the energy of its row is taken
  /// `share` times away (share in (0, 1]; 1: the sample pulls nothing), `target` its target.
  struct LetGo
  {
    Eigen::Index sample = 0;
    double share = 0;
    Eigen::Vector3d target = Eigen::Vector3d::Zero();
  };
  /// Every sample of `lines` (one pose) inside one of `bones`, deeper than it was at rest
  /// (`restDepths`, SampleDepthsInBones of the rest pose; none: as if outside every bone at
  /// rest): the line there says nothing of where the muscle is, so the sample pulls the less the
  /// deeper it is, and nothing once it is as deep in the bone as it was in the rest muscle. Its
  /// target is RightHandSide's (beside the bone). A line that crosses a bone then carries the
  /// muscle by its parts outside, and the muscle lies against the bone on the side its surface
  /// is on as a whole, instead of being pulled to both sides sample by sample (docs/DESIGN.md
  /// section 7).
  std::vector<LetGo> SamplesLetGo(const std::vector<MatchedLine>& lines, const std::vector<FixedObstacle>& bones,
    const std::vector<double>* restDepths) const;
  /// Each sample's depth in the one of `bones` it is deepest in (negative: how far inside; 0 outside) in the
  /// pose `lines` describes.
  std::vector<double> SampleDepthsInBones(
    const std::vector<MatchedLine>& lines, const std::vector<FixedObstacle>& bones) const;
  const Row& SampleRow(Eigen::Index sample) const { return this->SampleRows[static_cast<size_t>(sample)]; }
  /// Rows^T Rows.
  const SparseMatrix& NormalMatrix() const { return this->Normal; }

  /// The normal matrix's inverse applied to every column of `rhs`.
  Points Solve(const Points& rhs) const;
  /// Column `key` of the normal matrix's inverse (how every point moves
  /// when a unit force acts on point `key`), or with `key` a sample's key
  /// (SampleKey) the inverse applied to that sample's row; computed once and
  /// kept. `Prepare` computes the missing ones of `keys` in parallel.
  void Prepare(const std::vector<Eigen::Index>& keys) const;
  /// Prepare of every energy with its keys, in one parallel loop over all of them.
  static void PrepareAll(
    const std::vector<const SurfaceEnergy*>& energies, const std::vector<std::vector<Eigen::Index>>& keys);
  const Eigen::VectorXd& InverseColumn(Eigen::Index key) const;
  /// The key of action-line sample `sample`'s row among the inverse's columns.
  static Eigen::Index SampleKey(Eigen::Index sample) { return -1 - sample; }

  /// The rest surface's triangles with its duplicate points welded (WeldedTriangles): the
  /// energy is posed on them, so that a scan's exact and split duplicates give the same energy.
  const Triangles& Surface() const { return this->Welded; }
  /// Writes every point of the muscle that the welded surface does not use but its own
  /// triangles do into `settled` (the welded surface's points settled): a welded twin goes where
  /// the point it was welded to goes, and a point that only dropped (degenerate) triangles used
  /// goes to the affine combination of those triangles' welded points that gives it in the rest
  /// pose (plus what remains of the rest offset). Placed from the rest pose, not moved along
  /// from the step's start: the static resolution and the volume restore move a twin and its
  /// point apart a little, and carried from step to step that gap grew until a twin lay inside a
  /// bone its point was held out of.
  void CarryToUnwelded(Points& settled) const;

  const std::vector<char>& Used() const { return this->PointUsed; }
  Eigen::Index SampleCount() const { return static_cast<Eigen::Index>(this->SampleIndex.size()); }
  double Size() const { return this->Span; }
  /// The points of the parts of the surface (connected pieces) that no action-line row
  /// touches: a piece a scan left apart from the rest, with nothing but the follow rows to
  /// place it (it moves with its nearest action-line segment).
  std::int64_t PointsNoLineDrives() const { return this->Undriven; }
  /// The entries of the energy's factor: what a solve with it costs.
  Eigen::Index FactorEntries() const { return this->Factor.matrixL().nestedExpression().nonZeros(); }
  /// The points the welded surface uses.
  std::int64_t PointsUsed() const { return std::count(this->PointUsed.begin(), this->PointUsed.end(), 1); }
  /// What to say of muscle `muscle` when a part of it no line drives (PartApartWarning); empty
  /// when every part is driven.
  std::string UndrivenWarning(const std::string& muscle) const
  {
    return this->Undriven > 0 ? PartApartWarning(muscle, this->Undriven, this->PointsUsed(), "its surface") : "";
  }

private:
  static constexpr int kBlock = 8; ///< columns solved in one pass over the factor
  /// The keys of `keys` whose columns are not kept yet, sorted, each once.
  std::vector<Eigen::Index> Missing(const std::vector<Eigen::Index>& keys) const;
  /// Columns `keys[0..width)` (width <= kBlock) of the inverse into `solved`.
  void SolveColumns(const Eigen::Index* keys, size_t width, Eigen::VectorXd* solved) const;
  void FindLeaders(const TriangleMesh& rest, const std::vector<std::int64_t>& representative);
  /// Each point's follow row's weight: an attachment area's points are held harder.
  std::vector<double> FollowWeights() const;

  Points RestPoints;
  Triangles Welded;
  /// A point of the muscle that the welded surface does not use, and where it goes: the
  /// combination of welded points `leaders` with `weights` (summing to 1), plus `offset`.
  struct Follower
  {
    Eigen::Index point = 0;
    std::vector<Eigen::Index> leaders;
    std::vector<double> weights;
    Eigen::RowVector3d offset = Eigen::RowVector3d::Zero();
  };
  std::vector<Follower> Leaders;
  double Span = 0;
  int SamplesPerSegment = 10;
  std::vector<char> PointUsed;
  Points Delta; // rest-pose Laplacian coordinates (rows of unused points zero)
  double ShapeWeight = 1;
  double FollowWeight = 0;
  std::vector<Attachment> Attachments;
  double AttachmentWeight = 0;           ///< the rows of the attachment areas' points
  std::vector<double> FollowRowWeights;  ///< each point's follow row's weight (FollowWeights)
  double BlendWidth = 0;                 ///< SettleParameters::blendWidth
  std::vector<Eigen::Index> SampleIndex; // samples (SampleMatchedLines order) inside the rest muscle
  std::vector<double> SampleClearance;   // their distances from the rest surface
  std::vector<Row> SampleRows;           // their rows (ChordRow)
  std::int64_t Undriven = 0;             // points of pieces no row touches
  SparseMatrix Rows;                     // shape, action-line and follow rows stacked
  SparseMatrix Normal;                   // Rows^T Rows
  Eigen::SimplicialLDLT<SparseMatrix> Factor;
  mutable std::unordered_map<Eigen::Index, Eigen::VectorXd> Columns;
};

/// A muscle's SurfaceEnergy kept between runs with what it was made from: it depends on the
/// rest-pose surface, the matched action lines at rest and the energy's own settings only, so it
/// holds (with the inverse's columns found so far) while those are the same.
struct KeptSurfaceEnergy
{
  std::shared_ptr<const SurfaceEnergy> energy;
  TriangleMesh surface;
  std::vector<MatchedLine> restLines;
  SettleParameters settle;
  std::vector<Attachment> attachments;

  bool Holds(const TriangleMesh& muscle, const std::vector<MatchedLine>& lines, const SettleParameters& parameters,
    const std::vector<Attachment>& areas = {}) const;
  void Keep(std::shared_ptr<const SurfaceEnergy> built, const TriangleMesh& muscle,
    const std::vector<MatchedLine>& lines, const SettleParameters& parameters,
    const std::vector<Attachment>& areas = {});
};

/// [muscle][line][bone][sample]: whether each sample of the current pose of a muscle's matched
/// lines (SampleMatchedLines') lies inside the bone.
using LineSamplesInside = std::vector<std::vector<std::vector<std::vector<char>>>>;
/// LineSamplesInside of `lines[m]` (every muscle's matched lines) with `bones` in that pose.
LineSamplesInside LineSamplesInBones(
  const std::vector<std::vector<MatchedLine>>& lines, const std::vector<FixedObstacle>& bones, int samplesPerSegment);

/// What to say of every muscle (`names[m]`) one of whose action lines (`lines[m]`, their current
/// pose the bones') crosses a bone it did not cross at rest (`atRest`, LineSamplesInBones' of the
/// rest pose; null: the bones' rest pose is not known, and no line crossed one): goes into it and
/// out again, not only ends in it, as a line does at its attachment. Solved on the surface, a
/// line's pull is moved beside the bone on the side nearest to each sample, so a line that
/// crosses a bone pulls the muscle round it (docs/DESIGN.md section 7).
std::vector<std::string> LinesThroughBones(const std::vector<std::string>& names,
  const std::vector<std::vector<MatchedLine>>& lines, const std::vector<FixedObstacle>& bones,
  const LineSamplesInside* atRest, int samplesPerSegment);

/// The rest pose's lines as a motion that goes nowhere (rest -> rest), with their own points
/// `knots[l]` (none given: every point is its own).
std::vector<MatchedLine> StillLines(const std::vector<Points>& restLines, const std::vector<Knots>& knots = {});
/// The rest poses of matched lines, with their own points, as a motion that goes nowhere.
std::vector<MatchedLine> StillLines(const std::vector<MatchedLine>& lines);

/// The muscles' indices (of `energies`), the one whose factor costs most to solve with first: a
/// parallel loop over the muscles that hands them out in this order (schedule dynamic) starts the
/// longest solve at once instead of leaving it to the end while the other core idles (the LHDL
/// gluteus maximus's factor has as many entries as the other three muscles' together).
std::vector<int> CostliestFirst(const std::vector<const SurfaceEnergy*>& energies);
}
