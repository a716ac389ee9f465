// SPDX-License-Identifier: BSD-3-Clause
// Paths over the bones (Motion/PathOverBones.h) on the LHDL hip: the eight paths of the four
// muscles kept out of the scanned iliac bone, sacrum and femur at every frame of a motion, each
// frame started from the one before. Per frame: the time of the eight paths (the bones' trees
// moved to the frame beforehand, as a motion filter keeps them), the paths that run over a bone
// (how much longer than straight, how many points on which bone) and the largest move of a path
// point since the frame before. Then the spread under input noise: the motion again with every
// coordinate of the bones and the paths moved by up to 1e-7 of itself (three draws), the largest
// difference of a path point and of a path's length from the exact input's, naming each path and
// frame where a point moves by more than 0.001 mm (and the bone it is held on). Prints figures;
// asserts nothing.
//
//   BenchmarkPathsOverBones [data folder] [motion: hip_flexion | hip_adduction] [points per segment]
#include "Motion/PathOverBones.h"
#include "RealData.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace
{
/// Every coordinate moved by up to 1e-7 of itself, the move a function of the value and the seed
/// (a splitmix64 hash of both: equal coordinates move alike, as a scan's duplicate points must).
void Perturb(md::Points& points, int seed)
{
  for (Eigen::Index i = 0; i < points.size(); ++i)
  {
    double& x = points.data()[i];
    std::uint64_t z = 0;
    std::memcpy(&z, &x, sizeof z);
    z += 0x9e3779b97f4a7c15ULL * static_cast<std::uint64_t>(seed);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    x *= 1 + 1e-7 * (2.0 * static_cast<double>(z >> 11) / 9007199254740992.0 - 1.0);
  }
}

/// The motion's paths over the bones at every frame ([frame][muscle][path]), each frame from the
/// one before; seed > 0: the input perturbed. `report`: print each frame and the times.
std::vector<std::vector<std::vector<md::PathOverBonesResult>>> Run(const std::string& folder, const std::string& motion,
  const md::PathOverBonesParameters& parameters, int seed, bool report)
{
  std::vector<std::vector<std::vector<md::PathOverBonesResult>>> frames;
  std::vector<md::TriangleTree> rest;
  std::vector<std::vector<md::Points>> last;
  std::vector<double> times;
  double largestMove = 0;
  for (int k = 0;; ++k)
  {
    LhdlCase lhdl;
    if (!LoadLhdlCase(motion, k, lhdl, folder))
    {
      break;
    }
    if (seed > 0)
    {
      for (size_t b = 0; b < lhdl.bonesRest.size(); ++b)
      {
        Perturb(lhdl.bonesRest[b].points, seed);
        Perturb(lhdl.bonesCurrent[b].points, seed);
      }
      for (LhdlCase::Muscle& muscle : lhdl.muscles)
      {
        for (md::Points& line : muscle.linesCurrent)
        {
          Perturb(line, seed);
        }
      }
    }
    if (rest.empty())
    {
      for (const md::TriangleMesh& bone : lhdl.bonesRest)
      {
        rest.emplace_back(bone);
      }
    }
    std::vector<md::TriangleTree> now = rest;
    std::vector<const md::TriangleTree*> bones;
    for (size_t b = 0; b < now.size(); ++b)
    {
      now[b].Refit(lhdl.bonesCurrent[b].points);
      bones.push_back(&now[b]);
    }
    std::vector<std::vector<md::Points>> paths(lhdl.muscles.size());
    std::string over;
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::vector<md::PathOverBonesResult>> results(lhdl.muscles.size());
    for (size_t m = 0; m < lhdl.muscles.size(); ++m)
    {
      for (size_t l = 0; l < lhdl.muscles[m].linesCurrent.size(); ++l)
      {
        const md::Points* from = last.empty() ? nullptr : &last[m][l];
        results[m].push_back(md::PathOverBones(lhdl.muscles[m].linesCurrent[l], bones, parameters, from));
      }
    }
    times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    double move = 0;
    for (size_t m = 0; m < results.size(); ++m)
    {
      for (size_t l = 0; l < results[m].size(); ++l)
      {
        const md::PathOverBonesResult& r = results[m][l];
        paths[m].push_back(r.points);
        if (!last.empty() && last[m][l].rows() == r.points.rows())
        {
          move = std::max(move, (r.points - last[m][l]).rowwise().norm().maxCoeff());
        }
        if (r.length > r.straightLength + 1e-6 || !r.converged)
        {
          char text[160];
          std::snprintf(text, sizeof text, "  %s[%zu] +%.2f mm (%d rounds%s; points on bones %d %d %d)",
            lhdl.muscles[m].name.c_str(), l, r.length - r.straightLength, r.iterations,
            r.converged ? "" : ", not settled", r.pointsOnBone[0], r.pointsOnBone[1], r.pointsOnBone[2]);
          over += text;
        }
      }
    }
    largestMove = std::max(largestMove, move);
    frames.push_back(results);
    if (!report)
    {
      last = paths;
      continue;
    }
    std::printf("frame %2d (flexion %5.1f, adduction %5.1f deg): %5.2f ms, largest move %.2f mm%s\n", k,
      lhdl.frame.hipFlexion, lhdl.frame.hipAdduction, times.back(), move, over.c_str());
    last = paths;
  }
  if (!report || times.empty())
  {
    return frames;
  }
  std::vector<double> sorted = times;
  std::sort(sorted.begin(), sorted.end());
  double sum = 0;
  for (double t : times)
  {
    sum += t;
  }
  std::printf("%s, %d points per segment: %zu frames, eight paths %.2f ms a frame on average (median %.2f, "
              "largest %.2f); largest move of a path point between frames %.2f mm\n",
    motion.c_str(), parameters.pointsPerSegment, times.size(), sum / static_cast<double>(times.size()),
    sorted[sorted.size() / 2], sorted.back(), largestMove);
  return frames;
}
}

