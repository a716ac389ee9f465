// SPDX-License-Identifier: BSD-3-Clause
// Obstacle queries (the bounding-volume hierarchy of Filters/Algorithms/Geometry/TriangleTree.h)
// on the phantom's femur and, when present, the LHDL bones: build time,
// inside tests and first hits per second. Prints figures; asserts nothing.
//
//   BenchmarkObstacles [data folder]
#include "Geometry/TriangleTree.h"
#include "Phantom/Phantom.h"
#include "RealData.h"

#include <chrono>
#include <cstdio>
#include <random>

namespace
{
double Seconds(std::chrono::steady_clock::time_point since)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

void Measure(const std::string& name, const md::TriangleMesh& bone)
{
  auto start = std::chrono::steady_clock::now();
  const md::TriangleTree tree(bone);
  const double build = Seconds(start);
  const Eigen::Vector3d low = bone.points.colwise().minCoeff().transpose();
  const Eigen::Vector3d high = bone.points.colwise().maxCoeff().transpose();
  std::mt19937 generator(1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto random = [&]() {
    return Eigen::Vector3d(
      low + (high - low).cwiseProduct(Eigen::Vector3d(unit(generator), unit(generator), unit(generator))));
  };
  constexpr int queries = 20000;
  std::vector<Eigen::Vector3d> points(queries);
  for (auto& p : points)
  {
    p = random();
  }
  start = std::chrono::steady_clock::now();
  int inside = 0;
  for (const auto& p : points)
  {
    inside += tree.Inside(p) ? 1 : 0;
  }
  const double insideTime = Seconds(start);
  start = std::chrono::steady_clock::now();
  int hits = 0;
  const double step = 0.02 * (high - low).norm(); // short moves, as of a vertex in one iteration
  for (const auto& p : points)
  {
    hits += tree.FirstHit(p, p + step * (random() - p).normalized()) ? 1 : 0;
  }
  const double hitTime = Seconds(start);
  std::printf(
    "%-28s %7ld | build %7.1f ms | inside %6.2f us each (%5.1f %% in) | first hit %6.2f us each (%4.1f %% hit)\n",
    name.c_str(), static_cast<long>(bone.triangles.rows()), 1e3 * build, 1e6 * insideTime / queries,
    100.0 * inside / queries, 1e6 * hitTime / queries, 100.0 * hits / queries);
}
}

int main(int argc, char** argv)
{
  const std::string folder = argc > 1 ? argv[1] : "";
  std::printf("Obstacle bounding-volume hierarchy, %s build expected; %d random queries in each bone's box.\n\n",
    "Release", 20000);
  std::printf("%-28s %7s\n", "bone", "tris");
  const md::Phantom phantom = md::BuildPhantom(md::PhantomParameters{});
  Measure("phantom/Femur", phantom.bones[1].rest);
  int missing = 0;
  for (const char* file : { "lhdl_hip_r/iliac_r.vtk", "lhdl_hip_r/sacrum.vtk", "lhdl_hip_r/femur_r.vtk" })
  {
    const std::string path = RealDataFile(file, folder);
    if (path.empty())
    {
      ++missing;
      continue;
    }
    Measure(file, ReadSurface(path));
  }
  if (missing > 0)
  {
    std::printf(
      "\n%d LHDL bones not found: skipped (pass the data folder or set MUSCLEDEFORMATION_DATA_DIR)\n", missing);
  }
  return 0;
}
