// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkMuscleDeformation
 * @brief   Deforms muscles from the rest pose to the current pose in one pass.
 *
 * DeformationMesh MUSCLE_SURFACE solves the pass on every point of the
 * muscles' own surfaces (md::SettleInOnePass, docs/DESIGN.md section 7): the
 * energy below posed on the full mesh, contact a constraint (no point ends
 * inside an obstacle or another muscle), the rest volume held; the answer does
 * not depend on a hull, and the Hull input and the hull and iteration
 * properties are not used.
 *
 * DeformationMesh HULL (default): the deformation of Kellnhofer & Kohout (after Huang et al. 2006), the
 * paper's "original method": the unknowns are the points of each muscle's
 * coarse hull (input 3, or built as HullDecimation does), the muscle follows
 * by mean value coordinates. Least squares of the hull's cotangent Laplacian
 * (its rest-pose Laplacian coordinates rotated as the nearest action-line
 * segment turns) and of action-line rows (samples of each matched rest-pose
 * line must reach the matching current-pose samples), with the volume held
 * by Gauss-Newton steps with a Lagrange multiplier (the corrected form: the
 * volume converges to the rest volume). A coarse phase on the hull, then a
 * fine phase with the volume measured on the full mesh and dynamic
 * intersections: a point that would enter an obstacle stops at its surface;
 * one inside a bone stays where it is. Triangles the mapping turns over are
 * unfolded (their neighbourhood takes back its rest shape).
 *
 * Inputs: 0 Input, muscles in the rest pose; 1 ActionLines, output 0 of
 * ActionLineMatching (rest-pose lines with point array CurrentPosition), one
 * block per muscle (by name, else by order); 2 Obstacles, any number of
 * meshes in the current pose (optional); 3 Hull, optional, one per muscle.
 * All muscles of the input are deformed together, each an obstacle for the
 * others.
 *
 * Output: the muscles (same structure, cells and arrays) with moved points,
 * point array Displacement, and field data VolumeChangePercent,
 * NumberOfIterations, Converged, FlippedTriangleCount, HullSeconds (the hull
 * and its mapping, or the full-mesh energy), DeformationSeconds, ElapsedSeconds;
 * with HULL also CoarseIterations, PointsFrozenInObstacles,
 * PointsStoppedAtObstacles, RestActionLineSamplesInside,
 * CurrentActionLineSamplesInside; with MUSCLE_SURFACE PointsInContact.
 */
#pragma once

#include "MuscleDeformationFiltersModule.h"

#include <vtkPassInputTypeAlgorithm.h>

#include <memory>
#include <string>
#include <vector>

namespace md
{
struct TriangleMesh;
struct LocalFrame;
}
namespace mdvtk
{
struct Leaf;
}

class MUSCLEDEFORMATIONFILTERS_EXPORT vtkMuscleDeformation : public vtkPassInputTypeAlgorithm
{
public:
  static vtkMuscleDeformation* New();
  vtkTypeMacro(vtkMuscleDeformation, vtkPassInputTypeAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Connections: port 1 action lines, port 2 obstacles (repeatable), port 3 hull.
  void SetActionLinesConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void AddObstacleConnection(vtkAlgorithmOutput* output) { this->AddInputConnection(2, output); }
  void RemoveAllObstacles() { this->SetInputConnection(2, nullptr); }
  void SetHullConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(3, output); }

  enum DeformationMeshes
  {
    HULL = 0,
    MUSCLE_SURFACE = 1,
  };
  /// HULL (default): solved on a coarse hull the muscle follows, the paper's original method (the
  /// Hull input and the properties below apply to it only, SamplesPerSegment aside);
  /// MUSCLE_SURFACE: on the muscles' own surfaces.
  vtkSetClampMacro(DeformationMesh, int, HULL, MUSCLE_SURFACE);
  vtkGetMacro(DeformationMesh, int);

  /// Iterations of both phases together. Default 200.
  vtkSetClampMacro(MaximumNumberOfIterations, int, 1, 100000);
  vtkGetMacro(MaximumNumberOfIterations, int);

  /// Of them, at most this many on the hull alone. Default 100.
  vtkSetClampMacro(MaximumCoarseIterations, int, 0, 100000);
  vtkGetMacro(MaximumCoarseIterations, int);

  /// Converged when no hull coordinate moves more than this in an iteration
  /// (data units). Default 0.01.
  vtkSetClampMacro(ConvergenceTolerance, double, 1e-12, VTK_DOUBLE_MAX);
  vtkGetMacro(ConvergenceTolerance, double);

