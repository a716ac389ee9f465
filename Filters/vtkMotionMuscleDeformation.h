// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkMotionMuscleDeformation
 * @brief   Deforms muscles through a whole motion: each frame from the one before it.
 *
 * Inputs: 0 Input, the muscles in the rest pose; 1 BonesRest, the bones in the rest pose;
 * 2 BonesMotion, the same bones over time (a time-varying source: OpenSimModelReader with
 * PlayMotion and MoveWithBodies, or any source with time steps); 3 ActionLinesRest, the raw
 * action lines in the rest pose, one block per muscle; 4 ActionLinesMotion, the same lines over
 * time; 5 Attachments (optional), landmarks of the muscles' attachment areas (AttachmentAreas).
 * Blocks pair by name, else by order, as in InterpolatedMuscleDeformation. Each frame's
 * action line is taken at the rest line's points (the point at each rest point's normalised arc
 * length), so a path that gains or loses a point keeps its points.
 *
 * The filter advertises the motion's times. The muscles at frame k are deformed from those at
 * frame k - 1 (the first from the rest pose) by the interpolation method's steps on the muscles'
 * surfaces (docs/DESIGN.md section 8): as many steps as keep each bone point's move within
 * MaximumStepDisplacement (the first frame: NumberOfSteps when not 0), all muscles together,
 * with contact, the static resolution and the volume restore.
 *
 * Frames are computed once and kept (up to CacheMemoryLimit megabytes; the measures of every
 * frame are kept whatever the limit): a request for frame k computes what is missing from the
 * last frame kept before k, and going back to a kept frame computes nothing. A change of an input
 * or of a property other than CacheMemoryLimit starts the motion again (the muscles' energies,
 * which depend on the rest pose alone, are kept). Stopping a run keeps the frames done.
 *
 * Outputs: 0 the muscles at the requested time (point array Displacement from the rest pose;
 * field data per muscle: VolumeChangePercent, NewPenetrationCount, MaxNewPenetrationDepth,
 * NewBonePenetrationCount, MaxNewBonePenetrationDepth, MaxStaticShift, SharpEdgeCount,
 * FlippedTriangleCount, NumberOfIterations and FrameSeconds of this frame, Converged,
 * SecondDifference and SmoothnessRatio, Frame, Time); 1 the bones and 2 the action lines at that
 * time, as the method used them; 3 MeasuresOverTime, a table with one row per frame computed so
 * far (Time, Frame, Steps, FrameSeconds, and each muscle's measures as "<measure> (<muscle>)").
 */
#pragma once

#include "MuscleDeformationFiltersModule.h"

#include <vtkPassInputTypeAlgorithm.h>

#include <memory>
#include <string>

class vtkMultiBlockDataSet;
class vtkTable;
namespace md
{
struct MotionPose;
}

class MUSCLEDEFORMATIONFILTERS_EXPORT vtkMotionMuscleDeformation : public vtkPassInputTypeAlgorithm
{
public:
  static vtkMotionMuscleDeformation* New();
  vtkTypeMacro(vtkMotionMuscleDeformation, vtkPassInputTypeAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void SetBonesRestConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void SetBonesMotionConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(2, output); }
  void SetActionLinesRestConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(3, output); }
  void SetActionLinesMotionConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(4, output); }
  void SetAttachmentsConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(5, output); }

  enum InterpolationModes
  {
    LINEAR = 0,
    RIGID = 1,
  };

  /// Steps from the rest pose to the first frame; 0 (default): as MaximumStepDisplacement says.
  vtkSetClampMacro(NumberOfSteps, int, 0, 10000);
  vtkGetMacro(NumberOfSteps, int);
  /// Largest move of a bone point in one step (data units); frames farther apart get more
  /// steps. Default 20.
  vtkSetClampMacro(MaximumStepDisplacement, double, 1e-9, VTK_DOUBLE_MAX);
  vtkGetMacro(MaximumStepDisplacement, double);
  /// Between two frames, bones and action lines move RIGID (default) or LINEAR.
  vtkSetClampMacro(BoneInterpolationMode, int, LINEAR, RIGID);
  vtkGetMacro(BoneInterpolationMode, int);
  /// Share of the static correction each muscle takes against another. Default 0.6.
  vtkSetClampMacro(DeformableShare, double, 0.0, 1.0);
  vtkGetMacro(DeformableShare, double);
  /// Default on.
  vtkSetMacro(PreserveVolume, bool);
  vtkGetMacro(PreserveVolume, bool);
  vtkBooleanMacro(PreserveVolume, bool);
  /// Megabytes the kept frames may take (the muscles, the bones and where the motion stood);
  /// beyond it the frames farthest from the one shown are dropped. Changing it keeps the frames.
  /// Default 2048.
  vtkSetClampMacro(CacheMemoryLimit, double, 1.0, VTK_DOUBLE_MAX);
  vtkGetMacro(CacheMemoryLimit, double);

  /// Where the muscles are attached to the bones (docs/DESIGN.md, "Attachment areas"): 0 off
  /// (they move with their action lines only), 1 (default) the areas the landmarks mark (the
  /// Attachments input and AttachmentFileName), and for a muscle with none, the areas at its
  /// action lines' ends near a bone. An area moves rigidly with its bone.
  vtkSetClampMacro(AttachmentAreas, int, 0, 1);
  vtkGetMacro(AttachmentAreas, int);
  /// A landmark table (CSV with a header: muscle, bone, x, y, z, optionally area; the LHDL data
  /// set's attachment_areas_rp_mm.csv reads as it is). Empty: none.
  vtkSetStringMacro(AttachmentFileName);
  vtkGetStringMacro(AttachmentFileName);
  /// Fibres per muscle, made in the rest pose and carried to every frame (docs/DESIGN.md,
  /// "Fibres"); 0: none. Default 100.
  vtkSetClampMacro(NumberOfFibres, int, 0, 10000);
  vtkGetMacro(NumberOfFibres, int);
  /// How the areas were found, as the output messages said it at the last start.
  const char* GetAttachmentReport() const;

  /// Frames computed so far (a frame shown again from the cache does not count).
  int GetFramesComputed() const;
  /// Frames kept, and the megabytes they take.
  int GetFramesKept() const;
  double GetCacheMegabytes() const;
  /// Full-mesh energies built so far (kept across changes of the motion or the properties).
  int GetSurfaceEnergyBuildCount() const;
  /// Times the fibres were made (kept, like the energies, while the muscles' rest surfaces, action
  /// lines and attachment areas, the bones at rest and NumberOfFibres stay the same).
  int GetFibreBuildCount() const;

