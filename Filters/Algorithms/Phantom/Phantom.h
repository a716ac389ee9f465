// SPDX-License-Identifier: BSD-3-Clause
// MusculoskeletalPhantom: a synthetic right hip built from swept tubes, so that
// demos and tests never depend on outside data.
#pragma once

#include "Common/MeshTypes.h"
#include "Geometry/RigidMotion.h"

#include <functional>
#include <string>
#include <vector>

namespace md
{
/// Dense polyline through `controlPoints` with every interior corner replaced
/// by a quadratic Bezier fillet of (at most) `cornerRadius`, resampled every
/// `spacing` along its length.
Points RoundedPolyline(const Points& controlPoints, double cornerRadius, double spacing);

struct TubeSpecification
{
  Points centreline; ///< dense polyline, as from RoundedPolyline
  /// Semi-axes of the elliptic cross-section (along the normal, along the
  /// binormal) at distance x of [0, length] along the centreline; both must
  /// reach 0 at x = 0 and x = length, where the tube is closed by a pole.
  std::function<Eigen::Vector2d(double x, double length)> radii;
  Eigen::Vector3d normalHint = Eigen::Vector3d::UnitX(); ///< first semi-axis direction
  int resolution = 24;                                   ///< points around each cross-section
};

/// Closed, manifold, outward-oriented triangle surface swept along the centreline.
TriangleMesh BuildTube(const TubeSpecification& specification);

struct PhantomParameters
{
  double flexionDegrees = 60; ///< hip flexion of the current pose
  double scale = 1;           ///< 1 gives an adult hip in millimetres
  int resolution = 24;        ///< points around each cross-section of every surface
};

struct PhantomBone
{
  std::string name;
  TriangleMesh rest;
  Points currentPoints; ///< the rest-pose points moved to the current pose
};

struct PhantomMuscle
{
  std::string name;
  TriangleMesh rest;
  std::vector<std::string> actionLineNames;
  std::vector<Points> actionLinesRest;
  std::vector<Points> actionLinesCurrent; ///< may have fewer points (conditional via points)
};

struct Phantom
{
  std::vector<PhantomBone> bones;     ///< Pelvis (fixed), Femur (moves)
  std::vector<PhantomMuscle> muscles; ///< Iliopsoas, GluteusMaximus, RectusFemoris
  RigidTransform femurMotion;         ///< rest pose -> current pose of the femur
  Eigen::Vector3d hipCentre;
};

/// Frame: x lateral, y anterior, z superior, hip joint centre at the origin.
/// Flexion rotates the femur about the x axis through the hip centre. The
/// Iliopsoas passes over a pelvic via point that is active only below 40
/// degrees of flexion (like OpenSim's conditional path points), so its current
/// action line can have fewer points than its rest one. At large flexion the
/// femur sweeps into the rest-pose RectusFemoris.
Phantom BuildPhantom(const PhantomParameters& parameters);
}
