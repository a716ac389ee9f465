// SPDX-License-Identifier: BSD-3-Clause
#include "Settle/SurfaceSettle.h"

#include "Common/Clock.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/TriangleTree.h"
#include "Settle/ActiveSet.h"
#include "Settle/SettleContacts.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <set>

namespace md
{
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

/// How many times an iteration's step is solved again with the watched contacts it would break
/// (SettleParameters::contactLookahead).
constexpr int kJoiningRounds = 10;

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
  const double seconds = SecondsSince(start);
  for (SettleReport& report : reports)
  {
    report.iterations = iteration;
    report.converged = settled;
    report.seconds = seconds / static_cast<double>(std::max<size_t>(1, count));
  }
  return reports;
}
}