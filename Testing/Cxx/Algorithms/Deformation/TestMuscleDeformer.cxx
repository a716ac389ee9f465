// SPDX-License-Identifier: BSD-3-Clause
// The one-pass muscle deformation (Filters/Algorithms/Deformation/MuscleDeformer.h) on the
// phantom and on small constructed cases.
#include "Deformation/MuscleDeformer.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/RigidMotion.h"
#include "Hull/ProgressiveHull.h"
#include "Motion/ActionLineMatching.h"
#include "Phantom/Phantom.h"
#include "TestMeshes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using md::Points;
using md::TriangleMesh;

namespace
{
/// The phantom's muscles with their hulls and matched action lines.
struct PhantomCase
{
  md::Phantom phantom;
  std::vector<TriangleMesh> hulls;
  std::vector<md::MuscleToDeform> muscles;
  std::vector<md::Obstacle> bones;

  explicit PhantomCase(double flexion)
    : phantom(md::BuildPhantom(md::PhantomParameters{ flexion, 1.0, 16 }))
  {
    md::HullParameters parameters;
    parameters.targetNumberOfPoints = 120;
    for (const md::PhantomMuscle& muscle : this->phantom.muscles)
    {
      this->hulls.push_back(md::BuildMuscleHull(muscle.rest, parameters).result.hull);
    }
    for (size_t m = 0; m < this->phantom.muscles.size(); ++m)
    {
      const md::PhantomMuscle& muscle = this->phantom.muscles[m];
      md::MuscleToDeform d{ muscle.name, &muscle.rest, &this->hulls[m], {} };
      for (size_t l = 0; l < muscle.actionLinesRest.size(); ++l)
      {
        const md::MatchedActionLines matched =
          md::MatchActionLines(muscle.actionLinesRest[l], muscle.actionLinesCurrent[l], 0.01);
        d.lines.push_back({ matched.rest, matched.current });
      }
      this->muscles.push_back(std::move(d));
    }
    std::vector<std::string> names;
    std::vector<TriangleMesh> current;
    for (const md::PhantomBone& bone : this->phantom.bones)
    {
      names.push_back(bone.name);
      current.push_back(TriangleMesh{ bone.currentPoints, bone.rest.triangles });
    }
    this->bones = md::BuildObstacles(names, current);
  }
};
}

TEST(MuscleDeformer, PhantomAt60DegreesConvergesWithVolumeKeptAndNothingFlipped)
{
  PhantomCase c(60);
  const auto results = md::DeformMuscles(c.muscles, c.bones, md::DeformationParameters{});
  ASSERT_EQ(results.size(), 3u);
  for (size_t m = 0; m < results.size(); ++m)
  {
    const md::DeformationResult& r = results[m];
    SCOPED_TRACE(c.muscles[m].name);
    EXPECT_TRUE(r.converged);
    EXPECT_LE(r.iterations, 100); // the cap is 200; the corrected step takes 5-50
    EXPECT_LT(std::abs(r.volumeChangePercent), 0.05);
    EXPECT_EQ(r.flippedTriangles, 0);
    EXPECT_TRUE(r.points.allFinite());
    // It moved: the insertion end follows the femur by tens of millimetres.
    EXPECT_GT((r.points - c.muscles[m].muscle->points).rowwise().norm().maxCoeff(), 20.0);
    // The action lines stay inside the muscle about as much as in the rest pose.
    EXPECT_GT(r.currentSamplesInside, r.restSamplesInside - 0.35);
  }
}

TEST(MuscleDeformer, RigidMotionsOfTheActionLinesMoveTheMuscleRigidly)
{
  PhantomCase c(0);
  md::MuscleToDeform muscle = c.muscles[1];
  const double size = (muscle.muscle->points.colwise().maxCoeff() - muscle.muscle->points.colwise().minCoeff()).norm();
  // A translation is reproduced exactly.
  md::RigidTransform shift;
  shift.translation = Eigen::Vector3d(40, -25, 10);
  // A rotation only approximately: the action lines give each segment's
  // direction, not its twist about itself (docs/DESIGN.md, section 4).
  const md::RigidTransform turn =
    md::RigidTransform::AboutPoint(Eigen::Vector3d(0.3, 1, 0.2), 50 * M_PI / 180, Eigen::Vector3d(10, -20, 5));
  for (const auto& [motion, tolerance] : { std::make_pair(shift, 1e-6), std::make_pair(turn, 0.02) })
  {
    for (md::MatchedLine& line : muscle.lines)
    {
      line.current = motion.Apply(line.rest);
    }
    const auto results = md::DeformMuscles({ muscle }, {}, md::DeformationParameters{});
    const Points expected = motion.Apply(muscle.muscle->points);
    EXPECT_LT((results[0].points - expected).rowwise().norm().maxCoeff(), tolerance * size);
    EXPECT_EQ(results[0].flippedTriangles, 0);
    EXPECT_LT(std::abs(results[0].volumeChangePercent), 1e-6);
  }
}

