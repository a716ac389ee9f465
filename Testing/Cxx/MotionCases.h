// SPDX-License-Identifier: BSD-3-Clause
// The inputs of the interpolation method (InterpolatedDeformation.h) for the
// phantom, with its action lines matched as ActionLineMatching does (the LHDL
// right hip: LhdlMotion in RealData.h). Shared by the tests and the benchmark.
#pragma once

#include "Method/InterpolatedDeformation.h"
#include "Motion/ActionLineMatching.h"
#include "Phantom/Phantom.h"

#include <functional>
#include <random>
#include <string>
#include <vector>

struct MotionCase
{
  std::string name;
  std::vector<md::MuscleMotion> muscles;
  std::vector<md::BoneMotion> bones;
};

/// The case with every coordinate rounded to float (as VTK pipelines with
/// float points carry them) and, for seed > 0, first moved by a pseudo-random
/// amount of that size (up to 1e-7 of the coordinate). By default the move is
/// a function of the value and the seed, so that equal coordinates stay equal
/// (a scan's duplicate points stay duplicates); with `splitDuplicates` it is a
/// function of the coordinate's place, so that they part by about 1e-7: how
/// much the results depend on such perturbations.
///
/// `kept` (with splitDuplicates false): arrays perturbed before with the same seed, each with its
/// perturbation, which an array equal to one of them takes instead of drawing it again (the same
/// bits: the move is a function of the value and the seed). The frames of a motion share most of
/// their arrays (the muscles, the bones that do not move), and a draw costs microseconds.
struct PerturbedArrays
{
  std::vector<std::pair<md::Points, md::Points>> arrays; // (exact, perturbed)
};
inline MotionCase Perturbed(MotionCase c, int seed, bool splitDuplicates = false, PerturbedArrays* kept = nullptr)
{
  int array = 0;
  auto perturb = [&](md::Points& points) {
    ++array;
    const bool keep = kept && !splitDuplicates;
    if (keep)
    {
      for (const auto& [exact, perturbed] : kept->arrays)
      {
        if (exact.rows() == points.rows() && exact == points)
        {
          points = perturbed;
          return;
        }
      }
    }
    const md::Points exact = keep ? points : md::Points();
    for (Eigen::Index i = 0; i < points.size(); ++i)
    {
      double& x = points.data()[i];
      if (seed > 0)
      {
        const int key = splitDuplicates ? static_cast<int>(i) * 131 + array : static_cast<int>(std::hash<double>{}(x));
        std::seed_seq sequence{ key, seed };
        std::mt19937 random(sequence);
        x *= 1 + 1e-7 * std::uniform_real_distribution<double>(-1.0, 1.0)(random);
      }
      x = static_cast<double>(static_cast<float>(x));
    }
    if (keep)
    {
      kept->arrays.emplace_back(exact, points);
    }
  };
  for (md::MuscleMotion& m : c.muscles)
  {
    perturb(m.muscle.points);
    for (md::MatchedLine& line : m.lines)
    {
      perturb(line.rest);
      perturb(line.current);
    }
  }
  for (md::BoneMotion& b : c.bones)
  {
    perturb(b.rest.points);
    perturb(b.current);
  }
  return c;
}

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
