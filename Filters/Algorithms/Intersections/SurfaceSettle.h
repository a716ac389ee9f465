// SPDX-License-Identifier: BSD-3-Clause
// The deformation's answer on the muscle itself (docs/DESIGN.md section 7):
// the energy of the Kellnhofer & Kohout deformation (rotated Laplacian
// coordinates, action-line rows, volume) with contact, posed on every point
// of the full mesh and converged there. Through a motion each step's settle
// starts from the last step's answer (SettleMotion), not from the hull-based
// pass, so the answer does not depend on the hull's size or on the order of
// its collapses. Contact is a constraint, not a penalty: a point may not go
// inside a bone or another muscle, each linearised as a half-space at its
// nearest surface point, and the constrained minimum is found by an active set
// on the constraints' multipliers with the energy's matrix factorised once per
// muscle (for a whole motion). The interpolation method's default
// (InterpolationParameters::settleOnSurface).
#pragma once

#include "Common/Attachment.h"
#include "Deformation/MuscleDeformer.h"
#include "Deformation/VolumeConstrainedSolver.h"
#include "Geometry/RigidMotion.h"
#include "Intersections/StaticIntersections.h"

#include <Eigen/SparseCholesky>

#include <algorithm>
#include <array>
#include <functional>
#include <memory>
#include <string>

#include <unordered_map>
#include <vector>

namespace md
{
struct SettleParameters
{
  /// A point in contact is held this fraction of its muscle's size outside
  /// the obstacle, so that the surfaces do not touch.
  double contactOffset = 1e-3;
  /// A point nearer an obstacle than the offset plus this fraction of its muscle's size, its
  /// contact not yet broken, is watched: it joins an iteration's step if that step would break
  /// it (the step solved again). Without it a point just beyond the offset went in unhindered
  /// and was pushed out at the next iteration, a different path from a point just within, and
  /// where the muscles have several equilibria rounding chose between them (LHDL adduction
  /// -40 degrees, N = 4, duplicates split by 1e-7: the gluteus medius 2.19 mm away on one seed
  /// of eight; with 0.0005 to 0.004, within 0.0003 mm on all eight). 0 watches nothing, as
  /// the one pass from the rest pose does (SettleInOnePass).
  double contactLookahead = 1e-3;
  /// Rows pulling every point to where the motion of the action-line segments
  /// near it takes it (BlendedSegments), relative to the shape rows: they fix
  /// the near-null modes of the other rows (see
  /// DeformationParameters::followWeight) and hold a muscle pressed between
  /// obstacles along the contact, where the other rows hold it only weakly
  /// (docs/DESIGN.md section 7: at 0.01, 1e-7 of input noise moved the LHDL
  /// gluteus medius by up to 0.019 mm and more triangles turned over).
  double followWeight = 0.1;
  /// Each point is turned and carried by the action-line segments whose distance from it exceeds
  /// the nearest one's by less than this fraction of the muscle's size, blended
  /// (BlendedSegments), so that no point's target jumps where two segments are equally near.
  double blendWidth = 0.05;
  int samplesPerSegment = 10;
  /// The rows that hold an attachment area's points where its bone carries them (Attachment),
  /// relative to the shape rows' weight. At 10 the LHDL landmarks slip by at most 0.08 mm
  /// through hip_flexion (0.81 mm through hip_adduction, where the psoas's insertion presses on
  /// the iliacus's) and the rest of the muscle follows smoothly (the shape rows spread the area's
  /// motion; there is no kink at its rim). Stiffer rows held the areas no better and made the
  /// settles slower to converge: at 30, 1e-7 of input noise moved hip_flexion's frame 1 by
  /// 0.035 mm on two seeds of six, at 100 its frame 30 by 0.46 mm (at 10, at most 0.0004 mm).
  double attachmentWeight = 10;
  /// The shape rows' cotangent weights are clamped to [0, largestCotangent] (CotangentLaplacian):
  /// a scan's slivers and obtuse triangles otherwise let points cross their neighbours. At 3
  /// (angles under 18.4 degrees count as 18.4) the LHDL hip's four poses and the phantom to 50
  /// degrees turn no triangle over (before: 1, 1, 4 and 1; up to 27), every step converges, and
  /// 1e-7 of input noise moves them by at most 0.0004 mm (before: 0.0011).
  double largestCotangent = 3;
  /// The shape rows are scaled so that the balance with the action-line rows
  /// is that of a hull of this many points (the hull-based pass's at its
  /// default size): the energy is then comparable with the paper's, and it
  /// depends on the muscle's own mesh only.
  double balancePoints = 250;
  /// A step of a motion whose unconstrained minimum moves by more than this fraction of a
  /// muscle's size is settled in as many equal parts as keep each part's move within it
  /// (SettleParts). A settle starts from the last answer moved as that minimum moved; from
  /// farther the linearised contacts lose their way: LHDL adduction -40 degrees in one step (a
  /// move of 0.28) diverged or swung without end on three seeds of four, and flexion 60 degrees
  /// in three parts (0.14 each) settled the gluteus maximus 0.9 mm apart on one seed of three.
  /// At an eighth, each step of N = 4 on the LHDL hip (at most 0.11) is one part. Measured on
  /// the minimum, not on whether a settle converged, so that the count changes with the input
  /// only where the move crosses a multiple of this, not under rounding noise.
  double largestStartMove = 0.125;
  /// A step of a motion that carries its contacts (SettleMotion::carryContacts) is settled in as
  /// many equal parts as keep each part's unconstrained minimum within this fraction of a
  /// muscle's size (SettleParts), each part starting with the contacts the last one ended with:
  /// the muscles go on from the equilibrium they are in, even where they jump (an OpenSim path
  /// point comes or goes, and its line with it). The LHDL motions' frames move 0.017 (0.039 and
  /// 0.10 where a path point comes or goes), the phantom's sweep 0.03-0.05 (0.08 and 0.16 at two
  /// frames). Before, a jump started with no contacts: the LHDL iliacus at hip_flexion frame 33
  /// (0.10) swung between contacts with the iliac bone for 25 iterations, and where it came to rest
  /// moved by 0.17 mm under 1e-7 of input noise; in two parts that carry their contacts, by
  /// 0.0004 mm. (Carried in one part, it swung for 30 iterations or more, and whether it had
  /// converged by then, which rounding decided, chose between two answers 1.1 mm apart.)
  double largestCarriedMove = 0.0625;
  /// Linearisations of the volume and of the obstacles' surfaces. The LHDL hip's slowest step
  /// (flexion 60 degrees, N = 8, step 5) takes about 75 on the exact input and fewer on
  /// perturbed ones: at 50 the exact one was halved (InterpolatedDeformation) and the others
  /// not, and that step's answers differed by 0.65 mm. A settle that is nearly there when they
  /// run out (its contacts held, every move within 1e-5 of its muscle's size) goes on for as many
  /// again.
  int maximumIterations = 100;
  /// Converged when no point moves more than this fraction of the muscle's
  /// size in an iteration, the contacts are those of the iteration before,
  /// and the volume is within 1e-9 of its target.
  double tolerance = 1e-7;

