// SPDX-License-Identifier: BSD-3-Clause
// Hull decimation and mean value coordinates on every muscle at hand: the
// phantom's and, when present, those of ../shared/data/lhdl_hip_r and
// ../shared/data/vhf_right. Prints figures; asserts nothing (see the tests).
//
//   BenchmarkHull [data folder] [target points]
#include "Common/Fnv1a.h"
#include "Geometry/MeanValueCoordinates.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/SurfaceRepair.h"
#include "Hull/ProgressiveHull.h"
#include "Phantom/Phantom.h"
#include "RealData.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

namespace
{
/// Of every repaired surface, hull and weight matrix, so that two builds can be compared to the bit.
md::Fnv1a checksum;

double Seconds(std::chrono::steady_clock::time_point since)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

void Measure(const std::string& name, const md::TriangleMesh& muscle, int target)
{
  const double size = (muscle.points.colwise().maxCoeff() - muscle.points.colwise().minCoeff()).norm();
  // Times are the median of three runs: single runs on this kind of machine vary by up to 30 %.
  constexpr int runs = 3;
  std::vector<double> repairTimes, hullTimes;
  md::RepairReport report;
  md::TriangleMesh clean;
  md::HullResult result;
  for (int run = 0; run < runs; ++run)
  {
    auto start = std::chrono::steady_clock::now();
    try
    {
      clean = md::RepairClosedSurface(muscle, report);
    }
    catch (const md::InputError& e)
    {
      std::printf("%-34s refused: %s\n", name.c_str(), e.what());
      return;
    }
    repairTimes.push_back(Seconds(start));
    md::HullParameters parameters;
    parameters.targetNumberOfPoints = target;
    start = std::chrono::steady_clock::now();
    result = md::BuildProgressiveHull(clean, parameters, &report.pointsToEnclose);
    hullTimes.push_back(Seconds(start));
  }
  std::sort(repairTimes.begin(), repairTimes.end());
  std::sort(hullTimes.begin(), hullTimes.end());
  const double repairTime = repairTimes[runs / 2];
  const double hullTime = hullTimes[runs / 2];
  const md::TriangleMesh& hull = result.hull;

  const auto start = std::chrono::steady_clock::now();
  const md::WeightMatrix weights = md::MeanValueCoordinates(hull, muscle.points);
  const double mvcTime = Seconds(start);
  const md::Points reproduced = weights * hull.points;
  const double mvcError = (reproduced - muscle.points).rowwise().norm().maxCoeff() / size;
  for (const md::TriangleMesh* mesh : { &std::as_const(clean), &hull })
  {
    checksum.Add(mesh->points.data(), sizeof(double) * static_cast<size_t>(mesh->points.size()));
    checksum.Add(mesh->triangles.data(), sizeof(std::int64_t) * static_cast<size_t>(mesh->triangles.size()));
  }
  checksum.Add(reproduced.data(), sizeof(double) * static_cast<size_t>(reproduced.size()));
  const double sumError = (weights.rowwise().sum().array() - 1.0).abs().maxCoeff();

  // The muscle's points are those its triangles use (files carry unused ones too).
  const std::int64_t outside = md::CountOutside(hull, md::UsedPoints(muscle), 1e-9 * size);
  const md::EdgeReport edges = md::CheckEdges(hull.triangles);
  const std::int64_t intersections = md::CountSelfIntersections(hull);
  const double ratio =
    md::SignedVolume(hull.points, hull.triangles) / md::SignedVolume(muscle.points, muscle.triangles);
  std::printf("%-34s %6ld %6ld | %4ld %4ld %s | %8.3f %8.3f | %6.3f | %7ld %4s %4ld | %7.3f %9.2e %8.1e\n",
    name.c_str(), static_cast<long>(muscle.points.rows()), static_cast<long>(muscle.triangles.rows()),
    static_cast<long>(hull.points.rows()), static_cast<long>(hull.triangles.rows()), result.reachedTarget ? "  " : "!!",
    repairTime, hullTime, ratio, static_cast<long>(outside), edges.IsClosedOrientedManifold() ? "yes" : "NO",
    static_cast<long>(intersections), mvcTime, mvcError, sumError);
  if (result.pointsBumpedIn > 0 || result.pointsLeftOutside > 0)
  {
    std::printf("%-34s   points bumped into the hull: %d, left outside: %ld\n", "", result.pointsBumpedIn,
      static_cast<long>(result.pointsLeftOutside));
  }
  if (report.Changed())
  {
    std::printf("%-34s   repaired: %s\n", "", report.Describe().c_str());
  }
}
}

int main(int argc, char** argv)
{
  const char* fromEnvironment = std::getenv("MUSCLEDEFORMATION_DATA_DIR");
  const std::string data = argc > 1 ? argv[1] : (fromEnvironment ? fromEnvironment : "../shared/data");
  const int target = argc > 2 ? std::atoi(argv[2]) : 250;
  std::printf("Hull decimation to %d points and mean value coordinates (MVC). Release build expected;\n"
              "repair and hull times are the median of 3 runs.\n"
              "The original implementation (progressive hulls, Cholt 2012) needed \"easily a minute\" per hull.\n\n",
    target);
  std::printf("%-34s %6s %6s | %4s %4s %2s | %8s %8s | %6s | %7s %4s %4s | %7s %9s %8s\n", "muscle", "points", "tris",
    "hull", "tris", "", "repair s", "hull s", "V/V0", "outside", "mfld", "self", "MVC s", "MVC err", "sum err");
  const md::Phantom phantom = md::BuildPhantom(md::PhantomParameters{});
  for (const md::PhantomMuscle& muscle : phantom.muscles)
  {
    Measure("phantom/" + muscle.name, muscle.rest, target);
  }
  const std::vector<std::string> files = { "lhdl_hip_r/gluteus_maximus_r.vtk", "lhdl_hip_r/gluteus_medius_r.vtk",
    "lhdl_hip_r/iliacus_r.vtk", "lhdl_hip_r/psoas_r.vtk", "vhf_right/VHF_Right_Muscle_GluteusMaximus_smooth.stl",
    "vhf_right/VHF_Right_Muscle_GluteusMedius_smooth.stl", "vhf_right/VHF_Right_Muscle_Illiacus_smooth.stl",
    "vhf_right/VHF_Right_Muscle_PsoasMajor_smooth.stl", "vhf_right/VHF_Right_Muscle_RectusFemoris_smooth.stl" };
  int missing = 0;
  for (const std::string& file : files)
  {
    const std::string path = RealDataFile(file, data);
    if (path.empty())
    {
      ++missing;
      continue;
    }
    const md::TriangleMesh muscle = ReadSurface(path);
    Measure(file.substr(0, file.find('/')) + "/" + file.substr(file.rfind('/') + 1), muscle, target);
  }
  if (missing > 0)
  {
    std::printf("\n%d real-data muscles not found under %s: skipped\n", missing, data.c_str());
  }
  std::printf("\nV/V0: hull volume / muscle volume. outside: muscle points (those its triangles use) outside the\n"
              "hull, every point tested, tolerance 1e-9 of the muscle's size. mfld: closed, manifold, oriented. self: "
              "intersecting triangle\n"
              "pairs of the hull. MVC err: largest |sum w_j h_j - x| over the muscle's points / muscle size.\n");
  std::printf("checksum of every repaired surface, hull and reproduction: %016llx\n",
    static_cast<unsigned long long>(checksum.Value()));
  return 0;
}
