// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkInterpolatedMuscleDeformation
 * @brief   Deforms muscles from the rest pose to the current pose by the interpolation method.
 *
 * Hajkova & Kohout's interpolation method: the motion is split into
 * NumberOfSteps steps; at each step the bones and the matched action lines
 * are interpolated (BoneInterpolationMode), the muscles are deformed from
 * the previous step's result (all together, obstacles for each other and
 * for no bone to enter), then the static intersections are resolved and
 * the volume each muscle had in the rest pose is given back. Overlap the
 * rest pose already has (scans overlap the bones) is left alone.
 *
 * DeformationMesh MUSCLE_SURFACE (default) solves each step on every point of
 * the muscle's own surface (docs/DESIGN.md section 7): the answer does not
 * depend on a hull, moves with the input continuously, and no point enters a
 * bone or another muscle; where an action line runs through a bone the muscle
 * is drawn round it (see the XML documentation). HULL is the paper's pass:
 * each step's deformation solved on a coarse hull that the muscle follows.
 * HullMode Refit (default) keeps each muscle's rest-pose hull and mean value
 * coordinates for the whole motion and refits the hull to the resolved mesh by
 * least squares after each step, keeping the residual as per-point detail;
 * Rebuild builds a new hull and mapping before every step, as the paper did.
 *
 * Inputs: 0 Input, muscles in the rest pose; 1 BonesRest and 2 BonesCurrent,
 * the bones in both poses (blocks paired by name, else by order; the same
 * points); 3 ActionLinesRest and 4 ActionLinesCurrent, the raw action lines
 * in both poses, one block per muscle (by name, else by order), polylines
 * paired by order inside a block and matched as ActionLineMatching does;
 * 5 Attachments (optional), landmarks of the muscles' attachment areas (AttachmentAreas).
 *
 * Outputs 1 (Bones) and 2 (ActionLines): the bones and the matched action
 * lines at the same step, as the method moved them, in the structure of
 * BonesRest and ActionLinesRest. Output 3 (Measures): a table of the
 * muscles' field data below, one row per muscle (column Muscle: its name).
 * Output 4 (Fibres): each muscle's fibres at the same step (NumberOfFibres,
 * made in the rest pose, carried by the muscle), a block of polylines per
 * muscle with cell data FibreLength.
 *
 * Output 0: the muscles at the requested time step j (0 = rest pose, N =
 * current pose; every step is computed once and kept), point arrays
 * Displacement (from the rest pose) and StaticShift (step j's static
 * resolution), and field data per muscle: VolumeChangePercent,
 * NewPenetrationCount, MaxNewPenetrationDepth, NewBonePenetrationCount,
 * MaxNewBonePenetrationDepth, MaxStaticShift (steps 1..j), StepStaticShift,
 * SharpEdgeCount, FlippedTriangleCount, NumberOfIterations (steps 1..j),
 * Converged, PointsFrozenInObstacles, InterpolationStep, NumberOfSteps,
 * HullSeconds (the rest hull and its mapping, and each step's refit or rebuild;
 * with MUSCLE_SURFACE the muscle's full-mesh energy), StepSeconds,
 * ElapsedSeconds (the whole run).
 */
#pragma once

#include "MuscleDeformationFiltersModule.h"

#include <vtkPassInputTypeAlgorithm.h>

#include <memory>
#include <string>
#include <vector>

namespace md
{
struct RestMappingCache;
struct MuscleMotion;
struct BoneMotion;
struct LocalFrame;
struct InterpolationParameters;
}
namespace mdvtk
{
struct Leaf;
struct MadeFibres;
class FibreKeeper;
}
class vtkMultiBlockDataSet;

class MUSCLEDEFORMATIONFILTERS_EXPORT vtkInterpolatedMuscleDeformation : public vtkPassInputTypeAlgorithm
{
public:
  static vtkInterpolatedMuscleDeformation* New();
  vtkTypeMacro(vtkInterpolatedMuscleDeformation, vtkPassInputTypeAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void SetBonesRestConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void SetBonesCurrentConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(2, output); }
  void SetActionLinesRestConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(3, output); }
  void SetActionLinesCurrentConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(4, output); }
  void SetAttachmentsConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(5, output); }

  enum InterpolationModes
  {
    LINEAR = 0,
    RIGID = 1,
  };
  enum HullModes
  {
    REFIT = 0,
    REBUILD = 1,
  };
  enum DeformationMeshes
  {
    HULL = 0,
    MUSCLE_SURFACE = 1,
  };

  /// N; 0 = automatic from MaximumStepDisplacement. Default 4.
  vtkSetClampMacro(NumberOfSteps, int, 0, 10000);
  vtkGetMacro(NumberOfSteps, int);
  /// Largest move of a bone point in one step when NumberOfSteps is 0 (data units). Default 20.
  vtkSetClampMacro(MaximumStepDisplacement, double, 1e-9, VTK_DOUBLE_MAX);
  vtkGetMacro(MaximumStepDisplacement, double);
  /// LINEAR (the paper's eq. 1) or RIGID (default), for bones and action lines.
  vtkSetClampMacro(BoneInterpolationMode, int, LINEAR, RIGID);
  vtkGetMacro(BoneInterpolationMode, int);
  /// MUSCLE_SURFACE (default): each step solved on the muscle's own surface; HULL: on a coarse
  /// hull the muscle follows (the paper's; the Hull, iteration and contact-weight properties apply
  /// to it only).
  vtkSetClampMacro(DeformationMesh, int, HULL, MUSCLE_SURFACE);
  vtkGetMacro(DeformationMesh, int);
  /// With DeformationMesh HULL: REFIT (default) or REBUILD.
  vtkSetClampMacro(HullMode, int, REFIT, REBUILD);
  vtkGetMacro(HullMode, int);
  /// Action-line matching tolerance (normalised arc length). Default 0.01.
  vtkSetClampMacro(MatchingTolerance, double, 0.0, 0.5);
  vtkGetMacro(MatchingTolerance, double);
  /// Share of the static correction each muscle takes against another. Default 0.6.
  vtkSetClampMacro(DeformableShare, double, 0.0, 1.0);
  vtkGetMacro(DeformableShare, double);
  /// Iterations of one step's deformation. Default 200.
  vtkSetClampMacro(MaximumNumberOfIterations, int, 1, 100000);
  vtkGetMacro(MaximumNumberOfIterations, int);
  /// Default 0.01 (data units).
  vtkSetClampMacro(ConvergenceTolerance, double, 1e-12, VTK_DOUBLE_MAX);
  vtkGetMacro(ConvergenceTolerance, double);
  /// Default on.
  vtkSetMacro(PreserveVolume, bool);
  vtkGetMacro(PreserveVolume, bool);
  vtkBooleanMacro(PreserveVolume, bool);
  /// Weight of the rows that push a muscle's points out of a bone that moved
  /// into them, in each step's deformation (against 1 for the action-line
  /// rows). Default 0.5; 0 = the paper's step, where a bone only stops
  /// points that move into it and the static resolution does the rest.
  vtkSetClampMacro(BoneContactWeight, double, 0.0, 100.0);
  vtkGetMacro(BoneContactWeight, double);
  /// Points of each muscle's hull. Default 250.
  vtkSetClampMacro(HullTargetNumberOfPoints, int, 4, 1000000);
  vtkGetMacro(HullTargetNumberOfPoints, int);
  /// Shape regularisation of the Refit least squares (relative). Default 1e-3.
  vtkSetClampMacro(RefitRegularisation, double, 1e-9, 1e3);
  vtkGetMacro(RefitRegularisation, double);

  /// Where the muscles are attached to the bones (docs/DESIGN.md, "Attachment areas"): 0 off
  /// (they move with their action lines only), 1 (default) the areas the landmarks mark (the
  /// Attachments input and AttachmentFileName), and for a muscle with none, the areas at its
  /// action lines' ends near a bone. An area moves rigidly with its bone. Honoured with
  /// DeformationMesh MUSCLE_SURFACE (the hull-based pass moves with the action lines only).
  vtkSetClampMacro(AttachmentAreas, int, 0, 1);
  vtkGetMacro(AttachmentAreas, int);
  /// A landmark table (CSV with a header: muscle, bone, x, y, z, optionally area; the LHDL data
  /// set's attachment_areas_rp_mm.csv reads as it is). Empty: none.
  vtkSetStringMacro(AttachmentFileName);
  vtkGetStringMacro(AttachmentFileName);
  /// How the areas were found, as the output messages said it at the last run.
  const char* GetAttachmentReport() const;

  /// Fibres per muscle, made in the rest pose and carried to every step (output Fibres,
  /// docs/DESIGN.md "Fibres"); 0: none. Default 100.
  vtkSetClampMacro(NumberOfFibres, int, 0, 10000);
  vtkGetMacro(NumberOfFibres, int);

  /// N as resolved by the last RequestInformation.
  vtkGetMacro(ResolvedNumberOfSteps, int);

  /// Rest-pose hulls built so far. A muscle's rest-pose hull and its mean value coordinates depend
  /// on its rest-pose surface and HullTargetNumberOfPoints only, so they are kept: another number
  /// of steps, other bones or action lines, or another deformation setting reuses them; a changed
  /// muscle or hull size rebuilds that muscle's. (HullMode Rebuild's hulls of later steps are
  /// built anew on every run and not counted.)
  int GetHullBuildCount() const;
  /// Full-mesh energies built so far (DeformationMesh MUSCLE_SURFACE). A muscle's energy depends on
  /// its rest-pose surface and its matched action lines in the rest pose only, so it is kept like
  /// the hulls, with the columns of its inverse found so far.
  int GetSurfaceEnergyBuildCount() const;
  /// Times the fibres were made. They depend on the muscles' rest surfaces, action lines and
  /// attachment areas, the bones at rest and NumberOfFibres only, so they are kept like the hulls:
  /// another number of steps, current pose or deformation setting reuses them.
  int GetFibreBuildCount() const;

