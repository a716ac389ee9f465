// SPDX-License-Identifier: BSD-3-Clause
// Hulls and mean value coordinates of every real muscle: ../shared/data
// (MUSCLEDEFORMATION_DATA_DIR), lhdl_hip_r and vhf_right. Skipped, and
// reported as skipped by ctest, when the data is absent.
#include "Geometry/MeanValueCoordinates.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/SurfaceRepair.h"
#include "Hull/ProgressiveHull.h"
#include "RealData.h"

#include <gtest/gtest.h>

#include <random>

namespace
{
class RealMuscleHull : public ::testing::TestWithParam<std::string>
{
};
}

TEST_P(RealMuscleHull, EnclosesEveryPointIsClosedManifoldAndReproducesPoints)
{
  const std::string path = RealDataFile(GetParam());
  if (path.empty())
  {
    GTEST_SKIP() << GetParam() << " not found: set MUSCLEDEFORMATION_DATA_DIR (default ../shared/data)";
  }
  const md::TriangleMesh muscle = ReadSurface(path);
  const md::Points points = md::UsedPoints(muscle);
  const double size = (points.colwise().maxCoeff() - points.colwise().minCoeff()).norm();
  md::RepairReport report;
  const md::TriangleMesh clean = md::RepairClosedSurface(muscle, report);
  const md::HullResult result = md::BuildProgressiveHull(clean, md::HullParameters{}, &report.pointsToEnclose);
  const md::TriangleMesh& hull = result.hull;
  std::cout << "[ measured ] " << GetParam() << ": " << hull.points.rows() << " hull points, volume ratio "
            << md::SignedVolume(hull.points, hull.triangles) / md::SignedVolume(clean.points, clean.triangles)
            << (report.Changed() ? ", repaired: " + report.Describe() : "") << "\n";
  EXPECT_TRUE(result.reachedTarget);
  EXPECT_TRUE(md::CheckEdges(hull.triangles).IsClosedOrientedManifold());
  EXPECT_EQ(md::CountSelfIntersections(hull), 0);
  EXPECT_EQ(md::CountOutside(hull, points, 1e-9 * size), 0) << "every muscle point tested";
  const md::WeightMatrix weights = md::MeanValueCoordinates(hull, points);
  EXPECT_LT((weights * hull.points - points).rowwise().norm().maxCoeff(), 1e-9 * size);
  EXPECT_LT((weights.rowwise().sum().array() - 1.0).abs().maxCoeff(), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(LhdlAndVhf, RealMuscleHull,
  ::testing::Values("lhdl_hip_r/gluteus_maximus_r.vtk", "lhdl_hip_r/gluteus_medius_r.vtk", "lhdl_hip_r/iliacus_r.vtk",
    "lhdl_hip_r/psoas_r.vtk", "vhf_right/VHF_Right_Muscle_GluteusMaximus_smooth.stl",
    "vhf_right/VHF_Right_Muscle_GluteusMedius_smooth.stl", "vhf_right/VHF_Right_Muscle_Illiacus_smooth.stl",
    "vhf_right/VHF_Right_Muscle_PsoasMajor_smooth.stl", "vhf_right/VHF_Right_Muscle_RectusFemoris_smooth.stl"),
  [](const ::testing::TestParamInfo<std::string>& info) {
    std::string name = info.param.substr(info.param.rfind('/') + 1);
    name = name.substr(0, name.find('.'));
    for (char& c : name)
    {
      c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    }
    return name;
  });

// Noise of 1e-7 of each coordinate that splits a scan's duplicate points apart (the scans
// carry exact duplicates) made the LHDL gluteus medius's hull non-manifold: the repair now merges
// them, and every LHDL muscle gets its enclosing hull under such noise.
TEST(RealMuscleHulls, RoundingNoiseThatSplitsDuplicatePointsIsNoFailure)
{
  for (const char* name : { "gluteus_maximus_r", "gluteus_medius_r", "iliacus_r", "psoas_r" })
  {
    const std::string path = RealDataFile(std::string("lhdl_hip_r/") + name + ".vtk");
    if (path.empty())
    {
      GTEST_SKIP() << "lhdl_hip_r not found: set MUSCLEDEFORMATION_DATA_DIR (default ../shared/data)";
    }
    const md::TriangleMesh muscle = ReadSurface(path);
    md::RepairReport exact;
    md::RepairClosedSurface(muscle, exact);
    for (unsigned seed : { 1u, 2u })
    {
      SCOPED_TRACE(std::string(name) + ", seed " + std::to_string(seed));
      md::TriangleMesh noisy = muscle;
      std::mt19937 random(seed);
      std::uniform_real_distribution<double> noise(-1e-7, 1e-7);
      for (Eigen::Index i = 0; i < noisy.points.size(); ++i)
      {
        noisy.points.data()[i] *= 1 + noise(random); // each copy of a point moves its own way
      }
      md::MuscleHull built;
      ASSERT_NO_THROW(built = md::BuildMuscleHull(noisy, md::HullParameters{}));
      EXPECT_TRUE(md::CheckEdges(built.result.hull.triangles).IsClosedOrientedManifold());
      EXPECT_EQ(built.report.duplicatePointsMerged, exact.duplicatePointsMerged); // the same ones
    }
  }
}
