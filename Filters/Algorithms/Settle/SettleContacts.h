// SPDX-License-Identifier: BSD-3-Clause
// The settle's contacts (docs/DESIGN.md section 7), the Settle stage's own: each linearised as a
// half-space at a triangle of its obstacle, and found at each iteration by a search that skips
// the points proven clear of an obstacle. Used by SurfaceSettle.cxx only.
#pragma once

#include "Geometry/TriangleTree.h"
#include "Intersections/StaticIntersections.h"
#include "Settle/SurfaceEnergy.h"

#include <map>
#include <memory>
#include <tuple>
#include <utility>
#include <vector>

namespace md
{
/// How far (a fraction of the muscle's size) the contact search looks beyond the offset for a
/// point that is outside an obstacle, so that it need not test that point again until it, or the
/// obstacle, has moved that far (ContactSearch's `clearance`).
constexpr double kClearanceReach = 0.03;
/// The rounding of a distance to an obstacle, a fraction of the muscle's size: a clearance less
/// this is still one (ContactSearch, ProvenOutsideBones).
constexpr double kClearanceRounding = 1e-9;
/// Two muscle-muscle contact rows whose cosine in the dual system's metric is below minus this
/// bound the same gap from opposite sides (ExcludeOpposedContacts): exactly, as where a point
/// inside and its partner outside name each other; nearly, where watched contacts held from
/// earlier iterations meet points inside. An iteration that blows up (a point moved by more than
/// kBlownUp of its muscle's size) is solved again leaving out the nearly opposed rows as well
/// and watching nothing: two spindles crossed at 45 degrees blew up at their ninth iteration
/// (a move of 3.85 times a spindle's size) and, solved again, settled apart.
constexpr double kExactlyOpposed = 1 - 1e-9;
constexpr double kNearlyOpposed = 0.9;

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
Eigen::Vector3d Where(const Term& t, const Points& points);

/// The term `b`'s point (or sample) in the inverse's column of term `a`: a . K^-1 b.
double InverseBetween(const Term& a, const Term& b);

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
  bool violated, const TriangleTree& tree, size_t bones, double offset);

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
  std::vector<char>& active, std::vector<double>& slack, double opposed);

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
    std::vector<std::vector<double>>& clearance, bool carriesContacts);

  int NumberOfBlocks() const { return static_cast<int>(this->Blocks.size()); }

  /// Tests the points of block `block` against every obstacle.
  void Run(int block);

  /// The contacts found, muscle by muscle and point by point; `wasInside` updated.
  /// `pending`: the watched contacts (near, not broken, not held), in the same order.
  std::vector<Contact> Finish(std::vector<Contact>& pending);

private:
  /// Points a block of the search holds.
  static constexpr Eigen::Index kSearchBlock = 256;

  size_t Obstacles() const { return this->Bones.size() + this->Meshes.size(); }

  const TriangleTree& Obstacle(size_t o) const
  {
    return o < this->Bones.size() ? *this->Bones[o].tree : *this->Trees[o - this->Bones.size()];
  }

  void TestPoint(size_t m, Eigen::Index i);

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
  const std::vector<std::vector<double>>& clearance);
}
