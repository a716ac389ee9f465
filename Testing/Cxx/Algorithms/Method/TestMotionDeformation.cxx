// SPDX-License-Identifier: BSD-3-Clause
// MotionDeformation (Filters/Algorithms/Method/MotionDeformation.h): the phantom through a flexion sweep, each
// frame from the one before.
#include "AnatomyMeasures.h"
#include "MotionFrames.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace
{
/// The phantom's rest pose as a motion's input, and its poses at `degrees`.
struct PhantomSweep
{
  std::vector<md::MotionDeformation::Muscle> muscles;
  std::vector<md::MotionDeformation::Bone> bones;
  std::vector<md::MotionPose> poses;
  std::vector<MotionCase> cases;
  explicit PhantomSweep(const std::vector<double>& degrees)
  {
    for (double d : degrees)
    {
      md::PhantomParameters parameters;
      parameters.flexionDegrees = d;
      parameters.resolution = 16;
      const md::Phantom phantom = md::BuildPhantom(parameters);
      if (this->muscles.empty())
      {
        for (const md::PhantomMuscle& m : phantom.muscles)
        {
          this->muscles.push_back({ m.name, m.rest, m.actionLinesRest });
        }
        for (const md::PhantomBone& b : phantom.bones)
        {
          this->bones.push_back({ b.name, b.rest });
        }
      }
      md::MotionPose pose;
      for (const md::PhantomBone& b : phantom.bones)
      {
        pose.bones.push_back(b.currentPoints);
      }
      for (size_t m = 0; m < phantom.muscles.size(); ++m)
      {
        pose.lines.emplace_back();
        for (size_t l = 0; l < phantom.muscles[m].actionLinesCurrent.size(); ++l)
        {
          pose.lines.back().push_back(
            md::AtRestParameters(this->muscles[m].restLines[l], phantom.muscles[m].actionLinesCurrent[l]));
        }
      }
      this->poses.push_back(std::move(pose));
      this->cases.push_back(PhantomMotion(d, 16));
    }
  }
};
}

TEST(MotionDeformation, AFrameIsTheSameHoweverItIsReached)
{
  const PhantomSweep sweep({ 5, 10, 15, 20 });
  md::InterpolationParameters parameters;
  md::MotionDeformation a(sweep.muscles, sweep.bones, parameters);
  std::vector<md::MotionFrameResult> frames;
  std::shared_ptr<const md::MotionDeformation::State> atOne;
  for (size_t k = 0; k < sweep.poses.size(); ++k)
  {
    frames.push_back(a.Advance(sweep.poses[k]));
    if (k == 1)
    {
      atOne = a.Save();
    }
  }
  // Another object, and the first one resumed from frame 1: the same bits.
  md::MotionDeformation b(sweep.muscles, sweep.bones, parameters);
  b.Advance(sweep.poses[0]);
  b.Advance(sweep.poses[1]);
  const md::MotionFrameResult again = b.Advance(sweep.poses[2]);
  a.Resume(atOne);
  const md::MotionFrameResult resumed = a.Advance(sweep.poses[2]);
  a.Resume(nullptr); // the rest pose
  const md::MotionFrameResult first = a.Advance(sweep.poses[0]);
  for (size_t m = 0; m < sweep.muscles.size(); ++m)
  {
    EXPECT_EQ((again.points[m] - frames[2].points[m]).cwiseAbs().maxCoeff(), 0.0) << sweep.muscles[m].name;
    EXPECT_EQ((resumed.points[m] - frames[2].points[m]).cwiseAbs().maxCoeff(), 0.0) << sweep.muscles[m].name;
    EXPECT_EQ((first.points[m] - frames[0].points[m]).cwiseAbs().maxCoeff(), 0.0) << sweep.muscles[m].name;
  }
  EXPECT_EQ(a.FramesAdvanced(), 6);
}

