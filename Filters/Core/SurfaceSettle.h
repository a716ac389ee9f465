// SPDX-License-Identifier: BSD-3-Clause
// The deformation's answer on the muscle itself (docs/DESIGN.md section 7):
// the energy of the Kellnhofer & Kohout deformation (rotated Laplacian
// coordinates, action-line rows, volume) with contact, posed on every point
// of the full mesh and converged there. The hull-based pass gives the
// starting guess; the answer is the energy's minimum, so it does not depend on
// the hull's size or on the order of its collapses. Experimental and off by
// default (InterpolationParameters::settleOnSurface): without contact it
// converges in a few iterations; with contact it does not yet (a patch in
// contact slides by small steps) and costs a factorisation per change of the
// contacts.
#pragma once

#include "MuscleDeformer.h"
#include "StaticIntersections.h"
#include "VolumeConstrainedSolver.h"

#include <vector>

namespace md
{
struct SettleParameters
{
  /// Contact rows: a point inside a bone (or another muscle) is pulled just
  /// outside by a row of this weight (a point's Laplacian row weighs about 1;
  /// see SurfaceEnergy).
  double contactWeight = 4;
  /// Of an overlap between two muscles, the share each side moves out.
  double muscleShare = 0.5;
  /// Rows pulling every point to where its nearest action-line segment's
  /// motion takes it, relative to the shape rows: they fix the near-null
  /// modes of the other rows (see DeformationParameters::followWeight).
  double followWeight = 0.01;
  int samplesPerSegment = 10;
  /// The shape rows are scaled so that the balance with the action-line rows
  /// is that of a hull of this many points (the hull-based pass's at its
  /// default size): the energy is then comparable with the paper's, and it
  /// depends on the muscle's own mesh only.
  double balancePoints = 250;
  int maximumIterations = 100;
  /// Converged when no point moves more than this fraction of the muscle's
  /// size in an iteration and the volume is within 1e-9 of its target.
  double tolerance = 1e-7;
};

/// The rest-pose parts of one muscle's full-mesh energy, built once and kept
/// for every step of a motion: the shape rows (the cotangent Laplacian of the
/// rest surface and its Laplacian coordinates), the action-line rows (each
/// action-line sample inside the rest muscle written as a fixed combination of
/// the surface points where chords through it along the three axes meet the
/// surface: a sparse row that reproduces the sample exactly in the rest pose),
/// the follow rows, and their normal matrix.
class SurfaceEnergy
{
public:
  /// `restLines`: the muscle's action lines in the rest pose (matched, the
  /// same points as every pose's lines). Throws InputError when no sample of
  /// the lines lies inside the muscle.
  SurfaceEnergy(const TriangleMesh& rest, const std::vector<Points>& restLines, const SettleParameters& parameters);

  /// Rows^T targets for the pose that `lines` (rest -> current) describe:
  /// the right-hand side of the normal equations without contact.
  Points RightHandSide(const std::vector<MatchedLine>& lines) const;
  /// Rows^T Rows.
  const SparseMatrix& NormalMatrix() const { return this->Normal; }

  const std::vector<char>& Used() const { return this->PointUsed; }
  Eigen::Index SampleCount() const { return static_cast<Eigen::Index>(this->SampleIndex.size()); }
  double Size() const { return this->Span; }

private:
  Points RestPoints;
  double Span = 0;
  int SamplesPerSegment = 10;
  std::vector<char> PointUsed;
  Points Delta; // rest-pose Laplacian coordinates (rows of unused points zero)
  double ShapeWeight = 1;
  double FollowWeight = 0;
  std::vector<Eigen::Index> SampleIndex; // samples (SampleMatchedLines order) inside the rest muscle
  SparseMatrix Rows;                     // shape, action-line and follow rows stacked
  SparseMatrix Normal;                   // Rows^T Rows
};

struct SettleReport
{
  int iterations = 0;
  bool converged = false;
  std::int64_t pointsInContact = 0; ///< held by contact rows at the minimum
  double seconds = 0;
};

/// Settles every muscle of `meshes` (their points in, the settled points
/// out) to the minimum of its full-mesh energy for the pose `lines[m]`
/// describes, holding `volumes[m]`, with contact rows against the bones
/// (`bones`, in that pose) and against each other (each moving `muscleShare`
/// of an overlap). Overlap the rest pose has (`restOverlap`, OverlapMasks
/// order) is left alone. The starting points decide only which side of an
/// obstacle a point is on. `energies[m]` belong to the muscles' rest poses.
std::vector<SettleReport> SettleMuscles(std::vector<TriangleMesh>& meshes,
  const std::vector<const SurfaceEnergy*>& energies, const std::vector<std::vector<MatchedLine>>& lines,
  const std::vector<double>& volumes, const std::vector<FixedObstacle>& bones, const OverlapMasks* restOverlap,
  const SettleParameters& parameters);
}
