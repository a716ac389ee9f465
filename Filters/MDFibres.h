// SPDX-License-Identifier: BSD-3-Clause
// What the deformation filters share about fibres and moment arms (Anatomy/MuscleFibres.h,
// Anatomy/TendonExcursion.h): the fibres made and reported, written as polylines, the pose's
// coordinates read from the bones' field data, and the MomentArms table. Not part of the public
// API.
#pragma once

#include "Anatomy/MuscleFibres.h"
#include "Method/MotionDeformation.h"

#include <vtkSmartPointer.h>

#include <memory>
#include <string>
#include <vector>

class vtkAlgorithm;
class vtkDataObject;
class vtkPolyData;
class vtkTable;

namespace mdvtk
{
/// The coordinates of a motion's poses, as the bones over time carry them in their field data
/// (MoveWithBodies passes OpenSimModelReader's BodyTransforms' on): every single number but Time,
/// the rotational ones (in degrees there) listed in RotationalCoordinates.
struct PoseCoordinates
{
  std::vector<std::string> names;
  std::vector<char> rotational;
};

/// The pose's values of `names`' coordinates in `bones`' field data (radians for a rotational
/// one), NaN for one it lacks; with `names` empty, names them first (none: no coordinates).
std::vector<double> ReadCoordinates(vtkDataObject* bones, PoseCoordinates& names);

/// Each muscle's fibres and the rest trees of the bones they keep out of, with what they were
/// made from, so that another run from the same muscles and bones (a setting of the deformation
/// changed) takes them as they are (FibreKeeper).
struct MadeFibres
{
  std::vector<std::unique_ptr<md::MuscleFibres>> ofMuscle; ///< [muscle]; null: none
  std::vector<md::TriangleTree> boneTrees;                 ///< the bones' at rest; none without fibres
  int count = 0;                                           ///< what they were made from
  std::vector<md::MotionDeformation::Muscle> muscles;
  std::vector<md::MotionDeformation::Bone> bones;
  std::vector<char> failed;
};

/// A deformation filter's fibres, kept across its runs while what they are made from stays the
/// same, bit for bit: the count, the muscles (names, rest surfaces, lines, knots, attachment
/// areas), the bones at rest and the failures. Making them costs seconds (the LHDL hip's four
/// muscles: about 3.5 s); keeping them, a comparison of the inputs.
class FibreKeeper
{
public:
  /// The kept fibres when made from these inputs; else each muscle's `count` fibres (0: none)
  /// made anew in the rest pose between its attachment areas (or its ends along its lines) and
  /// out of the bones, a muscle whose fibres cannot be made getting none and a warning naming it,
  /// the output messages saying what was made (`filterName` first); these are then kept.
  std::shared_ptr<const MadeFibres> KeepOrMake(vtkAlgorithm* filter, const std::string& filterName, int count,
    const std::vector<md::MotionDeformation::Muscle>& muscles, const std::vector<md::MotionDeformation::Bone>& bones,
    const std::vector<char>& failed);
  /// Times fibres were made.
  int Builds() const { return this->builds; }

private:
  std::shared_ptr<const MadeFibres> kept;
  int builds = 0;
};

/// The names of `lines`' polylines (cell data ActionLineName), else "<muscle>" for one line and
/// "<muscle> line <i>" for several; `count` names.
std::vector<std::string> LineNames(vtkPolyData* lines, const std::string& muscle, size_t count);

/// A bone where it is now (`now`, its points) as an obstacle of the fibres: its rest tree (and
/// distance grid) and the rigid motion there when it moved rigidly (to md::kRigidObstacleShare of
/// its size); else `moved`, a copy of the rest tree refitted to `now`.
md::FibreObstacle BoneWhereItIs(
  const md::TriangleTree& restTree, std::unique_ptr<md::TriangleTree>& moved, const md::Points& now);

/// A muscle's fibres as polylines: cell data FibreLength (`lengths`).
vtkSmartPointer<vtkPolyData> FibrePolylines(const md::Points& points, int perFibre, const std::vector<double>& lengths);

/// The lengths at a frame's pose stepped in one coordinate (OpenSimModelReader's MomentArmStep),
/// the muscles deformed there from the frame's own state.
struct SteppedLengths
{
  int coordinate = -1;                           ///< PoseCoordinates' index
  double step = 0;                               ///< how far that coordinate was stepped (radians, signed)
  std::vector<std::vector<double>> fibreLengths; ///< [muscle][fibre]
  std::vector<std::vector<double>> lineLengths;  ///< [muscle][line]
};

/// One frame of a motion, for the MomentArms table.
struct FrameLengths
{
  double time = 0;
  std::vector<double> coordinates;               ///< PoseCoordinates' order
  std::vector<std::vector<double>> fibreLengths; ///< [muscle][fibre]
  std::vector<std::vector<double>> lineLengths;  ///< [muscle][line]
  std::vector<SteppedLengths> stepped;           ///< none without stepped poses
};

/// The stepped poses a motion's bones carry (OpenSimModelReader's MomentArmStep, passed on by
/// MoveWithBodies: field data MomentArmStep on `bones`, point arrays PointsAt(<pose>) on each
/// bone, of which `bone` is one): each pose's name and, as SteppedLengths, its coordinate (by
/// `coordinates`' names; -1 for none of them) and step. None where the bones carry none.
std::vector<std::pair<std::string, SteppedLengths>> SteppedPosesOf(
  vtkDataObject* bones, vtkPolyData* bone, const PoseCoordinates& coordinates);

/// The MomentArms table of a motion's frames (in order, consecutive): per frame Time, the
/// coordinates that move (degrees where rotational), and for each muscle its fibres' median,
/// smallest and largest length and moment arm about each of those coordinates, then each
/// action line's length and moment arm, r = -dL/dq (per fibre, then over fibres). About a
/// coordinate a frame was stepped in (SteppedLengths at +-step), the central difference of the
/// stepped lengths; else the difference between frames (md::MomentArmsAlongMotion's). Field data
/// MomentArmsFrom says which.
void WriteMomentArms(const std::vector<FrameLengths>& frames, const PoseCoordinates& coordinates,
  const std::vector<std::string>& muscleNames, const std::vector<std::vector<std::string>>& lineNames, vtkTable* table);
}