TEST(MotionDeformation, EveryFrameIsSoundAndTheLastIsNearTheInterpolationMethodsAnswer)
{
  const PhantomSweep sweep({ 0, 5, 10, 15, 20, 25, 30 });
  md::InterpolationParameters parameters;
  md::MotionDeformation motion(sweep.muscles, sweep.bones, parameters);
  std::vector<md::MotionFrameResult> frames;
  for (const md::MotionPose& pose : sweep.poses)
  {
    frames.push_back(motion.Advance(pose));
    for (size_t m = 0; m < sweep.muscles.size(); ++m)
    {
      const md::MuscleStepMeasures& s = frames.back().measures[m];
      EXPECT_LT(std::abs(s.volumeChangePercent), 1e-4) << sweep.muscles[m].name;
      EXPECT_EQ(s.newBonePenetrationCount, 0) << sweep.muscles[m].name;
      EXPECT_TRUE(s.converged) << sweep.muscles[m].name;
      EXPECT_TRUE(frames.back().points[m].allFinite());
    }
  }
  EXPECT_EQ(frames[0].steps, 0); // flexion 0 is the rest pose: nothing moves
  for (size_t k = 2; k < frames.size(); ++k)
  {
    const double driven = md::LargestSecondDifference(sweep.poses[k - 2], sweep.poses[k - 1], sweep.poses[k]);
    for (size_t m = 0; m < sweep.muscles.size(); ++m)
    {
      const double second =
        md::LargestSecondDifference(frames[k - 2].points[m], frames[k - 1].points[m], frames[k].points[m]);
      EXPECT_LE(second, 3.0 * driven) << sweep.muscles[m].name << " at frame " << k; // measured up to 1.5 times
    }
  }
  // The interpolation method straight from the rest pose to 30 degrees, with the same lines: the
  // same muscles where nothing presses on them (without contact the answer is that of the last
  // pose, not of the way there).
  std::vector<md::MuscleMotion> muscles;
  for (size_t m = 0; m < sweep.muscles.size(); ++m)
  {
    muscles.push_back({ sweep.muscles[m].name, sweep.muscles[m].rest, {} });
    for (size_t l = 0; l < sweep.muscles[m].restLines.size(); ++l)
    {
      muscles.back().lines.push_back({ sweep.muscles[m].restLines[l], sweep.poses.back().lines[m][l] });
    }
  }
  const md::InterpolationResult direct = md::DeformByInterpolation(muscles, sweep.cases.back().bones, parameters);
  for (size_t m = 0; m < sweep.muscles.size(); ++m)
  {
    const md::Points difference = direct.points.back()[m] - frames.back().points[m];
    const double largest = difference.rowwise().norm().maxCoeff();
    std::printf("[ measured ] %s: %.4f mm at most from the interpolation method's answer\n",
      sweep.muscles[m].name.c_str(), largest);
    // Measured: 0 for the iliopsoas and the gluteus maximus, 0.86 mm for the rectus femoris, which
    // the femur sweeps into (the contact's answer depends a little on the way: the method itself
    // at N = 12 against N = 4 is 0.70 mm apart).
    EXPECT_LT(largest, 1.5) << sweep.muscles[m].name;
  }
}

