// SPDX-License-Identifier: BSD-3-Clause
// Muscles through a whole motion in the core (Filters/Algorithms/Method/MotionDeformation.h): the four LHDL
// hip muscles through every frame of hip_flexion or hip_adduction (iliac bone, sacrum and femur),
// or the phantom through a flexion sweep. Per frame: steps, settle iterations, time, the largest
// |VolumeChangePercent|, new bone penetration, flipped triangles, new sharp edges and the
// frame-to-frame smoothness (the largest second difference of a muscle point over three frames,
// and its ratio to the bones' own). At the frame nearest 60 degrees of flexion (hip_flexion frame
// 35), the distance to InterpolatedMuscleDeformation's answer for that pose from the rest pose.
// Prints figures; asserts nothing (see the tests). Last, a checksum of every frame's points and
// measures: a change meant to leave the answer alone (a speed-up, a restructuring) must leave it
// the same on the same machine and build. With a seed (LHDL), the same motion on the exact input
// too, and the largest distance between the two runs' surfaces at any frame. The LHDL muscles'
// slip at the data set's attachment landmarks and their largest step between frames against its
// median (AnatomyMeasures.h), with the muscles attached as `attachments` says: by the data set's
// landmarks, by their action lines' ends, or not at all.
//
//   BenchmarkMotion [data folder] [hip_flexion|hip_adduction|phantom] [seed: -1 none, 0 float, s > 0 noise]
//                   [attachments: landmarks (default) | lines | none]
#include "Anatomy/MuscleFibres.h"
#include "AnatomyMeasures.h"
#include "Common/Fnv1a.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/TriangleTree.h"
#include "MotionFrames.h"
#include "StepChecksum.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

namespace
{
/// The fibres over a motion: their cost a frame, points outside their muscle or inside a bone,
/// and the largest change of a fibre's length between frames against its median.
struct FibreMeasures
{
  explicit FibreMeasures(size_t muscles)
    : outside(muscles, 0)
    , inBone(muscles, 0)
    , lengths(muscles)
  {
  }
  std::vector<std::int64_t> outside, inBone;
  std::vector<std::vector<std::vector<double>>> lengths; ///< [muscle][frame][fibre]
  std::vector<std::vector<md::Points>> points;           ///< [frame][muscle]
  std::vector<double> seconds;                           ///< carrying and lengths, a frame
  long long moved = 0, stuck = 0;                        ///< fibre points kept in, over the motion
  std::vector<md::TriangleTree> restTrees;               ///< the bones' at rest, with distance grids

  void Add(const std::vector<std::unique_ptr<md::MuscleFibres>>& fibres, const std::vector<md::Points>& muscles,
    const std::vector<md::Points>& bonesNow, const std::vector<md::MotionDeformation::Bone>& bones)
  {
    // As the motion filter does: each bone's rest tree (with its distance grid), moved rigidly.
    if (restTrees.empty())
    {
      for (const md::MotionDeformation::Bone& bone : bones)
      {
        restTrees.emplace_back(bone.rest);
        restTrees.back().BuildDistanceGrid();
      }
    }
    std::vector<md::TriangleTree> boneTrees;
    for (size_t b = 0; b < bones.size(); ++b)
    {
      boneTrees.emplace_back(md::TriangleMesh{ bonesNow[b], bones[b].rest.triangles });
    }
    const auto start = std::chrono::steady_clock::now();
    std::vector<md::FibreObstacle> obstacles;
    for (size_t b = 0; b < bones.size(); ++b)
    {
      const auto rigid =
        md::RigidMotionOf(bones[b].rest.points, bonesNow[b], md::kRigidObstacleShare * md::BoxDiagonal(bonesNow[b]));
      obstacles.push_back(rigid ? md::FibreObstacle{ &restTrees[b], *rigid } : md::FibreObstacle{ &boneTrees[b], {} });
    }
    std::vector<md::Points> carried;
    for (size_t m = 0; m < fibres.size(); ++m)
    {
      std::pair<int, int> kept;
      carried.push_back(fibres[m]->At(muscles[m], obstacles, &kept));
      lengths[m].push_back(fibres[m]->Lengths(carried.back()));
      moved += kept.first;
      stuck += kept.second;
    }
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    points.push_back(carried);
    // Outside the muscle: by the winding number (a muscle folded over itself encloses its fold
    // twice); inside a bone: by the parity of rays.
    for (size_t m = 0; m < fibres.size(); ++m)
    {
      outside[m] += md::CountOutside(md::TriangleMesh{ muscles[m], fibres[m]->SurfaceTriangles() }, carried[m], 0.0);
      for (Eigen::Index p = 0; p < carried[m].rows(); ++p)
      {
        const Eigen::Vector3d x = carried[m].row(p).transpose();
        for (const md::TriangleTree& bone : boneTrees)
        {
          inBone[m] += bone.InBounds(x) && bone.Inside(x);
        }
      }
    }
  }

