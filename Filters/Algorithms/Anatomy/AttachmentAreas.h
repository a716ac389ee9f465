// SPDX-License-Identifier: BSD-3-Clause
// Where each muscle is attached to its bones (docs/DESIGN.md, "Attachment areas"): the parts of
// its surface that a data set's landmarks mark, or, where none are given, that lie at its action
// lines' ends (an OpenSim path's origin and insertion).
#pragma once

#include "Common/Attachment.h"

#include <string>
#include <vector>

namespace md
{
/// The landmarks of one attachment area as a data set gives them: the muscle and the bone by
/// name (either may name no input: FindAttachments then takes the nearest), in the muscles' frame.
struct LandmarkSet
{
  std::string muscle;
  std::string bone;
  std::string area; ///< the area's name ("" when the table has none)
  Points points;
};

/// A landmark table: comma-separated, a header row naming the columns. The muscle's column is
/// `muscle` or `muscle_group`, the bone's `bone` or `attached_to`, the area's (optional) `area`
/// or `cloud`, the coordinates `x`, `y`, `z` or `x_mm`, `y_mm`, `z_mm` (the LHDL data set's
/// attachment_areas_rp_mm.csv). One LandmarkSet per (muscle, area, bone), in the table's order.
/// Throws InputError naming `source` and the line for a missing column, a short row or a value
/// that is not a finite number.
std::vector<LandmarkSet> ParseLandmarkTable(const std::string& text, const std::string& source);

/// Attachment areas found for every muscle, and what to say of how.
struct FoundAttachments
{
  std::vector<std::vector<Attachment>> areas; ///< per muscle
  std::vector<std::string> messages;          ///< how each muscle's areas were found (one line each)
  std::vector<std::string> warnings;          ///< landmarks not used, and why
};

struct AttachmentParameters
{
  /// A landmark set whose median distance from its muscle's surface exceeds this fraction of
  /// the muscle's size marks no part of it (the LHDL gluteus maximus's landmarks on the tibia,
  /// 312 mm from its scan, which ends at the femur) and is not used.
  double farthestLandmarks = 0.25;
  /// Without landmarks: an action line's end marks the muscle's points within its distance from
  /// the surface plus this fraction of the muscle's size that lie within `boneGap` of the
  /// muscle's size of the bone nearest to the end, when that bone lies within `farthestBone` of
  /// the muscle's size of it: the surface next to the bone, not the whole end of the muscle.
  double lineEndRadius = 0.04;
  double boneGap = 0.02;
  double farthestBone = 0.1;
  /// Bone points near an area whose rigid motion carries it (at least).
  int anchorCount = 32;
  /// The data's length of one unit of the coordinates given, for the distances the messages
  /// give (a filter working in a local frame gives its unit).
  double messageUnit = 1.0;
};

/// The areas of `muscles` (in the rest pose, named `muscleNames`) on `bones` (rest pose, named
/// `boneNames`; boneIndex the bones' order). Names match ignoring case and a file extension
/// ("femur_r" is block "femur_r.vtk"). A landmark set belongs to the muscle it names, else
/// (all the sets naming one muscle together) to the muscle nearest to them, and to the bone it
/// names, else to the nearest bone; its area is the surface facing its landmarks: every point
/// within a landmark's distance from the surface plus the landmarks' spacing of it. A muscle no
/// landmark set belongs to takes, when `fromLineEnds`, the areas at its action lines' ends
/// (`restLines[m]`, first and last points) that lie near a bone.
FoundAttachments FindAttachments(const std::vector<std::string>& muscleNames, const std::vector<TriangleMesh>& muscles,
  const std::vector<std::vector<Points>>& restLines, const std::vector<std::string>& boneNames,
  const std::vector<TriangleMesh>& bones, const std::vector<LandmarkSet>& landmarks, bool fromLineEnds,
  const AttachmentParameters& parameters = {});
}