TEST(MuscleDeformer, VolumeConvergesToTheRestVolumeAtEveryStepLength)
{
  // The original's sign error leaves an error proportional to the step
  // length (TestVolumeConstrainedSolver shows 5 % at 0.1); the corrected step
  // must reach the rest volume whatever the step length.
  PhantomCase c(60);
  for (double alpha : { 0.1, 0.3, 1.0 })
  {
    md::DeformationParameters parameters;
    parameters.stepLength = alpha;
    parameters.dynamicIntersections = false;
    parameters.maximumIterations = 400;
    parameters.maximumCoarseIterations = 300;
    parameters.convergenceTolerance = 1e-4;
    const auto results = md::DeformMuscles({ c.muscles[0] }, {}, parameters);
    SCOPED_TRACE(alpha);
    EXPECT_TRUE(results[0].converged);
    EXPECT_LT(std::abs(results[0].volumeChangePercent), 1e-4);
  }
  md::DeformationParameters free;
  free.preserveVolume = false;
  free.dynamicIntersections = false;
  const auto unconstrained = md::DeformMuscles({ c.muscles[0] }, {}, free);
  EXPECT_GT(std::abs(unconstrained[0].volumeChangePercent), 0.5) << "the case must need the volume constraint";
}

TEST(MuscleDeformer, DynamicIntersectionsStopPointsAtTheObstacle)
{
  // The femur swings into the rectus femoris at 60 degrees.
  PhantomCase c(60);
  md::DeformationParameters off;
  off.dynamicIntersections = false;
  const auto free = md::DeformMuscles({ c.muscles[2] }, {}, off);
  const auto held = md::DeformMuscles({ c.muscles[2] }, c.bones, md::DeformationParameters{});
  const md::TriangleTree& femur = *c.bones[1].tree;
  const std::int64_t insideFree = md::CountInsideTree(femur, free[0].points);
  const std::int64_t insideHeld = md::CountInsideTree(femur, held[0].points);
  EXPECT_GT(insideFree, 0);
  // Only points already inside at the start of the fine phase stay inside; none enters.
  EXPECT_LE(insideHeld, held[0].verticesFrozen);
  EXPECT_EQ(held[0].flippedTriangles, 0);
  EXPECT_LT(std::abs(held[0].volumeChangePercent), 0.05);
}

namespace
{
/// The deepest of `points` inside `tree` (distance to its surface), 0 when none is.
double DeepestInside(const md::TriangleTree& tree, const Points& points)
{
  double deepest = 0;
  for (Eigen::Index i = 0; i < points.rows(); ++i)
  {
    const Eigen::Vector3d p = points.row(i).transpose();
    if (tree.InBounds(p) && tree.Inside(p))
    {
      deepest = std::max(deepest, tree.ClosestPoint(p).distance);
    }
  }
  return deepest;
}
}

TEST(MuscleDeformer, ContactRowsPushTheMuscleOffTheBoneThatMovedIntoIt)
{
  // The femur swings into the rectus femoris at 30 degrees: the paper's step
  // leaves the points it swept over inside (frozen) for the static
  // resolution; with contact rows the muscle moves off the bone as a whole.
  PhantomCase c(20);
  const md::TriangleTree& femur = *c.bones[1].tree;
  md::DeformationParameters paper;
  md::DeformationParameters contact;
  contact.contactWeight = 0.5;
  const auto without = md::DeformMuscles({ c.muscles[2] }, c.bones, paper);
  const auto with = md::DeformMuscles({ c.muscles[2] }, c.bones, contact);
  EXPECT_EQ(without[0].verticesInContact, 0);
  EXPECT_GT(with[0].verticesInContact, 0);
  const double deepWithout = DeepestInside(femur, without[0].points);
  const double deepWith = DeepestInside(femur, with[0].points);
  EXPECT_GT(deepWithout, 0);
  EXPECT_LT(deepWith, 0.5 * deepWithout);
  EXPECT_LT(with[0].verticesFrozen, without[0].verticesFrozen);
  EXPECT_TRUE(with[0].converged);
  EXPECT_LT(std::abs(with[0].volumeChangePercent), 0.05);
  EXPECT_EQ(with[0].flippedTriangles,
    md::CountFlippedTriangles(c.muscles[2].muscle->points, with[0].points, c.muscles[2].muscle->triangles));

  // Overlap a muscle may keep is left alone: with every point allowed inside
  // the femur, nothing is pushed.
  std::vector<std::vector<char>> allowed(c.bones.size(), std::vector<char>(c.muscles[2].muscle->points.rows(), 0));
  allowed[1].assign(allowed[1].size(), 1);
  md::MuscleToDeform keeping = c.muscles[2];
  keeping.boneOverlap = &allowed;
  const auto kept = md::DeformMuscles({ keeping }, c.bones, contact);
  EXPECT_EQ(kept[0].verticesInContact, 0);

  // A list per bone, one entry per point, or a clear refusal.
  std::vector<std::vector<char>> wrong(1, std::vector<char>(3, 0));
  keeping.boneOverlap = &wrong;
  try
  {
    md::DeformMuscles({ keeping }, c.bones, contact);
    ADD_FAILURE() << "a bone overlap of the wrong size was accepted";
  }
  catch (const md::InputError& e)
  {
    EXPECT_NE(std::string(e.what()).find(keeping.name), std::string::npos) << e.what();
  }
}