  void Print(const std::vector<md::MotionDeformation::Muscle>& muscles) const
  {
    std::vector<double> sorted = seconds;
    std::sort(sorted.begin(), sorted.end());
    std::printf("fibres: carried and measured in %.2f ms a frame (median; all muscles); %lld points kept in, %lld "
                "could not be\n",
      sorted.empty() ? 0.0 : 1000 * sorted[sorted.size() / 2], moved, stuck);
    for (size_t m = 0; m < muscles.size(); ++m)
    {
      // Per fibre, the largest change of length between frames against the median change.
      double worst = 0;
      const auto& l = lengths[m];
      for (size_t f = 0; l.size() > 2 && f < l[0].size(); ++f)
      {
        std::vector<double> steps;
        for (size_t k = 1; k < l.size(); ++k)
        {
          steps.push_back(std::abs(l[k][f] - l[k - 1][f]));
        }
        std::sort(steps.begin(), steps.end());
        const double median = steps[steps.size() / 2];
        worst = std::max(worst, median > 0 ? steps.back() / median : 0.0);
      }
      const md::Spread first = md::SpreadOf(l.front()), last = md::SpreadOf(l.back());
      std::printf("  %s: %lld fibre points outside the muscle, %lld inside a bone over the motion; length (mm) "
                  "%.1f [%.1f, %.1f] at the first frame, %.1f [%.1f, %.1f] at the last; largest step of a fibre's "
                  "length against its median %.2fx\n",
        muscles[m].name.c_str(), static_cast<long long>(outside[m]), static_cast<long long>(inBone[m]), first.median,
        first.low, first.high, last.median, last.low, last.high, worst);
    }
  }
};

/// Each muscle's fibres (MuscleFibres.h) between its areas, out of the bones; said when `say`.
std::vector<std::unique_ptr<md::MuscleFibres>> MakeFibres(const MotionFrames& frames, bool say)
{
  std::vector<std::unique_ptr<md::MuscleFibres>> fibres;
  std::vector<const md::TriangleMesh*> restBones;
  for (const md::MotionDeformation::Bone& b : frames.bones)
  {
    restBones.push_back(&b.rest);
  }
  for (const md::MotionDeformation::Muscle& m : frames.muscles)
  {
    const auto made = std::chrono::steady_clock::now();
    const md::FibreEnds ends = md::FindFibreEnds(m.rest, m.attachments, m.restLines);
    fibres.push_back(std::make_unique<md::MuscleFibres>(m.rest, ends, md::FibreParameters{}, restBones));
    if (say)
    {
      std::printf("fibres of %s: %d from %s to %s, %.1f weights a point, made in %.2f s\n", m.name.c_str(),
        fibres.back()->Count(), ends.originSource.c_str(), ends.insertionSource.c_str(),
        fibres.back()->MeanWeightsPerPoint(),
        std::chrono::duration<double>(std::chrono::steady_clock::now() - made).count());
    }
  }
  return fibres;
}

double LargestDistance(const md::Points& a, const md::Points& b)
{
  return a.rows() == b.rows() && a.rows() > 0 ? (a - b).rowwise().norm().maxCoeff() : -1.0;
}

/// Attaches the muscles of `frames` as `mode` says: by `landmarks`, by their action lines' ends
/// ("lines"), or not at all ("none"); prints how when `say`.
void AttachMuscles(
  MotionFrames& frames, const std::string& mode, const std::vector<md::LandmarkSet>& landmarks, bool say)
{
  if (mode == "none")
  {
    return;
  }
  const md::FoundAttachments found =
    AttachMotionMuscles(frames, mode == "landmarks" ? landmarks : std::vector<md::LandmarkSet>{}, true);
  for (const std::string& message : found.messages)
  {
    if (say)
    {
      std::printf("attachments: %s\n", message.c_str());
    }
  }
  for (const std::string& warning : found.warnings)
  {
    if (say)
    {
      std::printf("attachments, warning: %s\n", warning.c_str());
    }
  }
}
}