int main(int argc, char** argv)
{
  const std::string folder = argc > 1 ? argv[1] : "";
  const std::string motion = argc > 2 ? argv[2] : "hip_flexion";
  md::PathOverBonesParameters parameters;
  if (argc > 3)
  {
    parameters.pointsPerSegment = std::stoi(argv[3]);
  }
  const auto exact = Run(folder, motion, parameters, 0, true);
  if (exact.empty())
  {
    std::printf("LHDL data not found: nothing measured\n");
    return 0;
  }
  double points = 0, lengths = 0;
  for (int seed = 1; seed <= 3; ++seed)
  {
    const auto noisy = Run(folder, motion, parameters, seed, false);
    for (size_t k = 0; k < exact.size() && k < noisy.size(); ++k)
    {
      for (size_t m = 0; m < exact[k].size(); ++m)
      {
        for (size_t l = 0; l < exact[k][m].size(); ++l)
        {
          const md::PathOverBonesResult &a = exact[k][m][l], &b = noisy[k][m][l];
          lengths = std::max(lengths, std::abs(a.length - b.length));
          if (a.points.rows() == b.points.rows())
          {
            points = std::max(points, (a.points - b.points).rowwise().norm().maxCoeff());
            Eigen::Index at = 0;
            const double d = (a.points - b.points).rowwise().norm().maxCoeff(&at);
            if (d > 1e-3)
            {
              std::printf("draw %d, frame %zu, muscle %zu path %zu, point %ld: moves %.3g mm (held on bone %d / %d)\n",
                seed, k, m, l, static_cast<long>(at), d, a.boneOfPoint[static_cast<size_t>(at)],
                b.boneOfPoint[static_cast<size_t>(at)]);
            }
          }
        }
      }
    }
  }
  std::printf("1e-7 input noise (3 draws): a path point moves by up to %.2g mm, a path's length by up to %.2g mm\n",
    points, lengths);
  return 0;
}
