// The inputs of the interpolation method (InterpolatedDeformation.h) for the
// phantom, with its action lines matched as ActionLineMatching does (the LHDL
// right hip: LhdlMotion in RealData.h). Shared by the tests and the benchmark.
#pragma once

#include "ActionLineMatching.h"
#include "InterpolatedDeformation.h"
#include "Phantom.h"

#include <string>
#include <vector>

struct MotionCase
{
  std::string name;
  std::vector<md::MuscleMotion> muscles;
  std::vector<md::BoneMotion> bones;
};

inline std::vector<md::MatchedLine> MatchLines(
  const std::vector<md::Points>& rest, const std::vector<md::Points>& current, double tolerance = 0.01)
{
  std::vector<md::MatchedLine> lines;
  for (size_t l = 0; l < rest.size() && l < current.size(); ++l)
  {
    const md::MatchedActionLines matched = md::MatchActionLines(rest[l], current[l], tolerance);
    lines.push_back({ matched.rest, matched.current });
  }
  return lines;
}

inline MotionCase PhantomMotion(double flexionDegrees, int resolution = 24)
{
  md::PhantomParameters parameters;
  parameters.flexionDegrees = flexionDegrees;
  parameters.resolution = resolution;
  const md::Phantom phantom = md::BuildPhantom(parameters);
  MotionCase c;
  c.name = "phantom " + std::to_string(static_cast<int>(flexionDegrees)) + " deg";
  for (const md::PhantomMuscle& muscle : phantom.muscles)
  {
    c.muscles.push_back({ muscle.name, muscle.rest, MatchLines(muscle.actionLinesRest, muscle.actionLinesCurrent) });
  }
  for (const md::PhantomBone& bone : phantom.bones)
  {
    c.bones.push_back({ bone.name, bone.rest, bone.currentPoints });
  }
  return c;
}