TEST(MotionDeformation, APoseThatDoesNotFitIsRefusedAndTheMotionStaysWhereItWas)
{
  const PhantomSweep sweep({ 10, 20 });
  md::MotionDeformation motion(sweep.muscles, sweep.bones, md::InterpolationParameters{});
  const md::MotionFrameResult first = motion.Advance(sweep.poses[0]);
  md::MotionPose bad = sweep.poses[1];
  bad.bones[1].conservativeResize(bad.bones[1].rows() - 1, 3);
  try
  {
    motion.Advance(bad);
    FAIL() << "a bone with a point fewer was taken";
  }
  catch (const md::InputError& e)
  {
    EXPECT_NE(std::string(e.what()).find("bone '" + sweep.bones[1].name + "'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("must keep its points"), std::string::npos) << e.what();
  }
  bad = sweep.poses[1];
  bad.lines[0].pop_back();
  EXPECT_THROW(motion.Advance(bad), md::InputError);
  EXPECT_EQ(motion.FramesAdvanced(), 1);
  md::MotionDeformation again(sweep.muscles, sweep.bones, md::InterpolationParameters{});
  again.Advance(sweep.poses[0]);
  const md::MotionFrameResult a = motion.Advance(sweep.poses[1]);
  const md::MotionFrameResult b = again.Advance(sweep.poses[1]);
  EXPECT_EQ((a.points[0] - b.points[0]).cwiseAbs().maxCoeff(), 0.0);
}

TEST(MotionDeformation, AMuscleGivenAsABoneTooIsLeftOutAndTheOthersGoOn)
{
  // Every point of the muscle on the bone's surface: inside or out by rounding, so the answer
  // would depend on where the input sits. The interpolation method leaves it out; so does a motion.
  PhantomSweep sweep({ 10, 20 });
  std::vector<md::MotionDeformation::Bone> bones = sweep.bones;
  bones.push_back({ "MuscleBone", sweep.muscles[0].rest });
  md::MotionDeformation motion(sweep.muscles, bones, md::InterpolationParameters{});
  ASSERT_EQ(motion.Failures().size(), sweep.muscles.size());
  EXPECT_NE(motion.Failures()[0].find("lies in bone 'MuscleBone' in the rest pose"), std::string::npos)
    << motion.Failures()[0];
  for (size_t m = 1; m < sweep.muscles.size(); ++m)
  {
    EXPECT_EQ(motion.Failures()[m], "") << m;
  }
  for (md::MotionPose pose : sweep.poses)
  {
    pose.bones.push_back(sweep.muscles[0].rest.points); // the muscle-bone stays where it was
    const md::MotionFrameResult frame = motion.Advance(pose);
    EXPECT_EQ(frame.points[0].rows(), 0);
    EXPECT_GT(frame.points[1].rows(), 0);
  }
}

TEST(MotionDeformation, OnTheHipEveryFrameOfBothMotionsIsSound)
{
  for (const std::string motion : { "hip_flexion", "hip_adduction" })
  {
    MotionFrames frames;
    if (!LhdlFrames("", motion, -1, frames))
    {
      GTEST_SKIP() << "the LHDL data (lhdl_hip_r) was not found";
    }
    md::MotionDeformation deformation(frames.muscles, frames.bones, md::InterpolationParameters{});
    std::vector<md::MotionFrameResult> results;
    double largestRatio = 0;
    for (size_t k = 0; k < frames.poses.size(); ++k)
    {
      results.push_back(deformation.Advance(frames.poses[k]));
      for (size_t m = 0; m < frames.muscles.size(); ++m)
      {
        const md::MuscleStepMeasures& s = results[k].measures[m];
        EXPECT_LT(std::abs(s.volumeChangePercent), 1e-4) << motion << " frame " << k << " " << frames.muscles[m].name;
        EXPECT_LE(s.maxNewBonePenetrationDepth, 0.5) << motion << " frame " << k << " " << frames.muscles[m].name;
        EXPECT_TRUE(s.converged) << motion << " frame " << k << " " << frames.muscles[m].name;
        EXPECT_TRUE(results[k].points[m].allFinite()) << motion << " frame " << k;
        if (k >= 2)
        {
          const double driven = md::LargestSecondDifference(frames.poses[k - 2], frames.poses[k - 1], frames.poses[k]);
          largestRatio = std::max(largestRatio,
            md::LargestSecondDifference(results[k - 2].points[m], results[k - 1].points[m], results[k].points[m]) /
              driven);
        }
      }
    }
    // Measured: 1.96 (hip_flexion) and 3.01 (hip_adduction). Each frame's settle starts with the
    // last frame's contacts (SettleMotion::carryContacts); started with none, the iliacus and psoas
    // pressed together jumped by 4.5 mm at two frames of hip_adduction (8.9) and the iliacus by
    // 3.7 mm at hip_flexion's frame 35 (7.3), each to another equilibrium of their contact.
    std::printf("[ measured ] %s: largest smoothness ratio %.2f\n", motion.c_str(), largestRatio);
    EXPECT_LE(largestRatio, 4.0) << motion;
    if (motion == "hip_flexion")
    {
      // Frame 35 (60 degrees) against the interpolation method from the rest pose with the same lines.
      std::vector<md::MuscleMotion> same;
      for (size_t m = 0; m < frames.muscles.size(); ++m)
      {
        same.push_back({ frames.muscles[m].name, frames.muscles[m].rest, {} });
        for (size_t l = 0; l < frames.muscles[m].restLines.size(); ++l)
        {
          same.back().lines.push_back({ frames.muscles[m].restLines[l], frames.poses[35].lines[m][l] });
        }
      }
      const md::InterpolationResult direct =
        md::DeformByInterpolation(same, frames.cases[35].bones, md::InterpolationParameters{});
      for (size_t m = 0; m < frames.muscles.size(); ++m)
      {
        // Measured: 0.00 for the glutei, 0.40 mm for the psoas, 7.26 mm for the iliacus: the
        // motion's iliacus keeps the contacts it had through the frames since its path point went
        // (frame 33), the method from the rest pose finds another equilibrium against the iliac
        // bone and the psoas (the same muscles' answer depends on the way to it, as contact does).
        const double largest = (direct.points.back()[m] - results[35].points[m]).rowwise().norm().maxCoeff();
        std::printf("[ measured ] frame 35, %s: %.2f mm from the interpolation method's answer\n",
          frames.muscles[m].name.c_str(), largest);
        EXPECT_LT(largest, frames.muscles[m].name == "iliacus_r" ? 10.0 : 1.0) << frames.muscles[m].name;
      }
    }
  }
}

namespace
{
/// `motion` (LHDL) on the exact input and with every coordinate of the bones and muscles moved by
/// at most 1e-7 of itself (each of `seeds`): the surfaces at every frame within issue 13's 0.01 mm.
void ExpectNoRoundingNoise(const char* motion, const std::vector<int>& seeds)
{
  auto run = [](const char* motion, int seed, std::vector<std::vector<md::Points>>& points) {
    MotionFrames frames;
    if (!LhdlFrames("", motion, seed, frames))
    {
      return false;
    }
    md::InterpolationParameters parameters;
    parameters.numberOfSteps = 0; // the first frame in automatic steps, as the filter and BenchmarkMotion
    md::MotionDeformation deformation(frames.muscles, frames.bones, parameters);
    for (const md::MotionPose& pose : frames.poses)
    {
      points.push_back(deformation.Advance(pose).points);
    }
    return true;
  };
  std::vector<std::vector<md::Points>> exact;
  if (!run(motion, -1, exact))
  {
    GTEST_SKIP() << "the LHDL data (lhdl_hip_r) was not found";
  }
  for (const int seed : seeds)
  {
    std::vector<std::vector<md::Points>> perturbed;
    ASSERT_TRUE(run(motion, seed, perturbed));
    ASSERT_EQ(perturbed.size(), exact.size());
    double largest = 0;
    for (size_t k = 0; k < exact.size(); ++k)
    {
      for (size_t m = 0; m < exact[k].size(); ++m)
      {
        const double distance = (perturbed[k][m] - exact[k][m]).rowwise().norm().maxCoeff();
        largest = std::max(largest, distance);
        EXPECT_LT(distance, 0.01) << motion << " seed " << seed << " frame " << k << " muscle " << m;
      }
    }
    std::printf(
      "[ measured ] %s seed %d: largest distance from the exact input's surfaces %.6f mm\n", motion, seed, largest);
  }
}
}

TEST(MotionDeformation, OnTheHipAMotionDependsOnNoRoundingNoise)
{
  // hip_flexion and hip_adduction on the exact input and with every coordinate of the bones and
  // muscles moved by at most 1e-7 of itself (hip_flexion seeds 2, 5 and 6 here, hip_adduction seed 1
  // in the test below: the seeds that showed the rules below wanting; BenchmarkMotion for more):
  // the surfaces at every frame, within issue 13's 0.01 mm. Three rules hold that:
  // - A motion's step is settled in parts whose minimum moves at most largestCarriedMove, each
  //   carrying the last one's contacts (SettleParts). At hip_flexion frame 33 the iliacus's path
  //   point goes and its line jumps by 19 mm; settled from no contacts there, it swung between
  //   contacts with the iliac bone for 25 iterations, and where it came to rest moved by 0.17 mm
  //   with seed 2 (and by 1.1 mm when whether carried contacts settled within 30 iterations
  //   decided which of two answers it took).
  // - A settle whose steps grow is not extended as a creep (SteadyStep): at hip_adduction frame 13
  //   that extension moved the iliacus by 0.9 mm at once, and its answer by 0.12 mm with seed 1.
  // - Through a motion, a point inside a bone that held it goes out through the triangles that held
  //   it, not by its nearest (SurfaceSettle's ContactSearch): at hip_flexion frame 23 the start
  //   took a gluteus maximus point held on a slightly convex ridge of the iliac bone inside, near
  //   the ridge's bisector, where rounding chose the nearest face, and the face it went out
  //   through chose between two equilibria 0.128 mm apart with seed 5 (applied at the start only,
  //   frame 35 moved by 0.73 mm with seed 6).
  // Measured (Release): every frame within 0.0009 mm on seeds 1-7 of hip_flexion and 1-6 of
  // hip_adduction (BenchmarkMotion).
  ExpectNoRoundingNoise("hip_flexion", { 2, 5, 6 });
}

TEST(MotionDeformation, OnTheHipAdductionDependsOnNoRoundingNoiseEither)
{
  // Its own test, for the time each takes (a perturbed run loads and perturbs the whole motion).
  ExpectNoRoundingNoise("hip_adduction", { 1 });
}

TEST(MotionDeformation, AnAttachmentAreaMovesRigidlyWithItsBone)
{
  // The phantom's iliopsoas attached to the femur where its action line ends (its surface points
  // within 0.15 of its length of the line's last point), through a sweep to 30 degrees: the
  // area goes where the femur carries it, the rest of the muscle as before (volume, contact).
  PhantomSweep sweep({ 0, 10, 20, 30 });
  const size_t femur = 1, muscle = 0;
  ASSERT_EQ(sweep.bones[femur].name, "Femur");
  ASSERT_EQ(sweep.muscles[muscle].name, "Iliopsoas");
  const md::Points& rest = sweep.muscles[muscle].rest.points;
  const md::Points& line = sweep.muscles[muscle].restLines[0];
  const Eigen::RowVector3d end = line.row(line.rows() - 1);
  const double reach = 0.15 * (line.row(0) - end).norm();
  md::Attachment area;
  area.bone = "Femur";
  area.boneIndex = static_cast<Eigen::Index>(femur);
  for (Eigen::Index i = 0; i < rest.rows(); ++i)
  {
    if ((rest.row(i) - end).norm() < reach)
    {
      area.points.push_back(i);
    }
  }
  const md::Points& bone = sweep.bones[femur].rest.points;
  for (Eigen::Index j = 0; j < bone.rows(); j += std::max<Eigen::Index>(1, bone.rows() / 64))
  {
    area.anchors.push_back(j);
  }
  area.anchorsRest.resize(static_cast<Eigen::Index>(area.anchors.size()), 3);
  for (size_t k = 0; k < area.anchors.size(); ++k)
  {
    area.anchorsRest.row(static_cast<Eigen::Index>(k)) = bone.row(area.anchors[k]);
  }
  ASSERT_GT(area.points.size(), 10u);
  sweep.muscles[muscle].attachments = { area };
  md::MotionDeformation deformation(sweep.muscles, sweep.bones, md::InterpolationParameters{});
  const double size = (rest.colwise().maxCoeff() - rest.colwise().minCoeff()).norm();
  double worstAttached = 0, worstFree = 0;
  for (size_t k = 0; k < sweep.poses.size(); ++k)
  {
    const md::MotionFrameResult r = deformation.Advance(sweep.poses[k]);
    const md::RigidTransform carried = md::FitRigidTransform(bone, sweep.poses[k].bones[femur]).transform;
    for (Eigen::Index i : area.points)
    {
      const double slip = (r.points[muscle].row(i).transpose() - carried.Apply(Eigen::Vector3d(rest.row(i)))).norm();
      worstAttached = std::max(worstAttached, slip);
    }
    for (Eigen::Index i = 0; i < rest.rows(); ++i)
    {
      worstFree =
        std::max(worstFree, (r.points[muscle].row(i).transpose() - carried.Apply(Eigen::Vector3d(rest.row(i)))).norm());
    }
    EXPECT_LT(std::abs(r.measures[muscle].volumeChangePercent), 1e-4) << k;
    EXPECT_TRUE(r.measures[muscle].converged) << k;
    // Not asserted: flipped triangles. The area here is the muscle's whole end, chosen by hand,
    // not the surface against the bone (the phantom's muscles end clear of their bones); turned
    // with the femur, a few triangles at its rim turn over (6 at 30 degrees). FindAttachments
    // takes only the surface next to the bone for this reason.
  }
  std::printf("[ measured ] attached points' largest slip %.2e of the muscle's size; the muscle's farthest point "
              "from the femur's motion %.2f\n",
    worstAttached / size, worstFree / size);
  EXPECT_LT(worstAttached, 2e-3 * size);
  EXPECT_GT(worstFree, 0.05 * size); // the rest of it does not move with the femur
}

TEST(MotionDeformation, OnTheHipTheMusclesStayOnTheirLandmarks)
{
  // Issue 48: the data set's own 189 attachment landmarks on the pelvis and the femur, each
  // followed by the muscle surface point next to it: at most 1 mm from where its bone carries it,
  // at every frame of both motions (without the areas: up to 38.9 mm).
  const std::vector<md::LandmarkSet> landmarks = LhdlLandmarks();
  for (const std::string motion : { "hip_flexion", "hip_adduction" })
  {
    MotionFrames frames;
    if (landmarks.empty() || !LhdlFrames("", motion, -1, frames))
    {
      GTEST_SKIP() << "the LHDL data (lhdl_hip_r) was not found";
    }
    const md::FoundAttachments found = AttachMotionMuscles(frames, landmarks, true);
    ASSERT_EQ(found.warnings.size(), 1u); // the iliotibial tract's, on no bone of the case
    std::vector<std::string> muscleNames, boneNames;
    std::vector<md::TriangleMesh> muscles;
    std::vector<md::Points> boneRest;
    for (const md::MotionDeformation::Muscle& m : frames.muscles)
    {
      ASSERT_FALSE(m.attachments.empty()) << m.name;
      muscleNames.push_back(m.name);
      muscles.push_back(m.rest);
    }
    for (const md::MotionDeformation::Bone& b : frames.bones)
    {
      boneNames.push_back(b.name);
      boneRest.push_back(b.rest.points);
    }
    const std::vector<SlipProbe> probes = LhdlSlipProbes(landmarks, muscleNames, muscles, boneNames);
    ASSERT_EQ(probes.size(), 189u);
    md::InterpolationParameters parameters;
    parameters.numberOfSteps = 0;
    md::MotionDeformation deformation(frames.muscles, frames.bones, parameters);
    double worst = 0;
    for (size_t k = 0; k < frames.poses.size(); ++k)
    {
      const md::MotionFrameResult r = deformation.Advance(frames.poses[k]);
      const std::vector<double> slips = Slips(probes, muscles, r.points, boneRest, frames.poses[k].bones);
      for (size_t p = 0; p < probes.size(); ++p)
      {
        EXPECT_LE(slips[p], 1.0) << motion << " frame " << k << " " << probes[p].muscle << " point " << probes[p].point;
        worst = std::max(worst, slips[p]);
      }
      for (size_t m = 0; m < frames.muscles.size(); ++m)
      {
        const md::MuscleStepMeasures& s = r.measures[m];
        EXPECT_LT(std::abs(s.volumeChangePercent), 1e-4) << motion << " frame " << k << " " << muscleNames[m];
        EXPECT_LE(s.maxNewBonePenetrationDepth, 0.5) << motion << " frame " << k << " " << muscleNames[m];
        EXPECT_TRUE(s.converged) << motion << " frame " << k << " " << muscleNames[m];
      }
    }
    std::printf("[ measured ] %s: largest slip at a landmark %.2f mm\n", motion.c_str(), worst);
  }
}