TEST(MuscleDeformer, MusclesAreObstaclesForEachOther)
{
  // Two copies of a muscle side by side, the one behind pushed into the one
  // ahead. The coarse phase has no obstacles, so some overlap remains (for the
  // static resolution); the fine phase must not add to it.
  PhantomCase c(0);
  const md::MuscleToDeform& base = c.muscles[0];
  const double width = (base.muscle->points.col(0).maxCoeff() - base.muscle->points.col(0).minCoeff());
  TriangleMesh shifted = *base.muscle, shiftedHull = *base.hull;
  shifted.points.col(0).array() += 1.1 * width;
  shiftedHull.points.col(0).array() += 1.1 * width;
  md::MuscleToDeform ahead = base, behind = base;
  behind.name = "behind";
  ahead.name = "ahead";
  ahead.muscle = &shifted;
  ahead.hull = &shiftedHull;
  for (md::MatchedLine& line : ahead.lines)
  {
    line.rest.col(0).array() += 1.1 * width;
    line.current = line.rest; // stays
  }
  for (md::MatchedLine& line : behind.lines)
  {
    line.current = line.rest;
    line.current.col(0).array() += 0.6 * width;
  }
  md::DeformationParameters off;
  off.dynamicIntersections = false;
  const auto together = md::DeformMuscles({ behind, ahead }, {}, md::DeformationParameters{});
  const auto apart = md::DeformMuscles({ behind, ahead }, {}, off);
  const md::TriangleTree aheadTogether(TriangleMesh{ together[1].points, shifted.triangles });
  const md::TriangleTree aheadApart(TriangleMesh{ apart[1].points, shifted.triangles });
  const std::int64_t overlapTogether = md::CountInsideTree(aheadTogether, together[0].points);
  const std::int64_t overlapApart = md::CountInsideTree(aheadApart, apart[0].points);
  EXPECT_LT(overlapTogether, overlapApart);
  EXPECT_EQ(together[0].flippedTriangles, 0);
}

TEST(MuscleDeformer, FlippedTrianglesIgnoreRigidMotionAndFindTurnedTriangles)
{
  const TriangleMesh muscle = md::BuildPhantom(md::PhantomParameters{}).muscles[0].rest;
  const md::RigidTransform turn =
    md::RigidTransform::AboutPoint(Eigen::Vector3d(1, 0.5, 0), 170 * M_PI / 180, Eigen::Vector3d::Zero());
  EXPECT_EQ(md::CountFlippedTriangles(muscle.points, turn.Apply(muscle.points), muscle.triangles), 0);
  // Fold one triangle over its edge bc: its corner a goes to the other side.
  Points folded = muscle.points;
  const Eigen::Index t = 100;
  const Eigen::RowVector3d a = muscle.points.row(muscle.triangles(t, 0));
  const Eigen::RowVector3d b = muscle.points.row(muscle.triangles(t, 1));
  const Eigen::RowVector3d c = muscle.points.row(muscle.triangles(t, 2));
  const Eigen::RowVector3d foot = b + (a - b).dot(c - b) / (c - b).squaredNorm() * (c - b);
  folded.row(muscle.triangles(t, 0)) = foot + (foot - a);
  const std::vector<Eigen::Index> flipped = md::FlippedTriangles(muscle.points, folded, muscle.triangles);
  EXPECT_NE(std::find(flipped.begin(), flipped.end(), t), flipped.end());
}

