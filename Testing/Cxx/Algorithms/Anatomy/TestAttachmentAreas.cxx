// SPDX-License-Identifier: BSD-3-Clause
// Attachment areas: the landmark table read as the LHDL data set writes it, landmarks given to
// the muscle and bone they name or to the nearest, far landmarks left out and said, and the areas
// at action lines' ends where no landmark is given.
#include "Anatomy/AttachmentAreas.h"
#include "TestMeshes.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace
{
/// A sphere muscle (radius 5, z from 15 to 25) 0.2 below a "pelvis" box and 0.2 above a "femur" box,
/// its action line from inside the one to inside the other.
struct Case
{
  std::vector<std::string> muscleNames{ "muscle" };
  std::vector<md::TriangleMesh> muscles{ Sphere(Eigen::Vector3d(5, 5, 20), 5, 3) };
  std::vector<std::string> boneNames{ "pelvis_bone", "femur" };
  std::vector<md::TriangleMesh> bones{ Box(Eigen::Vector3d(-5, -5, 25.2), Eigen::Vector3d(15, 15, 35)),
    Box(Eigen::Vector3d(-5, -5, 5), Eigen::Vector3d(15, 15, 14.8)) };
  std::vector<std::vector<md::Points>> lines{ { (md::Points(2, 3) << 5, 5, 27, 5, 5, 13).finished() } };
};

md::LandmarkSet Marks(const std::string& muscle, const std::string& bone, std::initializer_list<Eigen::Vector3d> points)
{
  md::LandmarkSet set{ muscle, bone, "", md::Points(static_cast<Eigen::Index>(points.size()), 3) };
  Eigen::Index k = 0;
  for (const Eigen::Vector3d& p : points)
  {
    set.points.row(k++) = p.transpose();
  }
  return set;
}
}

TEST(AttachmentAreas, TheLandmarkTableReadsAsTheLhdlDataSetWritesIt)
{
  const std::string text = "muscle_group,cloud,attached_to,landmark,x_mm,y_mm,z_mm\n"
                           "R_Psoas,Ori_1,pelvis,1,1.5,2,3\n"
                           "R_Psoas,Ori_1,pelvis,2,4,5,6\n"
                           "R_Psoas,Ins_1,femur_r,1,7,8,9\n"
                           "\n"
                           "R_Iliacus,Ori_1,pelvis,1,0,0,-1e3\n";
  const std::vector<md::LandmarkSet> sets = md::ParseLandmarkTable(text, "areas.csv");
  ASSERT_EQ(sets.size(), 3u);
  EXPECT_EQ(sets[0].muscle, "R_Psoas");
  EXPECT_EQ(sets[0].area, "Ori_1");
  EXPECT_EQ(sets[0].bone, "pelvis");
  ASSERT_EQ(sets[0].points.rows(), 2);
  EXPECT_EQ(sets[0].points(0, 0), 1.5);
  EXPECT_EQ(sets[0].points(1, 2), 6);
  EXPECT_EQ(sets[1].bone, "femur_r");
  EXPECT_EQ(sets[2].points(0, 2), -1000);
  // A plain table: muscle, bone, x, y, z in any order, no area.
  const auto plain = md::ParseLandmarkTable("x,y,z,Bone,Muscle\n1,2,3,femur,psoas\n", "mine.csv");
  ASSERT_EQ(plain.size(), 1u);
  EXPECT_EQ(plain[0].muscle, "psoas");
  EXPECT_EQ(plain[0].bone, "femur");
  EXPECT_EQ(plain[0].area, "");
}