protected:
  vtkInterpolatedMuscleDeformation();
  ~vtkInterpolatedMuscleDeformation() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestDataObject(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  // The core's defaults (md::InterpolationParameters), set by the constructor.
  int NumberOfSteps;
  double MaximumStepDisplacement;
  int BoneInterpolationMode;
  int DeformationMesh;
  int HullMode;
  double MatchingTolerance;
  double DeformableShare;
  int MaximumNumberOfIterations;
  double ConvergenceTolerance;
  bool PreserveVolume;
  double BoneContactWeight;
  int HullTargetNumberOfPoints;
  double RefitRegularisation;
  int ResolvedNumberOfSteps;
  int NumberOfFibres;
  int AttachmentAreas = 1;
  char* AttachmentFileName = nullptr;
  std::string AttachmentReport;
  int ShownNumberOfSteps = 0; // N and step of the last output, to say when N changes under a time
  int ShownStep = 0;

private:
  vtkInterpolatedMuscleDeformation(const vtkInterpolatedMuscleDeformation&) = delete;
  void operator=(const vtkInterpolatedMuscleDeformation&) = delete;
  struct Cache;
  struct Lines;
  static constexpr int kPorts = 6;
  /// Reads the inputs and runs the method, into Computed: RequestData's result.
  int Deform(vtkDataObject* const inputs[kPorts], const std::vector<mdvtk::Leaf>& muscles);
  /// The muscles' attachment areas (AttachmentAreas) in `frame`, said in the output messages.
  void Attach(vtkDataObject* landmarks, const md::LocalFrame& frame, std::vector<md::MuscleMotion>& motions,
    const std::vector<md::BoneMotion>& bones);
  /// Brings `motions` (the muscles read, at their blocks Computed->blockOf) into `frame` and
  /// matches their action lines; a muscle whose lines fail is left out, `kept` the indices of the
  /// others. False (with RequestData's `result`) when the user stopped the run.
  bool MatchLines(const std::vector<mdvtk::Leaf>& muscles, const Lines& lines, const md::LocalFrame& frame,
    std::vector<md::MuscleMotion>& motions, std::vector<size_t>& kept, int& result);
  md::InterpolationParameters Parameters(const md::LocalFrame& frame);
  /// The step the request asks for (said when NumberOfSteps changed under the same time).
  int StepToShow(vtkInformation* request, vtkInformationVector* outputVector);
  /// Output 0, the muscles at `step`, and output 3, their measures.
  void WriteMuscles(
    vtkDataObject* input, const std::vector<mdvtk::Leaf>& muscles, int step, vtkInformationVector* outputVector);
  /// Outputs 1 and 2: the bones and action lines at `step`.
  bool WriteBonesAndLines(vtkDataObject* const inputs[5], int step, vtkInformationVector* outputVector);
  /// Each muscle's fibres (NumberOfFibres), made in the rest pose of `motions` and `bones` (the
  /// local frame), or kept from the last run when made from the same (KeptFibres), into Computed.
  void MakeFibres(const std::vector<md::MuscleMotion>& motions, const std::vector<md::BoneMotion>& bones);
  /// Output 4: each muscle's fibres at `step`, carried by the muscle there, out of the bones there.
  void WriteFibres(const std::vector<mdvtk::Leaf>& muscles, int step, vtkMultiBlockDataSet* output) const;
  std::unique_ptr<Cache> Computed;
  std::unique_ptr<md::RestMappingCache> KeptRest;
  std::unique_ptr<mdvtk::FibreKeeper> KeptFibres;
};
