// SPDX-License-Identifier: BSD-3-Clause
// Muscle surfaces made from paths: closed, manifold, outward, the estimated volume, the path
// inside, no fold at a via point's corner, ends at the path's ends; every OpenSim model's muscles.
#include "Anatomy/MuscleFromPath.h"

#include "Geometry/MeshChecks.h"
#include "Geometry/Polyline.h"
#include "OpenSim/OpenSimKinematics.h"
#include "OpenSim/OpenSimModel.h"
#include "RealData.h"
#include "TestMeshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>

namespace
{
md::MuscleProperties Muscle(double force, double fibre, double tendon)
{
  md::MuscleProperties muscle;
  muscle.maxIsometricForce = force;
  muscle.optimalFiberLength = fibre;
  muscle.tendonSlackLength = tendon;
  muscle.pennationAngle = 0.1;
  return muscle;
}

md::Points Path(std::initializer_list<Eigen::Vector3d> points)
{
  md::Points path(static_cast<Eigen::Index>(points.size()), 3);
  Eigen::Index i = 0;
  for (const Eigen::Vector3d& p : points)
  {
    path.row(i++) = p.transpose();
  }
  return path;
}

/// How many of `count` points along `path` between its ends (the ends themselves lie on the
/// caps) are not inside `surface`.
int PathPointsOutside(const md::Points& path, const md::TriangleMesh& surface, int count = 50)
{
  std::vector<Eigen::Vector3d> curve;
  for (Eigen::Index i = 0; i < path.rows(); ++i)
  {
    curve.emplace_back(path.row(i).transpose());
  }
  const md::Points samples = md::ResampleByArcLength(curve, count + 1);
  int outside = 0;
  for (Eigen::Index k = 1; k < count; ++k)
  {
    const Eigen::Vector3d p = samples.row(k).transpose();
    outside += std::abs(md::WindingNumber(surface.points, surface.triangles, p) - 1.0) > 1e-6;
  }
  return outside;
}

void ExpectSoundSurface(const md::MuscleFromPathResult& result, const md::Points& path, const std::string& label)
{
  const md::TriangleMesh& surface = result.surface;
  EXPECT_TRUE(md::CheckEdges(surface.triangles).IsClosedOrientedManifold()) << label;
  EXPECT_NEAR(md::SignedVolume(surface.points, surface.triangles) / result.estimatedVolume, 1.0, 1e-6) << label;
  EXPECT_NEAR(result.volume / result.estimatedVolume, 1.0, 1e-6) << label;
  EXPECT_EQ(PathPointsOutside(path, surface), 0) << label;
  // The ends are the path's own: the attachments.
  EXPECT_EQ((surface.points.row(surface.points.rows() - 2) - path.row(0)).norm(), 0.0) << label;
  EXPECT_EQ((surface.points.row(surface.points.rows() - 1) - path.row(path.rows() - 1)).norm(), 0.0) << label;
}

std::string InputErrorOf(const std::function<void()>& action)
{
  try
  {
    action();
  }
  catch (const md::InputError& e)
  {
    return e.what();
  }
  return "";
}
}

TEST(MuscleFromPath, AStraightPathGivesAClosedOutwardSpindleOfTheEstimatedVolume)
{
  // 1000 N at 0.6 N/mm^2 is 1667 mm^2 of cross-section; times 100 mm: 166,667 mm^3.
  const md::Points path = Path({ { 0, 0, 0 }, { 0, 0, 200 } });
  const md::MuscleFromPathResult result = md::MuscleFromPath(path, Muscle(1000, 100, 50), {});
  EXPECT_NEAR(result.estimatedVolume, 1000 / 0.6 * 100, 1e-6);
  ExpectSoundSurface(result, path, "straight");
  EXPECT_LE(result.surface.points.rows(), 600);
  EXPECT_GE(result.surface.points.rows(), 500);
  EXPECT_TRUE(result.notes.empty());
  // The belly is the path less its tendon, the tendon at both ends alike.
  EXPECT_NEAR(result.bellyStart, 25, 1e-9);
  EXPECT_NEAR(result.bellyEnd, 175, 1e-9);
  EXPECT_NEAR(result.tendonRadius, 0.25 * result.bellyRadius, 1e-12);
  // Along the tendons the surface keeps the tendon's radius; mid-belly, the belly's.
  double nearEnd = 0, mid = 0;
  for (Eigen::Index i = 0; i + 2 < result.surface.points.rows(); ++i)
  {
    const Eigen::Vector3d p = result.surface.points.row(i).transpose();
    const double r = std::hypot(p.x(), p.y());
    if (p.z() < 20)
    {
      nearEnd = std::max(nearEnd, r);
    }
    if (std::abs(p.z() - 100) < 5)
    {
      mid = std::max(mid, r);
    }
  }
  EXPECT_NEAR(nearEnd, result.tendonRadius, 1e-9 * result.bellyRadius);
  EXPECT_NEAR(mid, result.bellyRadius, 0.01 * result.bellyRadius);
  // A straight spindle of this volume has its belly's radius a little over sqrt(V / (pi 150)).
  EXPECT_GT(result.bellyRadius, std::sqrt(result.estimatedVolume / (M_PI * 150)));
}