  /// True when `other` gives the same SurfaceEnergy (the settle's own settings aside).
  bool SameEnergyAs(const SettleParameters& other) const
  {
    return this->followWeight == other.followWeight && this->blendWidth == other.blendWidth &&
      this->samplesPerSegment == other.samplesPerSegment && this->balancePoints == other.balancePoints &&
      this->largestCotangent == other.largestCotangent && this->attachmentWeight == other.attachmentWeight;
  }
};

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

struct SettleReport
{
  int iterations = 0;
  bool converged = false;
  std::int64_t pointsInContact = 0; ///< held by a contact at the minimum
  double seconds = 0;
};

/// A motion's settles, from step to step (SettleMuscles' `motion`): where the last settle
/// ended. The next step's settle starts from those points moved by the change of the
/// unconstrained minimum between the two poses: a start that depends continuously on the input
/// and not at all on the hull, so that the minimum found does too (docs/DESIGN.md section 7).
struct SettleMotion
{
  std::vector<Points> points; ///< every muscle's points where the last settle ended
  std::vector<Points> free;   ///< the minimum of that pose without contact and volume
  /// Per muscle, its action-line samples' depths in the bones at rest
  /// (SurfaceEnergy::SampleDepthsInBones): a sample is let go only deeper than that.
  std::vector<std::vector<double>> restDepths;
  /// Whether each settle starts with the contacts that held the muscles where the last one ended
  /// (`held`) active, rather than with none: a motion's frames are small pose changes, whose
  /// contacts persist, so the active set is found in fewer iterations, and the contacts are
  /// carried along the motion rather than found anew at every frame (MotionDeformation).
  bool carryContacts = false;
  /// The contacts that held the muscles where the last settle ended (with carryContacts), each
  /// as (muscle, point, obstacle, triangle), the obstacles the bones first and then the muscles.
  std::vector<std::array<Eigen::Index, 4>> held;
  /// The bones' points in the rest pose (StartMotion's `restBones`), shared by every step's
  /// SettleMotion: what `bonePlacements` place.
  std::shared_ptr<const std::vector<Points>> boneReference;
  /// Per bone, the rigid placement of its rest points that fits it where the last settle ended
  /// (with the largest distance of its points from the placed rest points).
  std::vector<RigidFit> bonePlacements;
  /// Per muscle, for each point and bone (point * bones + bone): how much farther than the
  /// contact offset the last settle's contact search proves the point from the bone where it
  /// ended (its clearance less the last move; 0 where it proves nothing). The static resolution
  /// after it need not test the points it proves (ProvenOutsideBones), and the next settle's first
  /// contact search starts from it,
  /// less how far the point has moved since relative to the bone's placement (BoneClearancesNow):
  /// a point near a bone mostly moves with it, so most points need not be searched again at the
  /// first iteration. Empty after a settle that diverged.
  std::vector<std::vector<double>> boneClearance;
};

/// Per muscle, for each point and bone (point * bones + bone): 1 where `boneClearance`
/// (SettleMotion's) proves the point outside the bone and farther than the contact offset, what
/// the static resolution after that settle need not test (ResolveStaticIntersections'
/// `outsideFixed`).
std::vector<std::vector<char>> ProvenOutsideBones(const std::vector<std::vector<double>>& boneClearance);

/// Each bone's rest points (`reference`, SettleMotion::boneReference) placed rigidly where
/// `bones`' trees are now (FitRigidTransform); empty without a reference.
std::vector<RigidFit> PlaceBones(
  const std::shared_ptr<const std::vector<Points>>& reference, const std::vector<FixedObstacle>& bones);

/// The clearances `motion` carries (SettleMotion::boneClearance) made good for the points
/// `muscles` hold and the bones where `placements` (PlaceBones') put them now: each less how far its
/// point has moved relative to the bone, in the bone's rest frame as the two placements put
/// it, and less both placements' largest residuals (a bone not quite rigid). The distance from
/// a point to a surface changes by at most the point's move relative to it, so a point that
/// was outside a bone, and farther than the offset, by a clearance is still outside by what is
/// left. Laid out as ContactSearch's clearance, point * (bones + muscles) + obstacle (the
/// muscles' entries 0). Empty where `motion` carries none (no settle before,
/// one that diverged, no bones).
std::vector<std::vector<double>> BoneClearancesNow(
  const SettleMotion& motion, const std::vector<TriangleMesh>& muscles, const std::vector<RigidFit>& placements);

/// The start of a motion: `muscles` in the rest pose (their action lines `restLines`, StillLines,
/// the bones `restBones` in the rest pose).
SettleMotion StartMotion(const std::vector<TriangleMesh>& muscles, const std::vector<const SurfaceEnergy*>& energies,
  const std::vector<std::vector<MatchedLine>>& restLines, const std::vector<FixedObstacle>& restBones);

/// Every muscle's unconstrained minimum (no contact, no volume) of its full-mesh energy for the
/// pose `lines[m]` describe, `bones` in that pose; in parallel.
std::vector<Points> FreeMinima(const std::vector<const SurfaceEnergy*>& energies,
  const std::vector<std::vector<MatchedLine>>& lines, const std::vector<FixedObstacle>& bones);

/// How far the muscles' unconstrained minimum moves from where `motion` is to the pose whose
/// minima are `freeMinima` (FreeMinima's): the largest point move, relative to its muscle's size
/// (0 without a motion to start from).
double LargestStartMove(
  const SettleMotion& motion, const std::vector<const SurfaceEnergy*>& energies, const std::vector<Points>& freeMinima);

/// How many equal parts a motion's step whose minimum moves by `startMove` (LargestStartMove's)
/// is settled in: the fewest in which no muscle's minimum moves by more than
/// SettleParameters::largestStartMove of its size, or, where each part `carriesContacts` to the
/// next (SettleMotion::carryContacts), largestCarriedMove (at most 64).
int SettleParts(double startMove, const SettleParameters& parameters, bool carriesContacts);

/// Settles every muscle of `muscles` (their points in, the settled points out) to the minimum
/// of its full-mesh energy for the pose `lines[m]` describes, holding `volumes[m]`, none of its
/// points inside a bone (`bones`, in that pose) or another muscle: the muscles are settled
/// together, and where two are in contact each gives way as its own stiffness says. Overlap
/// the rest pose has (`restOverlap`, OverlapMasks order) is left alone. The starting points
/// decide only which side of an obstacle a point is on. `energies[m]` belong to the muscles'
/// rest poses; the settle runs on their welded surfaces and writes the other points back with
/// CarryToUnwelded. A point inside an obstacle at the start goes out the nearest way; one that
/// goes in during the settle goes back out the way it came in. A settle that does not converge
/// within SettleParameters::maximumIterations keeps its last iterate, with `converged` false;
/// one that diverges (a third iteration that moves a point by half its muscle's size) stops
/// and leaves every muscle at its starting points, also with `converged` false.
/// With `motion` (a step of a motion, StartMotion at the first), the muscles' points in are
/// not read: the settle starts where `motion` says, and `motion` is moved on to where it ends.
/// `progress` (optional) receives the share of SettleParameters::maximumIterations done after
/// each iteration; it may throw (Cancelled) to stop the settle. `freeMinima`: FreeMinima of
/// `lines` and `bones` when the caller has them already (SettleParts'); empty: found here.
std::vector<SettleReport> SettleMuscles(std::vector<TriangleMesh>& muscles,
  const std::vector<const SurfaceEnergy*>& energies, const std::vector<std::vector<MatchedLine>>& lines,
  const std::vector<double>& volumes, const std::vector<FixedObstacle>& bones, const OverlapMasks* restOverlap,
  const SettleParameters& parameters, SettleMotion* motion = nullptr, const std::function<void(double)>& progress = {},
  std::vector<Points> freeMinima = {});
}