protected:
  vtkMotionMuscleDeformation();
  ~vtkMotionMuscleDeformation() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int RequestDataObject(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  int NumberOfSteps = 0; // automatic: frames far apart get more steps
  // The core's defaults (md::InterpolationParameters), set by the constructor.
  double MaximumStepDisplacement;
  int BoneInterpolationMode;
  double DeformableShare;
  bool PreserveVolume;
  double CacheMemoryLimit = 2048.0;
  int AttachmentAreas = 1;
  char* AttachmentFileName = nullptr;
  int NumberOfFibres = 100;

private:
  vtkMotionMuscleDeformation(const vtkMotionMuscleDeformation&) = delete;
  void operator=(const vtkMotionMuscleDeformation&) = delete;
  struct Internals;
  struct Signature;
  struct Leaves;
  struct MovingBones;
  /// What the frames depend on, and the inputs of this pass.
  Signature SignatureOf(vtkInformationVector** inputVector, vtkDataObject* inputs[5]);
  /// Ends the passes over the motion with `result`, or asks the executive for one more.
  int Stop(vtkInformation* request, int result);
  int GoOn(vtkInformation* request);
  /// Reads the rest pose and makes the motion's deformation; false with RequestData's `result`.
  bool Start(const Leaves& leaves, vtkDataObject* landmarks, int& result);
  /// Reads the pose of frame In->gather (`bones`, the lines of `leaves`), or its pose `stepped`.
  bool ReadPose(
    const MovingBones& bones, const Leaves& leaves, md::MotionPose& pose, int& result, const std::string& stepped = {});
  /// The lengths at frame In->gather's stepped poses (OpenSimModelReader's MomentArmStep), each
  /// reached from the frame's own state; the motion stays at the frame.
  bool MeasureSteppedPoses(const MovingBones& bones, const Leaves& leaves, int& result);
  /// Deforms the muscles to frame In->gather and keeps it.
  bool ComputeFrame(vtkDataObject* motionBones, const Leaves& leaves, int& result);
  /// The outputs at the frame asked for: the muscles, the bones and lines, the measures table.
  void WriteMuscles(vtkDataObject* input, const Leaves& leaves, vtkDataObject* output);
  void WriteBonesAndLines(vtkDataObject* const inputs[5], const Leaves& leaves, vtkInformationVector* outputVector);
  void WriteTable(const Leaves& leaves, vtkTable* table);
  void WriteFibres(const Leaves& leaves, vtkMultiBlockDataSet* output);
  void WriteMomentArms(const Leaves& leaves, vtkTable* table);
  std::unique_ptr<Internals> In;
};