TEST(MuscleFromPath, AViaPointsRightAngleDoesNotFoldTheSurfaceAndThePathStaysInside)
{
  // A thick belly (radius about 20) round a corner of 90 degrees and one of 120.
  const md::Points path = Path({ { 0, 0, 0 }, { 120, 0, 0 }, { 120, 120, 0 }, { 60, 200, 30 } });
  const md::MuscleFromPathResult result = md::MuscleFromPath(path, Muscle(2000, 150, 60), {});
  ExpectSoundSurface(result, path, "corners");
  EXPECT_EQ(md::CountSelfIntersections(result.surface), 0);
  EXPECT_GT(result.bellyRadius, 15);
}

TEST(MuscleFromPath, TheVolumeScalesWithTheForceAndFibreAndNotWithTheResolution)
{
  const md::Points path = Path({ { 0, 0, 0 }, { 50, 10, 0 }, { 100, 0, 20 } });
  const double coarse = md::MuscleFromPath(path, Muscle(500, 60, 10), { 0.6, 100, 0.25 }).volume;
  const double fine = md::MuscleFromPath(path, Muscle(500, 60, 10), { 0.6, 3000, 0.25 }).volume;
  const double twice = md::MuscleFromPath(path, Muscle(1000, 60, 10), { 0.6, 3000, 0.25 }).volume;
  const double weaker = md::MuscleFromPath(path, Muscle(500, 60, 10), { 0.3, 3000, 0.25 }).volume;
  EXPECT_NEAR(coarse / fine, 1.0, 1e-6);
  EXPECT_NEAR(twice / fine, 2.0, 1e-6);
  EXPECT_NEAR(weaker / fine, 2.0, 1e-6);
}

TEST(MuscleFromPath, ATendonLongerThanThePathLeavesTheBellyAThirdAndSaysSo)
{
  const md::Points path = Path({ { 0, 0, 0 }, { 90, 0, 0 } });
  const md::MuscleFromPathResult result = md::MuscleFromPath(path, Muscle(300, 40, 120), {});
  ASSERT_EQ(result.notes.size(), 1u);
  EXPECT_NE(result.notes[0].find("the belly takes 33.3"), std::string::npos) << result.notes[0];
  EXPECT_NEAR(result.bellyEnd - result.bellyStart, 30, 1e-9);
  ExpectSoundSurface(result, path, "long tendon");
}

TEST(MuscleFromPath, RefusesWhatItCannotUseSayingWhy)
{
  const md::Points path = Path({ { 0, 0, 0 }, { 0, 0, 100 } });
  EXPECT_NE(InputErrorOf([&] { md::MuscleFromPath(path.topRows(1), Muscle(100, 50, 10), {}); }).find("at least 2"),
    std::string::npos);
  md::Points bad = path;
  bad(1, 2) = std::nan("");
  EXPECT_NE(InputErrorOf([&] { md::MuscleFromPath(bad, Muscle(100, 50, 10), {}); }).find("finite"), std::string::npos);
  EXPECT_NE(InputErrorOf([&] {
    md::MuscleFromPath(Path({ { 1, 2, 3 }, { 1, 2, 3 } }), Muscle(100, 50, 10), {});
  }).find("no length"),
    std::string::npos);
  EXPECT_NE(InputErrorOf([&] { md::MuscleFromPath(path, Muscle(0, 50, 10), {}); }).find("max isometric force"),
    std::string::npos);
  EXPECT_NE(InputErrorOf([&] { md::MuscleFromPath(path, Muscle(100, std::nan(""), 10), {}); }).find("optimal fibre"),
    std::string::npos);
  EXPECT_NE(
    InputErrorOf([&] { md::MuscleFromPath(path, Muscle(100, 50, -1), {}); }).find("tendon slack"), std::string::npos);
  EXPECT_NE(InputErrorOf([&] {
    md::MuscleFromPath(path, Muscle(100, 50, 10), { 0.0, 600, 0.25 });
  }).find("specific tension"),
    std::string::npos);
  EXPECT_NE(InputErrorOf([&] {
    md::MuscleFromPath(path, Muscle(100, 50, 10), { 0.6, 10, 0.25 });
  }).find("points"),
    std::string::npos);
  EXPECT_NE(InputErrorOf([&] {
    md::MuscleFromPath(path, Muscle(100, 50, 10), { 0.6, 600, 0.0 });
  }).find("radius"),
    std::string::npos);
}

