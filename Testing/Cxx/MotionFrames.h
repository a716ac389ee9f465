// SPDX-License-Identifier: BSD-3-Clause
// Motions as MotionDeformation's input (Filters/Algorithms/Method/MotionDeformation.h): the LHDL right hip
// through every frame of one of its motions (RealData.h), or the phantom through a flexion sweep;
// each frame also as the interpolation method's input. Shared by the tests and the benchmark.
#pragma once

#include "Method/MotionDeformation.h"
#include "RealData.h"

#include <string>
#include <vector>

/// The frames of a motion: the rest pose as the motion's input and each frame's pose.
struct MotionFrames
{
  std::string name;
  std::vector<md::MotionDeformation::Muscle> muscles;
  std::vector<md::MotionDeformation::Bone> bones;
  std::vector<md::MotionPose> poses;
  std::vector<MotionCase> cases; ///< each frame as the interpolation method's input
  std::vector<double> flexion;
};

inline md::MotionPose PoseOf(const MotionCase& c, const std::vector<std::vector<md::Points>>& rawCurrent,
  const std::vector<md::MotionDeformation::Muscle>& muscles)
{
  md::MotionPose pose;
  for (const md::BoneMotion& b : c.bones)
  {
    pose.bones.push_back(b.current);
  }
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    pose.lines.emplace_back();
    for (size_t l = 0; l < muscles[m].restLines.size(); ++l)
    {
      pose.lines.back().push_back(md::AtRestParameters(muscles[m].restLines[l], rawCurrent[m][l]));
    }
  }
  return pose;
}

inline bool LhdlFrames(const std::string& folder, const std::string& motion, int seed, MotionFrames& out)
{
  out.name = "LHDL " + motion;
  PerturbedArrays kept; // the frames share most of their arrays
  for (int k = 0;; ++k)
  {
    LhdlCase lhdl;
    if (!LoadLhdlCase(motion, k, lhdl, folder))
    {
      return k > 0;
    }
    MotionCase c;
    c.name = out.name;
    std::vector<std::vector<md::Points>> rawCurrent;
    for (const LhdlCase::Muscle& muscle : lhdl.muscles)
    {
      c.muscles.push_back({ muscle.name, muscle.surface, MatchLines(muscle.linesRest, muscle.linesCurrent) });
      rawCurrent.push_back(muscle.linesCurrent);
    }
    for (size_t b = 0; b < lhdl.boneNames.size(); ++b)
    {
      c.bones.push_back({ lhdl.boneNames[b], lhdl.bonesRest[b], lhdl.bonesCurrent[b].points });
    }
    if (seed >= 0)
    {
      c = Perturbed(c, seed, false, &kept); // the bones and the surfaces; the raw lines as they are
    }
    if (k == 0)
    {
      for (size_t m = 0; m < lhdl.muscles.size(); ++m)
      {
        out.muscles.push_back({ lhdl.muscles[m].name, c.muscles[m].muscle, lhdl.muscles[m].linesRest });
      }
      for (const md::BoneMotion& b : c.bones)
      {
        out.bones.push_back({ b.name, b.rest });
      }
    }
    out.poses.push_back(PoseOf(c, rawCurrent, out.muscles));
    out.flexion.push_back(lhdl.frame.hipFlexion);
    out.cases.push_back(std::move(c));
  }
}

inline void PhantomFrames(MotionFrames& out, int lastDegrees = 60)
{
  out.name = "phantom flexion 0-" + std::to_string(lastDegrees) + " by 2 degrees";
  for (int degrees = 0; degrees <= lastDegrees; degrees += 2)
  {
    MotionCase c = PhantomMotion(degrees);
    std::vector<std::vector<md::Points>> rawCurrent;
    md::PhantomParameters parameters;
    parameters.flexionDegrees = degrees;
    const md::Phantom phantom = md::BuildPhantom(parameters);
    if (out.muscles.empty())
    {
      for (const md::PhantomMuscle& m : phantom.muscles)
      {
        out.muscles.push_back({ m.name, m.rest, m.actionLinesRest });
      }
      for (const md::BoneMotion& b : c.bones)
      {
        out.bones.push_back({ b.name, b.rest });
      }
    }
    for (const md::PhantomMuscle& m : phantom.muscles)
    {
      rawCurrent.push_back(m.actionLinesCurrent);
    }
    out.poses.push_back(PoseOf(c, rawCurrent, out.muscles));
    out.flexion.push_back(degrees);
    out.cases.push_back(std::move(c));
  }
}
