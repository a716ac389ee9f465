// SPDX-License-Identifier: BSD-3-Clause
// What a biomechanist checks of muscles carried through a motion, measured apart from the
// plugin's own choices: the slip at the data set's attachment landmarks (the muscle surface next
// to each landmark against where the landmark's bone carries it) and the largest step of a
// muscle point between two frames against its median. Shared by the tests and the benchmarks.
#pragma once

#include "Anatomy/AttachmentAreas.h"
#include "Geometry/RigidMotion.h"
#include "MotionFrames.h"
#include "RealData.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

/// The LHDL data set's landmarks (lhdl_hip_r/attachment_areas_rp_mm.csv); empty when absent.
inline std::vector<md::LandmarkSet> LhdlLandmarks(const std::string& folder = "")
{
  const std::string path = RealDataFile("lhdl_hip_r/attachment_areas_rp_mm.csv", folder);
  if (path.empty())
  {
    return {};
  }
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  return md::ParseLandmarkTable(text.str(), path);
}

/// FindAttachments for the muscles of `frames` (rest surfaces and lines) on its bones, by
/// `landmarks`, else, with `fromLineEnds`, at their lines' ends; each muscle's areas set.
inline md::FoundAttachments AttachMotionMuscles(
  MotionFrames& frames, const std::vector<md::LandmarkSet>& landmarks, bool fromLineEnds)
{
  std::vector<std::string> muscleNames, boneNames;
  std::vector<md::TriangleMesh> muscles, bones;
  std::vector<std::vector<md::Points>> lines;
  for (const md::MotionDeformation::Muscle& m : frames.muscles)
  {
    muscleNames.push_back(m.name);
    muscles.push_back(m.rest);
    lines.push_back(m.restLines);
  }
  for (const md::MotionDeformation::Bone& b : frames.bones)
  {
    boneNames.push_back(b.name);
    bones.push_back(b.rest);
  }
  md::FoundAttachments found =
    md::FindAttachments(muscleNames, muscles, lines, boneNames, bones, landmarks, fromLineEnds);
  for (size_t m = 0; m < frames.muscles.size(); ++m)
  {
    frames.muscles[m].attachments = found.areas[m];
  }
  return found;
}

/// One landmark's probe: the rest muscle point nearest to it, and the bone that carries it.
struct SlipProbe
{
  std::string muscle;
  size_t muscleIndex = 0;
  size_t boneIndex = 0;
  Eigen::Index point = 0;
};

/// The probes of the LHDL landmarks on the pelvis and the femur (the data set's own names, mapped
/// here by hand; the iliotibial tract's, on no bone of the case, left out), for `muscles` and
/// `bones` by name.
inline std::vector<SlipProbe> LhdlSlipProbes(const std::vector<md::LandmarkSet>& landmarks,
  const std::vector<std::string>& muscleNames, const std::vector<md::TriangleMesh>& muscles,
  const std::vector<std::string>& boneNames)
{
  const std::map<std::string, std::string> muscleOf = { { "R_Glut_Max", "gluteus_maximus_r" },
    { "R_Glut_Med", "gluteus_medius_r" }, { "R_Iliacus", "iliacus_r" }, { "R_Psoas_maj", "psoas_r" } };
  const std::map<std::string, std::string> boneOf = { { "pelvis", "iliac_r" }, { "femur_r", "femur_r" } };
  std::vector<SlipProbe> probes;
  for (const md::LandmarkSet& set : landmarks)
  {
    if (!muscleOf.count(set.muscle) || !boneOf.count(set.bone))
    {
      continue;
    }
    const auto m = std::find(muscleNames.begin(), muscleNames.end(), muscleOf.at(set.muscle));
    const auto b = std::find(boneNames.begin(), boneNames.end(), boneOf.at(set.bone));
    if (m == muscleNames.end() || b == boneNames.end())
    {
      continue;
    }
    const size_t mi = static_cast<size_t>(m - muscleNames.begin());
    for (Eigen::Index j = 0; j < set.points.rows(); ++j)
    {
      Eigen::Index nearest = 0;
      (muscles[mi].points.rowwise() - set.points.row(j)).rowwise().squaredNorm().minCoeff(&nearest);
      probes.push_back({ *m, mi, static_cast<size_t>(b - boneNames.begin()), nearest });
    }
  }
  return probes;
}

/// Per probe, how far its muscle point (`points[muscle]`, one frame) lies from where its bone
/// (rest `boneRest`, now `boneNow`, fitted rigidly) carries its rest position.
inline std::vector<double> Slips(const std::vector<SlipProbe>& probes, const std::vector<md::TriangleMesh>& restMuscles,
  const std::vector<md::Points>& points, const std::vector<md::Points>& boneRest,
  const std::vector<md::Points>& boneNow)
{
  std::vector<md::RigidTransform> carried;
  for (size_t b = 0; b < boneRest.size(); ++b)
  {
    carried.push_back(md::FitRigidTransform(boneRest[b], boneNow[b]).transform);
  }
  std::vector<double> slips;
  for (const SlipProbe& p : probes)
  {
    const Eigen::Vector3d rest = restMuscles[p.muscleIndex].points.row(p.point).transpose();
    const Eigen::Vector3d now = points[p.muscleIndex].row(p.point).transpose();
    slips.push_back((now - carried[p.boneIndex].Apply(rest)).norm());
  }
  return slips;
}

/// Per muscle, over a motion's frames (`frames[k][m]`): the largest step of any of its points
/// between two frames, against the median over the motion of each transition's largest step.
inline std::vector<double> StepRatios(const std::vector<std::vector<md::Points>>& frames)
{
  std::vector<double> ratios;
  if (frames.size() < 3)
  {
    return ratios;
  }
  for (size_t m = 0; m < frames[0].size(); ++m)
  {
    std::vector<double> steps;
    for (size_t k = 1; k < frames.size(); ++k)
    {
      steps.push_back((frames[k][m] - frames[k - 1][m]).rowwise().norm().maxCoeff());
    }
    std::vector<double> sorted = steps;
    std::sort(sorted.begin(), sorted.end());
    const double median = sorted[sorted.size() / 2];
    ratios.push_back(median > 0 ? sorted.back() / median : 0.0);
  }
  return ratios;
}