TEST(MuscleFromPath, ABoneBesideThePathHoldsTheSurfaceOffAndTheRestWidensToKeepTheVolume)
{
  // The belly's radius would be about 22 mm; a bone's face 12 mm from the path.
  const md::Points path = Path({ { 0, 0, 0 }, { 0, 0, 200 } });
  const md::TriangleMesh bone = Box({ 12, -60, -20 }, { 80, 60, 220 });
  const md::TriangleTree tree(bone);
  const md::MuscleFromPathResult free = md::MuscleFromPath(path, Muscle(1000, 100, 50), {});
  ASSERT_GT(free.surface.points.col(0).maxCoeff(), 20);
  const md::MuscleFromPathResult held = md::MuscleFromPath(path, Muscle(1000, 100, 50), {}, { &tree });
  ExpectSoundSurface(held, path, "beside a bone");
  EXPECT_GT(held.pointsHeldByBones, 0);
  EXPECT_NEAR(held.volumeKept, 1.0, 1e-6);
  EXPECT_TRUE(held.notes.empty());
  EXPECT_LT(held.surface.points.col(0).maxCoeff(), 12);
  EXPECT_GT(held.bellyRadius, free.bellyRadius); // the other side widens
  EXPECT_EQ(md::CountInside(bone.points, bone.triangles, held.surface.points), 0);
}

TEST(MuscleFromPath, APathThatStartsInABoneKeepsItsTubeThereAndAnOpenSheetHoldsFromItsFrontOnly)
{
  const md::Points path = Path({ { 0, 0, 0 }, { 0, 0, 200 } });
  const md::MuscleFromPathResult free = md::MuscleFromPath(path, Muscle(1000, 100, 50), {});
  // The origin inside a bone (an attachment): the rays from inside pass the faces they leave by.
  const md::TriangleMesh origin = Box({ -20, -20, -20 }, { 20, 20, 10 });
  const md::TriangleTree originTree(origin);
  const md::MuscleFromPathResult attached = md::MuscleFromPath(path, Muscle(1000, 100, 50), {}, { &originTree });
  EXPECT_EQ(attached.pointsHeldByBones, 0);
  EXPECT_TRUE(md::SameMesh(attached.surface, free.surface));
  // A sheet at x = 12 (two triangles): facing the path it holds the surface; facing away, not.
  md::TriangleMesh sheet;
  sheet.points.resize(4, 3);
  sheet.points << 12, -100, -50, 12, 100, -50, 12, 100, 250, 12, -100, 250;
  sheet.triangles.resize(2, 3);
  sheet.triangles << 0, 2, 1, 0, 3, 2; // normal -x: towards the path
  const md::TriangleTree facing(sheet);
  EXPECT_GT(md::MuscleFromPath(path, Muscle(1000, 100, 50), {}, { &facing }).pointsHeldByBones, 0);
  sheet.triangles.col(1).swap(sheet.triangles.col(2));
  const md::TriangleTree away(sheet);
  EXPECT_EQ(md::MuscleFromPath(path, Muscle(1000, 100, 50), {}, { &away }).pointsHeldByBones, 0);
}

TEST(MuscleFromPath, BonesThatLeaveNoRoomKeepWhatVolumeTheyCanAndSaySo)
{
  // A narrow channel, 8 mm wide, the whole length of the path.
  const md::Points path = Path({ { 0, 0, 0 }, { 0, 0, 200 } });
  const md::TriangleMesh left = Box({ -100, -100, -50 }, { -4, 100, 250 });
  const md::TriangleMesh right = Box({ 4, -100, -50 }, { 100, 100, 250 });
  const md::TriangleMesh below = Box({ -3, -100, -50 }, { 3, -4, 250 });
  const md::TriangleMesh above = Box({ -3, 4, -50 }, { 3, 100, 250 });
  const md::TriangleTree a(left), b(right), c(below), d(above);
  const md::MuscleFromPathResult result = md::MuscleFromPath(path, Muscle(1000, 100, 50), {}, { &a, &b, &c, &d });
  EXPECT_LT(result.volumeKept, 0.2);
  EXPECT_NEAR(result.volume / result.estimatedVolume, result.volumeKept, 1e-12);
  ASSERT_FALSE(result.notes.empty());
  EXPECT_NE(result.notes.back().find("leave room for"), std::string::npos);
  EXPECT_TRUE(md::CheckEdges(result.surface.triangles).IsClosedOrientedManifold());
}

