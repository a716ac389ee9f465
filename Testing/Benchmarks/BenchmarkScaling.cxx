// SPDX-License-Identifier: BSD-3-Clause
// How cost grows with the muscle's size: the VHF gluteus maximus (24,220 points) and the same
// surface subdivided once (96,874) and twice (387,490) at its edges' midpoints. For each: the
// repair and hull, the mean value coordinates of the muscle in its hull, and one deformation
// pass (its action line: the centroids of five slices along its long axis; the current pose turns
// it by 10 degrees about its first point; no obstacles). Prints seconds and the exponent of each
// between sizes. Asserts nothing.
//
//   BenchmarkScaling [data folder]
#include "Deformation/MuscleDeformer.h"
#include "Geometry/MeanValueCoordinates.h"
#include "Hull/ProgressiveHull.h"
#include "RealData.h"

#include <Eigen/Eigenvalues>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <utility>

namespace
{
using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point since)
{
  return std::chrono::duration<double>(Clock::now() - since).count();
}

/// Every triangle split into four at its edges' midpoints.
md::TriangleMesh Subdivide(const md::TriangleMesh& mesh)
{
  std::map<std::pair<std::int64_t, std::int64_t>, std::int64_t> midpoint;
  std::vector<Eigen::RowVector3d> points;
  for (Eigen::Index i = 0; i < mesh.points.rows(); ++i)
  {
    points.push_back(mesh.points.row(i));
  }
  auto middle = [&](std::int64_t a, std::int64_t b) {
    const auto key = std::minmax(a, b);
    auto found = midpoint.find(key);
    if (found != midpoint.end())
    {
      return found->second;
    }
    points.push_back(0.5 * (mesh.points.row(a) + mesh.points.row(b)));
    const auto index = static_cast<std::int64_t>(points.size()) - 1;
    midpoint.emplace(key, index);
    return index;
  };
  md::TriangleMesh out;
  out.triangles.resize(4 * mesh.triangles.rows(), 3);
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
  {
    const std::int64_t a = mesh.triangles(t, 0), b = mesh.triangles(t, 1), c = mesh.triangles(t, 2);
    const std::int64_t ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
    out.triangles.row(4 * t) << a, ab, ca;
    out.triangles.row(4 * t + 1) << ab, b, bc;
    out.triangles.row(4 * t + 2) << ca, bc, c;
    out.triangles.row(4 * t + 3) << ab, bc, ca;
  }
  out.points.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i)
  {
    out.points.row(static_cast<Eigen::Index>(i)) = points[i];
  }
  return out;
}

/// The centroids of five slices along the muscle's long axis, and that line turned by 10
/// degrees about its first point.
md::MatchedLine ActionLine(const md::TriangleMesh& muscle)
{
  const Eigen::RowVector3d centre = muscle.points.colwise().mean();
  const md::Points centred = muscle.points.rowwise() - centre;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca(centred.transpose() * centred);
  const Eigen::Vector3d axis = pca.eigenvectors().col(2);
  const Eigen::VectorXd along = centred * axis;
  const double low = along.minCoeff(), high = along.maxCoeff();
  constexpr int slices = 5;
  md::MatchedLine line;
  line.rest.resize(slices, 3);
  std::vector<int> count(slices, 0);
  line.rest.setZero();
  for (Eigen::Index i = 0; i < muscle.points.rows(); ++i)
  {
    const int s = std::min(slices - 1, static_cast<int>(slices * (along[i] - low) / (high - low)));
    line.rest.row(s) += muscle.points.row(i);
    ++count[s];
  }
  for (int s = 0; s < slices; ++s)
  {
    line.rest.row(s) /= std::max(1, count[s]);
  }
  const md::RigidTransform turn =
    md::RigidTransform::AboutPoint(pca.eigenvectors().col(1), 10.0 * M_PI / 180.0, line.rest.row(0).transpose());
  line.current = turn.Apply(line.rest);
  return line;
}
}

int main(int argc, char** argv)
{
  const std::string file =
    RealDataFile("vhf_right/VHF_Right_Muscle_GluteusMaximus_smooth.stl", argc > 1 ? argv[1] : "");
  if (file.empty())
  {
    std::printf("skipped: vhf_right/VHF_Right_Muscle_GluteusMaximus_smooth.stl not found (give the data folder)\n");
    return 0;
  }
  md::TriangleMesh muscle = ReadSurface(file);
  double previous[3] = { 0, 0, 0 };
  Eigen::Index previousPoints = 0;
  std::printf(
    "points    repair+hull s   weights s   one pass s  iterations  dV %%        (exponents against the size before)\n");
  for (int level = 0; level < 3; ++level)
  {
    if (level > 0)
    {
      muscle = Subdivide(muscle);
    }
    auto start = Clock::now();
    const md::MuscleHull hull = md::BuildMuscleHull(muscle, md::HullParameters());
    const double hullSeconds = Seconds(start);
    start = Clock::now();
    const md::WeightMatrix weights = md::MeanValueCoordinates(hull.result.hull, muscle.points);
    const double weightSeconds = Seconds(start);
    md::MuscleToDeform toDeform{ "gluteus maximus", &muscle, &hull.result.hull, { ActionLine(muscle) }, &weights };
    start = Clock::now();
    const std::vector<md::DeformationResult> result = md::DeformMuscles({ toDeform }, {}, md::DeformationParameters{});
    const double passSeconds = Seconds(start);
    const double now[3] = { hullSeconds, weightSeconds, passSeconds };
    std::printf("%7ld   %10.2f   %10.2f   %10.2f   %6d   %+.2e", static_cast<long>(muscle.points.rows()), hullSeconds,
      weightSeconds, passSeconds, result[0].iterations, result[0].volumeChangePercent);
    if (level > 0)
    {
      const double ratio = std::log(static_cast<double>(muscle.points.rows()) / previousPoints);
      std::printf("   (%.2f, %.2f, %.2f)", std::log(now[0] / previous[0]) / ratio,
        std::log(now[1] / previous[1]) / ratio, std::log(now[2] / previous[2]) / ratio);
    }
    std::printf("\n");
    std::copy(now, now + 3, previous);
    previousPoints = muscle.points.rows();
  }
  return 0;
}
