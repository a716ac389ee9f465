// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkHullDecimation
 * @brief   The coarse outer hull of each muscle: closed, manifold, enclosing it.
 *
 * Progressive hulls (Sander et al. 2000; Platis & Theoharis 2003): edges are
 * collapsed in order of the volume they add, each new point placed by a small
 * optimisation (least volume added, outside the plane of every triangle
 * around the edge), so every hull encloses the previous one and hence the
 * muscle. Collapses that would break manifoldness, make slivers
 * (MinimumAngle), turn a triangle too far (MaximumNormalDeviation), fold the
 * surface (MaximumFoldAngle) or make it intersect itself are refused.
 *
 * Scanned input is repaired first where that is safe, with a warning naming
 * what was done: unused and duplicate points, degenerate, duplicate and
 * back-to-back triangles, non-triangle polygons (triangulated), triangles
 * oriented against their neighbours, non-manifold edges where two sheets
 * touch (cut apart), small self-intersections (undone by smoothing the few
 * points involved; their original positions are still enclosed). Open
 * surfaces, empty or flat input, and a TargetNumberOfPoints larger than the
 * input are refused with an error.
 *
 * Output: one hull per input block (same structure and names), with field data
 * HullVolume, MuscleVolume, HullVolumeRatio, NumberOfCollapses,
 * ElapsedSeconds, and with VerifyEnclosure on PointsOutsideHull (muscle points
 * outside the hull, every point tested) and HullSelfIntersections (both 0).
 */
#pragma once

#include "MuscleDeformationFiltersModule.h"

#include <vtkPassInputTypeAlgorithm.h>
#include <vtkSmartPointer.h>

class vtkPolyData;
namespace md
{
struct MuscleHull;
}
namespace mdvtk
{
struct Leaf;
}

class MUSCLEDEFORMATIONFILTERS_EXPORT vtkHullDecimation : public vtkPassInputTypeAlgorithm
{
public:
  static vtkHullDecimation* New();
  vtkTypeMacro(vtkHullDecimation, vtkPassInputTypeAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Points of each hull. Default 250.
  vtkSetClampMacro(TargetNumberOfPoints, int, 4, VTK_INT_MAX);
  vtkGetMacro(TargetNumberOfPoints, int);

  /// Smallest angle (degrees) a collapse may create, unless the triangles it
  /// replaces already had a smaller one. Default 10.
  vtkSetClampMacro(MinimumAngle, double, 0.0, 59.0);
  vtkGetMacro(MinimumAngle, double);

  /// Largest turn (degrees) of a triangle's normal in one collapse. Default 90.
  vtkSetClampMacro(MaximumNormalDeviation, double, 1.0, 180.0);
  vtkGetMacro(MaximumNormalDeviation, double);

  /// Largest angle (degrees) between the normals of neighbouring triangles
  /// after a collapse. Default 150.
  vtkSetClampMacro(MaximumFoldAngle, double, 90.0, 180.0);
  vtkGetMacro(MaximumFoldAngle, double);

  /// Check that every muscle point is inside the hull and that the hull does
  /// not intersect itself; results in field data, a warning if either fails.
  /// Default on.
  vtkSetMacro(VerifyEnclosure, bool);
  vtkGetMacro(VerifyEnclosure, bool);
  vtkBooleanMacro(VerifyEnclosure, bool);

protected:
  vtkHullDecimation();
  ~vtkHullDecimation() override = default;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  // The core's defaults (md::HullParameters), set by the constructor.
  int TargetNumberOfPoints;
  double MinimumAngle;
  double MaximumNormalDeviation;
  double MaximumFoldAngle;
  bool VerifyEnclosure = true;

private:
  vtkHullDecimation(const vtkHullDecimation&) = delete;
  void operator=(const vtkHullDecimation&) = delete;
  /// The output block of `leaf`'s hull `built` (`converted` polygons or strips triangulated, in
  /// `seconds`), with its measures; what was repaired or not reached is said.
  vtkSmartPointer<vtkPolyData> HullOutput(
    const mdvtk::Leaf& leaf, const md::MuscleHull& built, vtkIdType converted, double seconds);
};