/// Points of each surface inside any other (by each surface's tree), over all pairs.
int PointsInsideOthers(const std::vector<md::MuscleFromPathResult>& made)
{
  std::vector<std::unique_ptr<md::TriangleTree>> trees;
  for (const auto& m : made)
  {
    trees.push_back(m.surface.triangles.rows() ? std::make_unique<md::TriangleTree>(m.surface) : nullptr);
  }
  int inside = 0;
  for (size_t a = 0; a < made.size(); ++a)
  {
    for (size_t b = 0; b < made.size(); ++b)
    {
      for (Eigen::Index i = 0; a != b && trees[b] && i < made[a].surface.points.rows(); ++i)
      {
        const Eigen::Vector3d p = made[a].surface.points.row(i).transpose();
        inside += trees[b]->InBounds(p) && trees[b]->Inside(p);
      }
    }
  }
  return inside;
}

TEST(MuscleFromPath, TwoMusclesSideBySideShareTheSpaceBetweenThemAndKeepTheirVolumes)
{
  // Bellies of about 22 mm radius on paths 30 mm apart: alone they overlap by a third.
  const std::vector<md::Points> paths{ Path({ { 0, 0, 0 }, { 0, 0, 200 } }), Path({ { 30, 0, 0 }, { 30, 0, 200 } }),
    Path({ { 15, 60, 0 }, { 15, 60, 200 } }) };
  const std::vector<md::MuscleProperties> muscles(3, Muscle(1000, 100, 50));
  std::vector<md::MuscleFromPathResult> alone;
  for (const md::Points& path : paths)
  {
    alone.push_back(md::MuscleFromPath(path, muscles[0], {}));
  }
  ASSERT_GT(PointsInsideOthers(alone), 50);
  std::vector<std::string> failures;
  const std::vector<md::MuscleFromPathResult> together = md::MusclesFromPaths(paths, muscles, {}, {}, failures);
  ASSERT_EQ(together.size(), 3u);
  EXPECT_EQ(failures, std::vector<std::string>(3));
  EXPECT_EQ(PointsInsideOthers(together), 0);
  for (size_t m = 0; m < 3; ++m)
  {
    ExpectSoundSurface(together[m], paths[m], "side by side " + std::to_string(m));
    EXPECT_NEAR(together[m].volumeKept, 1.0, 1e-6);
    EXPECT_EQ(together[m].pointsHeldByBones, 0);
  }
  EXPECT_GT(together[0].pointsHeldByMuscles, 0);
  EXPECT_GT(together[1].pointsHeldByMuscles, 0);
  // The pair meets halfway: no point of the first beyond x = 15, none of the second short of it.
  EXPECT_LT(together[0].surface.points.col(0).maxCoeff(), 15);
  EXPECT_GT(together[1].surface.points.col(0).minCoeff(), 15);
}

TEST(MuscleFromPath, MusclesWhosePathsCrossOverlapOnlyWhereThePathsForceItAndABadOneFailsAlone)
{
  // Two paths crossing at mid-length: near the crossing each centre is inside the other's tube.
  const std::vector<md::Points> paths{ Path({ { -100, 0, 0 }, { 100, 0, 0 } }), Path({ { 0, -100, 0 }, { 0, 100, 0 } }),
    Path({ { 0, 0, 100 }, { 0, 0, 300 } }) };
  std::vector<md::MuscleProperties> muscles(3, Muscle(600, 80, 40));
  muscles[2].maxIsometricForce = -1;
  std::vector<std::string> failures;
  const std::vector<md::MuscleFromPathResult> made = md::MusclesFromPaths(paths, muscles, {}, {}, failures);
  EXPECT_TRUE(failures[0].empty() && failures[1].empty());
  EXPECT_NE(failures[2].find("max isometric force"), std::string::npos);
  EXPECT_EQ(made[2].surface.points.rows(), 0);
  std::vector<md::MuscleFromPathResult> alone{ md::MuscleFromPath(paths[0], muscles[0], {}),
    md::MuscleFromPath(paths[1], muscles[1], {}) };
  const std::vector<md::MuscleFromPathResult> pair{ made[0], made[1] };
  EXPECT_LT(PointsInsideOthers(pair), PointsInsideOthers(alone) / 2);
  for (size_t m = 0; m < 2; ++m)
  {
    ExpectSoundSurface(made[m], paths[m], "crossing " + std::to_string(m));
  }
  // Every point left inside the other is near the crossing, where the paths force it.
  const md::TriangleTree other(made[1].surface);
  for (Eigen::Index i = 0; i < made[0].surface.points.rows(); ++i)
  {
    const Eigen::Vector3d p = made[0].surface.points.row(i).transpose();
    if (other.InBounds(p) && other.Inside(p))
    {
      EXPECT_LT(std::abs(p.x()), 2.5 * made[1].bellyRadius) << p.transpose();
    }
  }
}

