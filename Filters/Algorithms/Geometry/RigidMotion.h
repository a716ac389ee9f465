// SPDX-License-Identifier: BSD-3-Clause
// Rigid motions: least-squares fit (Kabsch) and constant-velocity interpolation.
#pragma once

#include "Common/MeshTypes.h"

#include <Eigen/Geometry>

#include <string>

namespace md
{
/// x -> rotation * x + translation
struct RigidTransform
{
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d Apply(const Eigen::Vector3d& x) const { return rotation * x + translation; }
  Points Apply(const Points& points) const;
  /// Rotation about `centre` by `angleRadians` around `axis` (normalised here).
  static RigidTransform AboutPoint(const Eigen::Vector3d& axis, double angleRadians, const Eigen::Vector3d& centre);
};

/// How far a rotation matrix may be from orthonormal (largest entry of R^T R - I) and still be
/// taken as a rotation: a table written with 7 significant digits passes.
constexpr double kRotationTolerance = 1e-6;

/// Why `t` is not a rigid motion (non-finite entries; a rotation part that is not orthonormal to
/// kRotationTolerance, or is a reflection), or "" when it is one.
std::string NotARigidMotion(const RigidTransform& t);

/// a after b: x -> a(b(x)).
RigidTransform Compose(const RigidTransform& a, const RigidTransform& b);
/// The transform undoing `t`.
RigidTransform Inverse(const RigidTransform& t);

struct RigidFit
{
  RigidTransform transform;
  double rmsResidual = 0; ///< root mean square of |to_i - T(from_i)|
  double maxResidual = 0; ///< largest |to_i - T(from_i)|
};

/// The proper rotation R closest to a 3 x 3 covariance sum(to_i from_i^T) of
/// centred point pairs, i.e. the R minimising sum |to_i - R from_i|^2 (Kabsch).
Eigen::Matrix3d BestRotation(const Eigen::Matrix3d& covariance);

/// BestRotation by the eigenvectors of covariance^T covariance in closed form rather than an
/// iterative SVD (about a tenth of its time; per triangle of a mesh, the SVD was most of
/// counting its flipped triangles). The same rotation to rounding where the two largest
/// singular values stand clear of zero; BestRotation itself where they do not.
Eigen::Matrix3d BestRotationDirect(const Eigen::Matrix3d& covariance);

/// The sign of b . (R a), R = BestRotationDirect(covariance), where bounds on the covariance's
/// singular values tell it without R (at a small part of its cost): +1 or -1; 0 where they do not
/// (the covariance far from a scaled rotation, or the product near zero), and R must be computed.
int SignUnderBestRotation(const Eigen::Matrix3d& covariance, const Eigen::Vector3d& a, const Eigen::Vector3d& b);

/// Proper rotation and translation minimising sum |to_i - (R from_i + t)|^2
/// (Kabsch / Horn). Both sets must have the same number of points (>= 1).
RigidFit FitRigidTransform(const Points& from, const Points& to);

/// The screw motion of a rigid transform, to move a body a fraction of the way:
/// rotation about the screw axis by quaternion slerp, slide along it linearly.
/// A rotation about a fixed centre (a joint) keeps that centre fixed at every
/// fraction; with no rotation it is a straight translation.
class ScrewInterpolation
{
public:
  /// `centroid` is any point of the moving body (used for numerical conditioning).
  ScrewInterpolation(const RigidTransform& motion, const Eigen::Vector3d& centroid);

  /// The transform that moves the body the fraction s in [0, 1] of the way.
  RigidTransform At(double s) const;

  double AngleRadians() const { return this->Angle; }

private:
  Eigen::Quaterniond Rotation;
  Eigen::Vector3d Axis;
  double Angle = 0;
  Eigen::Vector3d Centroid;
  Eigen::Vector3d CentroidOffset;   // b = component of the centroid's motion normal to the axis
  Eigen::Vector3d FixedPointOffset; // q: (I - R) q = b, q normal to the axis
  double Slide = 0;                 // d: motion along the axis
};
}