TEST(MuscleDeformer, BadInputIsRefusedWithTheMuscleNamed)
{
  PhantomCase c(60);
  // Action lines that miss the muscle.
  md::MuscleToDeform away = c.muscles[0];
  for (md::MatchedLine& line : away.lines)
  {
    line.rest.col(0).array() += 1000;
    line.current.col(0).array() += 1000;
  }
  try
  {
    md::DeformMuscles({ away }, {}, md::DeformationParameters{});
    FAIL() << "action lines outside the muscle were accepted";
  }
  catch (const md::InputError& e)
  {
    EXPECT_NE(std::string(e.what()).find("does not pass through the muscle"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Iliopsoas"), std::string::npos) << e.what();
  }
  // A muscle lying entirely inside an obstacle (given in the wrong place).
  const TriangleMesh box = Box(c.muscles[0].muscle->points.colwise().minCoeff().transpose().array() - 10,
    c.muscles[0].muscle->points.colwise().maxCoeff().transpose().array() + 10);
  ASSERT_GT(md::SignedVolume(box.points, box.triangles), 0);
  const auto swallowing = md::BuildObstacles({ "BigBone" }, { box });
  EXPECT_THROW(md::DeformMuscles({ c.muscles[0] }, swallowing, md::DeformationParameters{}), md::InputError);
  // No action line; unmatched lines; NaN.
  md::MuscleToDeform none = c.muscles[0];
  none.lines.clear();
  EXPECT_THROW(md::DeformMuscles({ none }, {}, md::DeformationParameters{}), md::InputError);
  md::MuscleToDeform unmatched = c.muscles[0];
  unmatched.lines[0].current = unmatched.lines[0].current.topRows(1);
  EXPECT_THROW(md::DeformMuscles({ unmatched }, {}, md::DeformationParameters{}), md::InputError);
  TriangleMesh broken = *c.muscles[0].muscle;
  broken.points(3, 1) = std::nan("");
  md::MuscleToDeform withNaN = c.muscles[0];
  withNaN.muscle = &broken;
  EXPECT_THROW(md::DeformMuscles({ withNaN }, {}, md::DeformationParameters{}), md::InputError);
}

TEST(ActionLineLimit, DenseLinesAreCutDownKeepingTheirCornersAndShortOnesAreUntouched)
{
  // A path through three corners, sampled every 0.01 mm over about 300 mm (30,000 points), its
  // current pose a rotated copy.
  const Eigen::Vector3d corners[4] = { { 0, 0, 0 }, { 100, 0, 0 }, { 100, 100, 0 }, { 100, 100, 100 } };
  std::vector<Eigen::Vector3d> dense;
  for (int c = 0; c < 3; ++c)
  {
    for (int k = 0; k < 10000; ++k)
    {
      dense.push_back(corners[c] + (corners[c + 1] - corners[c]) * (k / 10000.0));
    }
  }
  dense.push_back(corners[3]);
  md::MatchedLine line;
  line.rest.resize(static_cast<Eigen::Index>(dense.size()), 3);
  for (size_t i = 0; i < dense.size(); ++i)
  {
    line.rest.row(static_cast<Eigen::Index>(i)) = dense[i].transpose();
  }
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  line.current = line.rest * turn.transpose();
  md::MatchedLine shortLine;
  shortLine.rest = line.rest.topRows(100);
  shortLine.current = line.current.topRows(100);
  std::vector<md::MatchedLine> lines = { shortLine, line };
  const std::vector<std::string> notes = md::LimitActionLinePoints(lines, 256);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("action line 2 has 30001 points"), std::string::npos) << notes[0];
  // The short line: exactly as it was.
  EXPECT_EQ(lines[0].rest, shortLine.rest);
  EXPECT_EQ(lines[0].current, shortLine.current);
  // The dense one: within the limit, ends and corners kept, both poses cut at the same points.
  ASSERT_LE(lines[1].rest.rows(), 256);
  ASSERT_GE(lines[1].rest.rows(), 4);
  for (const Eigen::Vector3d& corner : corners)
  {
    bool found = false;
    for (Eigen::Index k = 0; k < lines[1].rest.rows(); ++k)
    {
      found = found || (lines[1].rest.row(k).transpose() - corner).norm() < 1e-9;
    }
    EXPECT_TRUE(found) << corner.transpose();
  }
  EXPECT_LT((lines[1].current - lines[1].rest * turn.transpose()).cwiseAbs().maxCoeff(), 1e-9);
  // A line's own points are kept whatever their deviation (here two on a straight stretch), and
  // named again among the points kept.
  md::MatchedLine withOwn = line;
  withOwn.knots = { 0, 5000, 10000, 15000, 30000 };
  std::vector<md::MatchedLine> owned{ withOwn };
  md::LimitActionLinePoints(owned, 256);
  ASSERT_EQ(owned[0].knots.size(), withOwn.knots.size());
  EXPECT_TRUE(md::KnotsFit(owned[0].knots, owned[0].rest.rows()));
  for (size_t j = 0; j < withOwn.knots.size(); ++j)
  {
    EXPECT_EQ(owned[0].rest.row(owned[0].knots[j]), withOwn.rest.row(withOwn.knots[j])) << j;
  }
}