/// Every muscle of an OpenSim model, in its default pose, in mm: what a user without muscle
/// surfaces gets. Each surface closed, oriented, of its estimated volume, its path inside it.
void EveryMuscleOfAModel(const std::string& relative, size_t muscles)
{
  const std::string file = RealDataFile(relative);
  if (file.empty())
  {
    GTEST_SKIP() << "OpenSim data not found: set MUSCLEDEFORMATION_DATA_DIR to the folder holding opensim/";
  }
  const md::osim::Model model = md::osim::ReadModel(file);
  std::vector<double> q = md::osim::DefaultCoordinates(model);
  md::osim::ApplyCouplers(model, q);
  const auto poses = md::osim::BodyPoses(model, q);
  size_t made = 0;
  int folded = 0, clamped = 0;
  double worst = 0;
  for (const md::osim::Path& path : model.paths)
  {
    if (!path.muscle.Known())
    {
      continue;
    }
    md::MuscleProperties mm = path.muscle;
    mm.optimalFiberLength *= 1000;
    mm.tendonSlackLength *= 1000;
    const md::Points points = 1000 * md::osim::PathAt(model, path, q, poses).points;
    const md::MuscleFromPathResult result = md::MuscleFromPath(points, mm, {});
    ExpectSoundSurface(result, points, path.name);
    worst = std::max(worst, std::abs(result.volume / result.estimatedVolume - 1));
    folded += md::CountSelfIntersections(result.surface) > 0;
    clamped += !result.notes.empty();
    ++made;
  }
  EXPECT_EQ(made, muscles);
  EXPECT_EQ(folded, 0);
  // All at once, sharing the space: fewer points of one inside another, every volume kept.
  std::vector<md::Points> paths;
  std::vector<md::MuscleProperties> properties;
  std::vector<md::MuscleFromPathResult> alone;
  for (const md::osim::Path& path : model.paths)
  {
    if (path.muscle.Known())
    {
      md::MuscleProperties mm = path.muscle;
      mm.optimalFiberLength *= 1000;
      mm.tendonSlackLength *= 1000;
      paths.push_back(1000 * md::osim::PathAt(model, path, q, poses).points);
      properties.push_back(mm);
      alone.push_back(md::MuscleFromPath(paths.back(), mm, {}));
    }
  }
  std::vector<std::string> failures;
  const auto together = md::MusclesFromPaths(paths, properties, {}, {}, failures);
  double leastKept = 1;
  for (size_t m = 0; m < together.size(); ++m)
  {
    EXPECT_TRUE(failures[m].empty()) << failures[m];
    EXPECT_TRUE(md::CheckEdges(together[m].surface.triangles).IsClosedOrientedManifold());
    EXPECT_EQ(PathPointsOutside(paths[m], together[m].surface), 0) << m;
    leastKept = std::min(leastKept, together[m].volumeKept);
  }
  const int before = PointsInsideOthers(alone), after = PointsInsideOthers(together);
  EXPECT_LT(after, before / 2);
  std::printf("%s: surface points inside another muscle %d alone, %d sharing the space; least volume kept %.6f\n",
    relative.c_str(), before, after, leastKept);
  std::printf("%s: %zu muscles, largest volume error %.2g, %d with a self-intersecting surface, %d with the belly's "
              "share clamped\n",
    relative.c_str(), made, worst, folded, clamped);
}

TEST(MuscleFromPath, EveryMuscleOfGait2392)
{
  EveryMuscleOfAModel("opensim/gait2392_walk_forward/subject01_simbody_adjusted.osim", 92);
}

TEST(MuscleFromPath, EveryMuscleOfRajagopal2016)
{
  EveryMuscleOfAModel("opensim/rajagopal2016_walk_armless_18musc/subject_walk_armless_18musc.osim", 18);
}

TEST(MuscleFromPath, EveryMuscleOfGait10dof18musc)
{
  EveryMuscleOfAModel("opensim/gait10dof18musc_walk/walk_gait1018_subject01.osim", 18);
}
