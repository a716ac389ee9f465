// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkOpenSimModelReader
 * @brief   Reads an OpenSim model (.osim) and, optionally, a motion (.mot/.sto): bodies, muscle
 *          paths, body transforms and wrap objects in the rest pose and at the current time.
 *
 * Forward kinematics of the model's coordinates (OpenSim 3.x and 4.x files; CustomJoint and the
 * other joint types; SimmSpline and the other functions; conditional and moving path points;
 * coordinate couplers). The motion's times (seconds) are advertised as time steps.
 *
 * Output ports (each but 4 a vtkMultiBlockDataSet of named vtkPolyData blocks):
 * 0 Bodies at the current time (one block per body, its mesh files; field data
 *   RestToCurrentTransform), 1 MusclePaths at the current time (one polyline per muscle; point
 *   data PathPointName, PathPointBody; field data PathLength, MuscleType, MetresPerLengthUnit and,
 *   for a muscle, OpenSim's max_isometric_force (N), optimal_fiber_length, tendon_slack_length
 *   (in the output's unit) and pennation_angle_at_optimal (radians)), 2 BodiesRest, 3 MusclePathsRest, 4 BodyTransforms
 * (a vtkTable: each body's rigid transform from the rest pose to the current time, x_CP = R x_RP + t), 5 WrapObjects at
 * the current time, 6 MomentArms (a vtkTable, a row per frame of the motion, or one at the rest pose: the time, the
 * coordinates that move, each path's length and its moment arm about each of them, r = -dL/dq, OpenSim's sign).
 *
 * Every output is in the frame that ReferenceBody has at the rest pose (ground when empty; with
 * FollowReferenceBody, in its frame at each time, so that it stays still), in
 * the model's units times Scale (1000: millimetres for a model in metres), so that surfaces
 * scanned in that body's frame, in the rest pose, lie where the model's bodies do.
 */
#pragma once

#include "MuscleDeformationFiltersModule.h"

#include <vtkMultiBlockDataSetAlgorithm.h>

#include <memory>
#include <string>
#include <vector>

class vtkFieldData;
class vtkTable;
namespace md
{
struct RigidTransform;
namespace osim
{
struct Path;
}
}

class MUSCLEDEFORMATIONFILTERS_EXPORT vtkOpenSimModelReader : public vtkMultiBlockDataSetAlgorithm
{
public:
  static vtkOpenSimModelReader* New();
  vtkTypeMacro(vtkOpenSimModelReader, vtkMultiBlockDataSetAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum OutputPorts
  {
    BODIES = 0,
    MUSCLE_PATHS = 1,
    BODIES_REST = 2,
    MUSCLE_PATHS_REST = 3,
    BODY_TRANSFORMS = 4,
    WRAP_OBJECTS = 5,
    MOMENT_ARMS = 6
  };

  enum AngleUnits
  {
    ANGLES_AS_FILE_SAYS = 0,
    ANGLES_IN_DEGREES = 1,
    ANGLES_IN_RADIANS = 2
  };

  /// The .osim file.
  vtkGetStringMacro(FileName);
  vtkSetStringMacro(FileName);

  /// The motion (.mot or .sto); none: the model stands in its rest pose.
  vtkGetStringMacro(MotionFileName);
  vtkSetStringMacro(MotionFileName);

  /// Further folders to search for mesh files (separated by ';'), after the model's folder and
  /// its Geometry/ and geometry/ subfolders.
  vtkGetStringMacro(GeometrySearchPath);
  vtkSetStringMacro(GeometrySearchPath);

  /// Coordinates of the rest pose, "name=value ..." (rotational ones in degrees); the others keep
  /// their default values.
  vtkGetStringMacro(RestPoseCoordinates);
  vtkSetStringMacro(RestPoseCoordinates);

  /// A motion file whose first row is the rest pose (a static trial in the scan pose), read as
  /// MotionFileName is; RestPoseCoordinates, when given, override its values.
  vtkGetStringMacro(RestPoseFileName);
  vtkSetStringMacro(RestPoseFileName);

  /// The body whose rest-pose frame the outputs are expressed in; empty: ground.
  vtkGetStringMacro(ReferenceBody);
  vtkSetStringMacro(ReferenceBody);

  /// Keep ReferenceBody where it is in the rest pose at every time: the outputs are in that
  /// body's frame at each time, and the model moves about it (a walk in place, the pelvis still).
  /// Default off (the outputs in its rest-pose frame, the body moving as the motion moves it).
  vtkSetMacro(FollowReferenceBody, bool);
  vtkGetMacro(FollowReferenceBody, bool);
  vtkBooleanMacro(FollowReferenceBody, bool);

  /// Multiplies every length (1000: millimetres for a model in metres). Default 1.
  vtkSetClampMacro(Scale, double, 1e-9, 1e9);
  vtkGetMacro(Scale, double);

  /// How the motion's angles are read. Default: as the file says.
  vtkSetClampMacro(AngleUnit, int, ANGLES_AS_FILE_SAYS, ANGLES_IN_RADIANS);
  vtkGetMacro(AngleUnit, int);

  /// Skip motion columns that name no coordinate of the model (with a warning) instead of failing,
  /// as OpenSim does. Default on.
  vtkSetMacro(IgnoreUnknownColumns, bool);
  vtkGetMacro(IgnoreUnknownColumns, bool);
  vtkBooleanMacro(IgnoreUnknownColumns, bool);

  /// The motion time (seconds) of the current pose when the pipeline asks for no time: for
  /// filters that advertise time steps of their own, such as InterpolatedMuscleDeformation.
  /// The frame nearest to it is used, with a warning when it lies outside the motion's times.
  /// Default 0: the first frame, also of a motion that starts later (no warning then).
  vtkSetMacro(CurrentPoseTime, double);
  vtkGetMacro(CurrentPoseTime, double);

  /// Play the motion: advertise its times as time steps and show the frame of the animation time.
  /// Off: no time steps; the outputs hold the pose at CurrentPoseTime (a fixed current pose for
  /// the interpolation method). Default on.
  vtkSetMacro(PlayMotion, bool);
  vtkGetMacro(PlayMotion, bool);
  vtkBooleanMacro(PlayMotion, bool);

  /// Spreads the jump of a path where a conditional path point comes or goes (a via point
  /// active over part of its coordinate's range) over this many degrees of the coordinate beyond
  /// the point's range: the point fades onto the straight segment between its neighbours, so the
  /// paths, and muscles deformed along them, move continuously. Paths are OpenSim's wherever
  /// their points are active. Default 0: OpenSim's paths, which jump (a warning names them when
  /// the motion makes them jump). The MomentArms table is always OpenSim's.
  vtkSetClampMacro(ConditionalPointFade, double, 0.0, 180.0);
  vtkGetMacro(ConditionalPointFade, double);
  /// For moment arms from small steps of a pose (MotionMuscleDeformation's fibres): with a motion
  /// playing and a step > 0 (degrees), every frame also gives its pose stepped by +-MomentArmStep
  /// in each rotational coordinate the motion moves (a coupled coordinate follows, as in OpenSim):
  /// BodyTransforms gets a row per body and stepped pose (column Pose: "<coordinate>+" or
  /// "<coordinate>-"; empty for the frame's own rows) and field data MomentArmStep, and each path
  /// of MusclePaths a point array PointsAt(<coordinate>+-) with its points there. A stepped path
  /// keeps the frame's conditional points and how far they have faded: the path as it is at the
  /// frame, whose moment arm OpenSim gives. Default 0: none.
  vtkSetClampMacro(MomentArmStep, double, 0.0, 10.0);
  vtkGetMacro(MomentArmStep, double);
  /// Read the bodies' mesh files. Default on.
  vtkSetMacro(LoadGeometry, bool);
  vtkGetMacro(LoadGeometry, bool);
  vtkBooleanMacro(LoadGeometry, bool);

  /// Times of the motion (seconds), after RequestInformation.
  int GetNumberOfTimeSteps();
  double GetTimeStep(int index);
  /// How many times the model file was read (a change of time does not read it again).
  vtkGetMacro(ModelReadCount, int);

protected:
  vtkOpenSimModelReader();
  ~vtkOpenSimModelReader() override;

  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* FileName = nullptr;
  char* MotionFileName = nullptr;
  char* GeometrySearchPath = nullptr;
  char* RestPoseCoordinates = nullptr;
  char* RestPoseFileName = nullptr;
  char* ReferenceBody = nullptr;
  bool FollowReferenceBody = false;
  double Scale = 1.0;
  static constexpr double kDefaultCurrentPoseTime = 0.0;
  double CurrentPoseTime = kDefaultCurrentPoseTime;
  bool PlayMotion = true;
  int AngleUnit = ANGLES_AS_FILE_SAYS;
  bool IgnoreUnknownColumns = true;
  bool LoadGeometry = true;
  double ConditionalPointFade = 0.0;
  double MomentArmStep = 0.0;
  int ModelReadCount = 0;

private:
  vtkOpenSimModelReader(const vtkOpenSimModelReader&) = delete;
  void operator=(const vtkOpenSimModelReader&) = delete;

  struct Internals;
  std::unique_ptr<Internals> Internal;
  /// A frame's pose stepped in one coordinate (MomentArmStep).
  struct SteppedPose;
  /// The stepped poses of the frame at `q` (none without MomentArmStep or a motion playing).
  std::vector<SteppedPose> SteppedPoses(const std::vector<double>& q) const;
  bool Load(); ///< (re)reads what changed; reports and returns false on failure
  /// The parts of Load, each only when what it reads from changed (throw md::InputError).
  void LoadModel(const std::string& fileName, std::vector<std::string>& warnings);
  void LoadMotion(std::vector<std::string>& warnings);
  void LoadRestPose();
  /// Ground in pose `poses` -> the output frame (lengths not yet scaled): the reference body's
  /// rest frame, or with FollowReferenceBody its frame in `poses`.
  md::RigidTransform OutputFrame(const std::vector<md::RigidTransform>& poses) const;
  /// Body `body` in pose `poses` -> the output frame (lengths not yet scaled).
  md::RigidTransform Placed(const std::vector<md::RigidTransform>& poses, size_t body) const;
  /// The bodies' meshes as blocks of `tree`, each with RestToCurrentTransform; throws
  /// md::InputError for a body placed at non-finite coordinates (`when`: "at time 0.5").
  void WriteBodies(
    const std::vector<md::RigidTransform>& poses, vtkMultiBlockDataSet* tree, const std::string& when) const;
  /// The muscles' paths at `coordinates` as polylines, blocks of `tree` (throws as WriteBodies),
  /// with their points at each of `stepped` (point arrays PointsAt(<pose>)).
  void WritePaths(const std::vector<double>& coordinates, const std::vector<md::RigidTransform>& poses,
    vtkMultiBlockDataSet* tree, const std::string& when, const std::vector<SteppedPose>& stepped = {}) const;
  /// Outputs WRAP_OBJECTS and BODY_TRANSFORMS at `poses` (and `stepped`).
  void WriteWrapsAndTransforms(const std::vector<md::RigidTransform>& poses, const std::vector<double>& q, double time,
    const std::vector<SteppedPose>& stepped, vtkInformationVector* outputVector) const;
  /// The path's MuscleType, MetresPerLengthUnit and, where the model gives them, its muscle's
  /// properties under OpenSim's names (lengths in the output's unit).
  void WriteMuscleProperties(const md::osim::Path& path, vtkFieldData* fieldData) const;
  /// Output MOMENT_ARMS, computed once per model, motion and Scale.
  void WriteMomentArms(vtkTable* table);
  /// Output BODY_TRANSFORMS: each body's rest-to-current motion; the time and coordinates as field data.
  void WriteTransforms(const std::vector<md::RigidTransform>& poses, const std::vector<double>& coordinates,
    double time, const std::vector<SteppedPose>& stepped, vtkTable* table) const;
};