  /// Gauss-Newton step length in (0, 1]. Default 1.
  vtkSetClampMacro(StepLength, double, 0.01, 1.0);
  vtkGetMacro(StepLength, double);

  /// Action-line rows per segment of each matched line. Default 10.
  vtkSetClampMacro(SamplesPerSegment, int, 1, 1000);
  vtkGetMacro(SamplesPerSegment, int);

  /// Hold the volume. Default on.
  vtkSetMacro(PreserveVolume, bool);
  vtkGetMacro(PreserveVolume, bool);
  vtkBooleanMacro(PreserveVolume, bool);

  /// Keep points out of the obstacles and the other muscles. Default on.
  vtkSetMacro(DynamicIntersections, bool);
  vtkGetMacro(DynamicIntersections, bool);
  vtkBooleanMacro(DynamicIntersections, bool);

  /// Points of the hulls built when input 3 is empty. Default 250.
  vtkSetClampMacro(HullTargetNumberOfPoints, int, 4, VTK_INT_MAX);
  vtkGetMacro(HullTargetNumberOfPoints, int);

  /// Hulls built so far (input 3 empty). A muscle's hull and its mean value coordinates depend on
  /// its rest-pose surface and HullTargetNumberOfPoints only, so they are kept: a new pose, new
  /// action lines or another iteration setting reuses them, a changed muscle or hull size
  /// rebuilds that muscle's.
  vtkGetMacro(HullBuildCount, int);
  /// Full-mesh energies built so far (DeformationMesh MUSCLE_SURFACE): kept per muscle while its
  /// rest-pose surface and action lines are the same.
  vtkGetMacro(SurfaceEnergyBuildCount, int);

protected:
  vtkMuscleDeformation();
  ~vtkMuscleDeformation() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  int DeformationMesh = HULL;
  // The core's defaults (md::DeformationParameters, md::HullParameters), set by the constructor.
  int MaximumNumberOfIterations;
  int MaximumCoarseIterations;
  double ConvergenceTolerance;
  double StepLength;
  int SamplesPerSegment;
  bool PreserveVolume;
  bool DynamicIntersections;
  int HullTargetNumberOfPoints;

private:
  vtkMuscleDeformation(const vtkMuscleDeformation&) = delete;
  void operator=(const vtkMuscleDeformation&) = delete;
  int HullBuildCount = 0;
  int SurfaceEnergyBuildCount = 0;
  struct RestPoseCache;
  struct PassInput;
  struct PassOutcome;
  struct Read;
  /// Reads the muscles, their action lines and given hulls; false when an input cannot be read
  /// (reported). A muscle that cannot be read is left out, in read.failedBlocks.
  bool ReadMuscles(vtkInformationVector** inputVector, Read& read);
  /// Brings what was read into the muscles' local frame.
  static md::LocalFrame ToLocalFrame(Read& read);
  /// The output block of every muscle: deformed (in the data's coordinates) or failed.
  void WriteMuscles(Read& read, const std::vector<std::string>& reportedBefore, const md::LocalFrame& frame,
    std::vector<PassOutcome>& outcomes, double seconds);
  enum class HullReady
  {
    Yes,
    No,     ///< failed: `failure` says why, reported
    Stopped ///< by the user
  };
  /// Muscle m's hull (given: checked; else built) and its mean value coordinates, kept in Kept.
  HullReady KeepHull(const PassInput& in, size_t m, const md::TriangleMesh* givenHull, const std::string& hullLabel,
    std::string& failure, int& result);
  /// The pass on the muscles' surfaces or on their hulls: each muscle's outcome, or its failure
  /// in `failures` (`reportedBefore`: the failures already reported when the deformation
  /// started); false (with RequestData's `result`) when the run stops.
  bool PassOnSurface(const PassInput& in, std::vector<std::string>& failures, std::vector<std::string>& reportedBefore,
    std::vector<PassOutcome>& outcomes, int& result);
  bool PassOnHull(const PassInput& in, bool hullGiven, std::vector<md::TriangleMesh>& hulls,
    const std::vector<mdvtk::Leaf>& hullLeaves, const std::vector<size_t>& hullOf, std::vector<std::string>& failures,
    std::vector<std::string>& reportedBefore, std::vector<PassOutcome>& outcomes, int& result);
  std::unique_ptr<RestPoseCache> Kept;
};