int main(int argc, char** argv)
{
  const std::string folder = argc > 1 ? argv[1] : "";
  const std::string motion = argc > 2 ? argv[2] : "hip_flexion";
  const int seed = argc > 3 ? std::atoi(argv[3]) : -1;
  const std::string attachments = argc > 4 ? argv[4] : "landmarks";
  MotionFrames frames;
  if (motion == "phantom")
  {
    PhantomFrames(frames);
  }
  else if (!LhdlFrames(folder, motion, seed, frames))
  {
    std::printf("SKIPPED: the LHDL data (lhdl_hip_r) was not found in '%s'\n", folder.c_str());
    return 0;
  }
  std::printf("%s: %zu frames, %zu muscles, %zu bones, seed %d\n", frames.name.c_str(), frames.poses.size(),
    frames.muscles.size(), frames.bones.size(), seed);
  const std::vector<md::LandmarkSet> landmarks =
    motion == "phantom" ? std::vector<md::LandmarkSet>{} : LhdlLandmarks(folder);
  AttachMuscles(frames, attachments, landmarks, true);
  std::vector<std::string> muscleNames, boneNames;
  std::vector<md::TriangleMesh> restMuscles;
  std::vector<md::Points> boneRest;
  for (const md::MotionDeformation::Muscle& m : frames.muscles)
  {
    muscleNames.push_back(m.name);
    restMuscles.push_back(m.rest);
  }
  for (const md::MotionDeformation::Bone& b : frames.bones)
  {
    boneNames.push_back(b.name);
    boneRest.push_back(b.rest.points);
  }
  const std::vector<SlipProbe> probes = LhdlSlipProbes(landmarks, muscleNames, restMuscles, boneNames);
  std::vector<double> worstSlip(frames.muscles.size(), 0.0);
  // The fibres of each muscle (MuscleFibres.h), made at rest, carried to every frame.
  const std::vector<std::unique_ptr<md::MuscleFibres>> fibres = MakeFibres(frames, true);
  FibreMeasures fibreMeasures(frames.muscles.size());
  md::InterpolationParameters parameters;
  parameters.numberOfSteps = 0; // the first frame from the rest pose: automatic
  const auto start = std::chrono::steady_clock::now();
  md::MotionDeformation deformation(frames.muscles, frames.bones, parameters);
  std::printf("prepared in %.3f s\n", deformation.PreparationSeconds());
  std::printf("%5s %7s %5s %6s %8s %9s %7s %6s %6s %9s %7s %s\n", "frame", "flexion", "steps", "iter", "ms", "max|dV|%",
    "bonePen", "flips", "sharp", "2nd diff", "ratio", "muscle");
  std::vector<std::vector<md::Points>> points;
  md::Fnv1a checksum; // of every frame's points and measures, so that two runs can be compared to the bit
  double framesSeconds = 0, worstRatio = 0, worstDepth = 0, worstVolume = 0;
  std::vector<double> frameSeconds; // after the first: their median (single frames here vary by 20 %)
  for (size_t k = 0; k < frames.poses.size(); ++k)
  {
    const md::MotionFrameResult r = deformation.Advance(frames.poses[k]);
    if (k > 0)
    {
      framesSeconds += r.seconds; // the first frame comes from the rest pose in several steps
      frameSeconds.push_back(r.seconds);
    }
    points.push_back(r.points);
    AddStepToChecksum(checksum, r.points, r.measures);
    fibreMeasures.Add(fibres, r.points, frames.poses[k].bones, frames.bones);
    const std::vector<double> slips = Slips(probes, restMuscles, r.points, boneRest, frames.poses[k].bones);
    for (size_t p = 0; p < probes.size(); ++p)
    {
      worstSlip[probes[p].muscleIndex] = std::max(worstSlip[probes[p].muscleIndex], slips[p]);
    }
    int iterations = 0;
    double volume = 0, depth = 0;
    std::int64_t flips = 0, sharp = 0;
    for (const md::MuscleStepMeasures& s : r.measures)
    {
      iterations += s.stepIterations;
      volume = std::max(volume, std::abs(s.volumeChangePercent));
      depth = std::max(depth, s.maxNewBonePenetrationDepth);
      flips += s.flippedTriangleCount;
      sharp += s.sharpEdgeCount;
    }
    double second = 0, boneSecond = 0;
    std::string popping; // the muscle with the largest second difference
    if (k >= 2)
    {
      for (size_t m = 0; m < points[k].size(); ++m)
      {
        const double own = md::LargestSecondDifference(points[k - 2][m], points[k - 1][m], points[k][m]);
        if (own > second)
        {
          second = own;
          popping = frames.muscles[m].name;
        }
      }
      boneSecond = md::LargestSecondDifference(frames.poses[k - 2], frames.poses[k - 1], frames.poses[k]);
    }
    const double ratio = boneSecond > 0 ? second / boneSecond : 0.0;
    if (k >= 2)
    {
      worstRatio = std::max(worstRatio, ratio);
    }
    worstDepth = std::max(worstDepth, depth);
    worstVolume = std::max(worstVolume, volume);
    std::printf("%5zu %7.1f %5d %6d %8.1f %9.1e %7.3f %6lld %6lld %9.4f %7.2f %s\n", k, frames.flexion[k], r.steps,
      iterations, 1000 * r.seconds, volume, depth, static_cast<long long>(flips), static_cast<long long>(sharp), second,
      ratio, popping.c_str());
    for (const std::string& w : r.warnings)
    {
      std::printf("      warning: %s\n", w.c_str());
    }
  }
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::sort(frameSeconds.begin(), frameSeconds.end());
  const double median = frameSeconds.empty() ? 0.0 : frameSeconds[frameSeconds.size() / 2];
  std::printf("total %.2f s; frames after the first %.1f ms on average, median %.1f ms; largest |dV| %.1e %%, bone "
              "penetration %.3f, smoothness ratio %.2f\n",
    total, frames.poses.size() > 1 ? 1000 * framesSeconds / (frames.poses.size() - 1) : 0.0, 1000 * median, worstVolume,
    worstDepth, worstRatio);
  const std::vector<double> stepRatios = StepRatios(points);
  std::printf("attachments '%s': %zu landmark probes; per muscle, the largest slip (mm) and the largest step between "
              "frames against its median:",
    attachments.c_str(), probes.size());
  for (size_t m = 0; m < frames.muscles.size(); ++m)
  {
    std::printf(" %s %.2f / %.2fx;", frames.muscles[m].name.c_str(), worstSlip[m], stepRatios[m]);
  }
  std::printf("\n");

  fibreMeasures.Print(frames.muscles);

  // Perturbed input against the exact input: how far every frame's surfaces moved (issue 13's
  // measure, through the whole motion).
  MotionFrames exactFrames;
  if (seed >= 0 && motion != "phantom" && LhdlFrames(folder, motion, -1, exactFrames) &&
    exactFrames.poses.size() == frames.poses.size())
  {
    AttachMuscles(exactFrames, attachments, landmarks, false);
    md::MotionDeformation exact(exactFrames.muscles, exactFrames.bones, parameters);
    const std::vector<std::unique_ptr<md::MuscleFibres>> exactFibres = MakeFibres(exactFrames, false);
    FibreMeasures exactFibreMeasures(exactFrames.muscles.size());
    for (size_t m = 0; m < fibres.size(); ++m)
    {
      std::printf("  %s: the fibres at rest, largest distance %.6f mm\n", frames.muscles[m].name.c_str(),
        fibres[m]->Rest().rows() == exactFibres[m]->Rest().rows()
          ? LargestDistance(fibres[m]->Rest(), exactFibres[m]->Rest())
          : -1.0);
    }
    double largestFibre = 0;
    size_t fibreCountsDiffer = 0;
    double largest = 0, worstRms = 0;
    size_t largestFrame = 0;
    std::string largestMuscle, beyond;
    constexpr double kNoiseBound = 0.01; // mm: issue 13's bound for 1e-7 of input noise
    for (size_t k = 0; k < exactFrames.poses.size(); ++k)
    {
      const md::MotionFrameResult r = exact.Advance(exactFrames.poses[k]);
      exactFibreMeasures.Add(exactFibres, r.points, exactFrames.poses[k].bones, exactFrames.bones);
      for (size_t m = 0; m < r.points.size(); ++m)
      {
        const md::Points& a = fibreMeasures.points[k][m];
        const md::Points& b = exactFibreMeasures.points.back()[m];
        if (a.rows() == b.rows())
        {
          largestFibre = std::max(largestFibre, LargestDistance(a, b));
        }
        else
        {
          ++fibreCountsDiffer;
        }
        const double distance = LargestDistance(points[k][m], r.points[m]);
        if (distance > kNoiseBound)
        {
          beyond += " " + std::to_string(k) + " (" + frames.muscles[m].name + " " + std::to_string(distance) + " mm)";
        }
        if (distance > largest)
        {
          largest = distance;
          largestFrame = k;
          largestMuscle = frames.muscles[m].name;
        }
        if (distance >= 0)
        {
          worstRms = std::max(worstRms, std::sqrt((points[k][m] - r.points[m]).rowwise().squaredNorm().mean()));
        }
      }
    }
    std::printf("against the exact input, every frame: largest distance %.6f mm (frame %zu, %s), RMS up to %.6f mm\n",
      largest, largestFrame, largestMuscle.c_str(), worstRms);
    std::printf("  frames beyond %.2f mm:%s\n", kNoiseBound, beyond.empty() ? " none" : beyond.c_str());
    std::printf("  the fibres, every frame: largest distance %.6f mm%s\n", largestFibre,
      fibreCountsDiffer ? " (some muscles got another count of fibres)" : "");
  }

  // The frame nearest 60 degrees of flexion against the interpolation method from the rest pose.
  if (motion != "hip_adduction")
  {
    size_t nearest = 0;
    for (size_t k = 0; k < frames.flexion.size(); ++k)
    {
      if (std::abs(frames.flexion[k] - 60) < std::abs(frames.flexion[nearest] - 60))
      {
        nearest = k;
      }
    }
    md::InterpolationParameters direct;
    const md::InterpolationResult r =
      md::DeformByInterpolation(frames.cases[nearest].muscles, frames.cases[nearest].bones, direct);
    std::printf("frame %zu (%.1f degrees) against InterpolatedMuscleDeformation (N = %d) from the rest pose:", nearest,
      frames.flexion[nearest], r.numberOfSteps);
    for (size_t m = 0; m < frames.muscles.size(); ++m)
    {
      const md::Points& a = points[nearest][m];
      const md::Points& b = r.points.back()[m];
      const double rms = a.rows() == b.rows() ? std::sqrt((a - b).rowwise().squaredNorm().mean()) : -1.0;
      std::printf(" %s %.2f (RMS %.2f) mm;", frames.muscles[m].name.c_str(), LargestDistance(a, b), rms);
    }
    std::printf("\n");
    // The same with the motion's own lines at that frame (the rest lines' points): what the way
    // through the motion changes, apart from how the lines are sampled.
    std::vector<md::MuscleMotion> same;
    for (size_t m = 0; m < frames.muscles.size(); ++m)
    {
      same.push_back({ frames.muscles[m].name, frames.muscles[m].rest, {} });
      for (size_t l = 0; l < frames.muscles[m].restLines.size(); ++l)
      {
        same.back().lines.push_back({ frames.muscles[m].restLines[l], frames.poses[nearest].lines[m][l] });
      }
    }
    const md::InterpolationResult sameLines = md::DeformByInterpolation(same, frames.cases[nearest].bones, direct);
    std::printf("  with the motion's lines (the rest lines' points):");
    for (size_t m = 0; m < frames.muscles.size(); ++m)
    {
      std::printf(" %s %.2f mm;", frames.muscles[m].name.c_str(),
        LargestDistance(points[nearest][m], sameLines.points.back()[m]));
    }
    std::printf("\n");
  }
  std::printf(
    "checksum of every frame's points and measures: %016llx\n", static_cast<unsigned long long>(checksum.Value()));
  return 0;
}
