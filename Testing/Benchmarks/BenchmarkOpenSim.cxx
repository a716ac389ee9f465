// SPDX-License-Identifier: BSD-3-Clause
// OpenSim models: loading and updating to a new time, in the core and through the reader
// (vtkOpenSimModelReader, as ParaView runs it), on gait2392 (23 coordinates, 92 muscles, 20
// meshes) and the other models of ../shared/data/opensim; one segment over each kind of wrap
// object (no data needed). Prints figures; asserts nothing.
//
//   BenchmarkOpenSim [data folder]
#include "OpenSim/OpenSimKinematics.h"
#include "OpenSim/OpenSimMotion.h"
#include "OpenSim/OpenSimWrapping.h"
#include "RealData.h"
#include "vtkOpenSimModelReader.h"

#include <vtkInformation.h>
#include <vtkStreamingDemandDrivenPipeline.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <vector>

namespace
{
double Seconds(std::chrono::steady_clock::time_point since)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

double Median(std::vector<double> values)
{
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

void Measure(const std::string& label, const std::string& model, const std::string& motion)
{
  namespace osim = md::osim;
  // Core: read, map the motion, then bodies and every path at each frame.
  std::vector<double> reads;
  osim::Model parsed;
  for (int run = 0; run < 5; ++run)
  {
    const auto start = std::chrono::steady_clock::now();
    parsed = osim::ReadModel(model);
    reads.push_back(Seconds(start));
  }
  osim::MotionOptions options;
  options.ignoreUnknownColumns = true;
  const osim::CoordinateTrajectory trajectory = osim::MapMotion(parsed, osim::ReadMotion(motion), options);
  std::vector<double> frames;
  for (int run = 0; run < 5; ++run)
  {
    const auto start = std::chrono::steady_clock::now();
    double total = 0;
    for (const std::vector<double>& q : trajectory.frames)
    {
      const std::vector<md::RigidTransform> poses = osim::BodyPoses(parsed, q);
      for (const osim::Path& path : parsed.paths)
      {
        total += osim::PathAt(parsed, path, q, poses).length;
      }
    }
    frames.push_back(Seconds(start) / trajectory.frames.size());
    if (total < 0)
    {
      std::printf("impossible\n");
    }
  }
  // The reader: first update (model, motion, meshes), then the bodies and paths at every time.
  std::vector<double> loads, updates;
  for (int run = 0; run < 3; ++run)
  {
    vtkNew<vtkOpenSimModelReader> reader;
    reader->SetFileName(model.c_str());
    reader->SetMotionFileName(motion.c_str());
    reader->IgnoreUnknownColumnsOn();
    auto start = std::chrono::steady_clock::now();
    reader->Update();
    loads.push_back(Seconds(start));
    start = std::chrono::steady_clock::now();
    for (double time : trajectory.times)
    {
      for (int port : { vtkOpenSimModelReader::BODIES, vtkOpenSimModelReader::MUSCLE_PATHS })
      {
        reader->GetOutputInformation(port)->Set(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP(), time);
        reader->Update(port);
      }
    }
    updates.push_back(Seconds(start) / trajectory.times.size());
  }
  std::printf("%-16s %3zu bodies %2zu coordinates %3zu paths %4zu frames | core: read %.1f ms, bodies + paths "
              "%.3f ms a frame | reader: load %.0f ms (meshes included), update to a new time (bodies and "
              "paths) %.2f ms (medians)\n",
    label.c_str(), parsed.bodies.size(), parsed.coordinates.size(), parsed.paths.size(), trajectory.frames.size(),
    1e3 * Median(reads), 1e3 * Median(frames), 1e3 * Median(loads), 1e3 * Median(updates));
}

/// One segment over each kind of wrap object, sized as a muscle's: a segment 20 cm long passing
/// 1 cm from the centre of an object of radius 2 cm (an ellipsoid 3.5 x 2 x 2 cm, as arm26's;
/// a torus of ring 5 cm and tube 2 cm, the segment through its ring). Microseconds a segment.
void MeasureWrapObjects()
{
  namespace osim = md::osim;
  using Vector = Eigen::Vector3d;
  const Vector p1(-0.1, 0.01, 0.004), p2(0.1, 0.008, -0.003);
  const auto time = [&](const char* label, const std::function<double(const Vector&)>& wrap) {
    std::vector<double> runs;
    double total = 0;
    constexpr int kSegments = 20000;
    for (int run = 0; run < 5; ++run)
    {
      const auto start = std::chrono::steady_clock::now();
      for (int i = 0; i < kSegments; ++i)
      {
        total += wrap(p1 + Vector(1e-9 * i, 0, 0)); // a new segment each time
      }
      runs.push_back(Seconds(start) / kSegments);
    }
    std::printf("  %-36s %6.2f us a segment (median of 5 runs of %d)%s\n", label, 1e6 * Median(runs), kSegments,
      total < 0 ? " impossible" : "");
  };
  std::printf("One segment over a wrap object:\n");
  osim::WrapResult result;
  time("cylinder (one wrap object)", [&](const Vector& p) {
    osim::WrapCylinderSegment(p, p2, 0.02, 0.2, 0, 0, false, result);
    return result.length;
  });
  time("cylinder (tangent points slid)", [&](const Vector& p) {
    osim::WrapCylinderSegment(p, p2, 0.02, 0.2, 0, 0, true, result);
    return result.length;
  });
  time("sphere", [&](const Vector& p) {
    osim::WrapSphereSegment(p, p2, 0.02, 0, 0, result);
    return result.length;
  });
  for (const auto& [label, method] : { std::pair{ "ellipsoid, hybrid", osim::EllipsoidWrapMethod::Hybrid },
         std::pair{ "ellipsoid, midpoint", osim::EllipsoidWrapMethod::Midpoint },
         std::pair{ "ellipsoid, axial", osim::EllipsoidWrapMethod::Axial } })
  {
    time(label, [&, method = method](const Vector& p) {
      osim::WrapEllipsoidSegment(p, p2, Vector(0.035, 0.02, 0.02), 0, 0, method, result);
      return result.length;
    });
  }
  const Vector r1(0.05 - 0.1, 0.001, 0.004), r2(0.05 + 0.1, -0.002, -0.003);
  time("torus", [&](const Vector& p) {
    osim::WrapTorusSegment(p - p1 + r1, r2, 0.05, 0.02, 0, 0, false, result);
    return result.length;
  });
}
}

int main(int argc, char** argv)
{
  MeasureWrapObjects();
  const std::string folder = argc > 1 ? argv[1] : "";
  struct Case
  {
    const char* label;
    const char* model;
    const char* motion;
  };
  const Case cases[] = {
    { "gait2392", "opensim/gait2392_walk_forward/subject01_simbody_adjusted.osim",
      "opensim/gait2392_walk_forward/subject01_walk1_Kinematics_q.mot" },
    { "gait10dof18musc", "opensim/gait10dof18musc_walk/walk_gait1018_subject01.osim",
      "opensim/gait10dof18musc_walk/walk_gait1018_state_reference.mot" },
    { "rajagopal2016", "opensim/rajagopal2016_walk_armless_18musc/subject_walk_armless_18musc.osim",
      "opensim/rajagopal2016_walk_armless_18musc/subject_walk_armless_coordinates.mot" },
    { "LHDL hip", "lhdl_hip_r/LHDL_hip_r.osim", "lhdl_hip_r/kinematics/hip_flexion.mot" },
  };
  for (const Case& c : cases)
  {
    const std::string model = RealDataFile(c.model, folder), motion = RealDataFile(c.motion, folder);
    if (model.empty() || motion.empty())
    {
      std::printf(
        "%-16s skipped: %s not found (give the data folder or set MUSCLEDEFORMATION_DATA_DIR)\n", c.label, c.model);
      continue;
    }
    Measure(c.label, model, motion);
  }
  return 0;
}