TEST(AttachmentAreas, ABadTableIsRefusedNamingTheLine)
{
  auto message = [](const std::string& text) {
    try
    {
      md::ParseLandmarkTable(text, "areas.csv");
    }
    catch (const md::InputError& e)
    {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("a,b,c\n1,2,3\n").find("must name the columns"), std::string::npos);
  EXPECT_NE(message("muscle,bone,x,y,z\nm,b,1,2\n").find("line 2: 4 values"), std::string::npos);
  EXPECT_NE(message("muscle,bone,x,y,z\nm,b,1,2,3\nm,b,1,nan,3\n").find("line 3: 'nan' is not a finite number"),
    std::string::npos);
  EXPECT_NE(message("muscle,bone,x,y,z\nm,b,1,2,3x\n").find("'3x'"), std::string::npos);
}

TEST(AttachmentAreas, LandmarksMarkTheSurfaceFacingThemOnTheBoneTheyName)
{
  const Case c;
  // Two landmarks on the femur's top face, under the sphere's bottom.
  const std::vector<md::LandmarkSet> marks{ Marks("muscle", "femur", { { 5, 5, 14.8 }, { 6, 5, 14.8 } }) };
  const md::FoundAttachments found =
    md::FindAttachments(c.muscleNames, c.muscles, c.lines, c.boneNames, c.bones, marks, true);
  ASSERT_EQ(found.areas[0].size(), 1u);
  const md::Attachment& area = found.areas[0][0];
  EXPECT_EQ(area.bone, "femur");
  EXPECT_EQ(area.boneIndex, 1);
  ASSERT_FALSE(area.points.empty());
  for (Eigen::Index i : area.points)
  {
    EXPECT_LT(c.muscles[0].points(i, 2), 17.0); // the bottom of the sphere only
  }
  // The point nearest each landmark is in the area.
  for (Eigen::Index j = 0; j < marks[0].points.rows(); ++j)
  {
    Eigen::Index nearest = 0;
    (c.muscles[0].points.rowwise() - marks[0].points.row(j)).rowwise().squaredNorm().minCoeff(&nearest);
    EXPECT_NE(std::find(area.points.begin(), area.points.end(), nearest), area.points.end());
  }
  EXPECT_EQ(area.anchors.size(), static_cast<size_t>(area.anchorsRest.rows()));
  EXPECT_GE(area.anchors.size(), 4u);
  EXPECT_TRUE(found.warnings.empty());
  EXPECT_NE(found.messages.back().find("muscle 'muscle': attached by landmarks 'muscle on femur' on 'femur'"),
    std::string::npos)
    << found.messages.back();
}

TEST(AttachmentAreas, NamesMatchIgnoringCaseAndFileExtensions)
{
  Case c;
  c.boneNames = { "Pelvis_Bone.vtk", "femur.stl" };
  const std::vector<md::LandmarkSet> marks{ Marks("MUSCLE", "femur", { { 5, 5, 14.8 }, { 6, 5, 14.8 } }) };
  const md::FoundAttachments found =
    md::FindAttachments(c.muscleNames, c.muscles, c.lines, c.boneNames, c.bones, marks, false);
  ASSERT_EQ(found.areas[0].size(), 1u);
  EXPECT_EQ(found.areas[0][0].boneIndex, 1);
  EXPECT_EQ(found.messages.size(), 1u); // nothing taken as the nearest
  EXPECT_EQ(found.messages[0].find("names no bone"), std::string::npos) << found.messages[0];
}

TEST(AttachmentAreas, NamesThatMatchNothingTakeTheNearestAndSaySo)
{
  const Case c;
  const std::vector<md::LandmarkSet> marks{ Marks("R_Muscle", "pelvis", { { 5, 5, 25.2 }, { 5, 6, 25.2 } }) };
  const md::FoundAttachments found =
    md::FindAttachments(c.muscleNames, c.muscles, c.lines, c.boneNames, c.bones, marks, true);
  ASSERT_EQ(found.areas[0].size(), 1u);
  EXPECT_EQ(found.areas[0][0].bone, "pelvis_bone");
  EXPECT_NE(found.messages[0].find("landmarks 'R_Muscle' belong to muscle 'muscle', the nearest"), std::string::npos);
  EXPECT_NE(found.messages[1].find("'pelvis' names no bone: the nearest"), std::string::npos) << found.messages[1];
}

TEST(AttachmentAreas, LandmarksFarFromTheMuscleAreLeftOutAndSaid)
{
  const Case c;
  const std::vector<md::LandmarkSet> marks{ Marks("muscle", "femur", { { 5, 5, -300 }, { 6, 5, -300 } }) };
  const md::FoundAttachments found =
    md::FindAttachments(c.muscleNames, c.muscles, c.lines, c.boneNames, c.bones, marks, false);
  EXPECT_TRUE(found.areas[0].empty());
  ASSERT_EQ(found.warnings.size(), 1u);
  EXPECT_NE(found.warnings[0].find("mark no part of its surface and are not used"), std::string::npos);
  EXPECT_NE(found.messages.back().find("no attachment area"), std::string::npos);
}

TEST(AttachmentAreas, WithoutLandmarksTheLinesEndsNextToABoneMarkTheAreas)
{
  const Case c;
  const md::FoundAttachments found =
    md::FindAttachments(c.muscleNames, c.muscles, c.lines, c.boneNames, c.bones, {}, true);
  ASSERT_EQ(found.areas[0].size(), 2u);
  EXPECT_EQ(found.areas[0][0].bone, "pelvis_bone");
  EXPECT_EQ(found.areas[0][1].bone, "femur");
  for (Eigen::Index i : found.areas[0][0].points)
  {
    EXPECT_GT(c.muscles[0].points(i, 2), 24.0); // the top, next to the pelvis
  }
  for (Eigen::Index i : found.areas[0][1].points)
  {
    EXPECT_LT(c.muscles[0].points(i, 2), 16.0);
  }
  EXPECT_NE(found.messages[0].find("the first point of action line 1 on 'pelvis_bone'"), std::string::npos)
    << found.messages[0];
  // Not asked for: none.
  EXPECT_TRUE(md::FindAttachments(c.muscleNames, c.muscles, c.lines, c.boneNames, c.bones, {}, false).areas[0].empty());
}
