// SPDX-License-Identifier: BSD-3-Clause
#include "RigidMotion.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>

namespace md
{
RigidTransform Compose(const RigidTransform& a, const RigidTransform& b)
{
  RigidTransform t;
  t.rotation = a.rotation * b.rotation;
  t.translation = a.rotation * b.translation + a.translation;
  return t;
}

RigidTransform Inverse(const RigidTransform& t)
{
  RigidTransform inverse;
  inverse.rotation = t.rotation.transpose();
  inverse.translation = -(inverse.rotation * t.translation);
  return inverse;
}

Points RigidTransform::Apply(const Points& points) const
{
  Points out = points * this->rotation.transpose();
  out.rowwise() += this->translation.transpose();
  return out;
}

RigidTransform RigidTransform::AboutPoint(
  const Eigen::Vector3d& axis, double angleRadians, const Eigen::Vector3d& centre)
{
  RigidTransform t;
  t.rotation = Eigen::AngleAxisd(angleRadians, axis.normalized()).toRotationMatrix();
  t.translation = centre - t.rotation * centre;
  return t;
}

Eigen::Matrix3d BestRotation(const Eigen::Matrix3d& covariance)
{
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d reflectionFix = Eigen::Matrix3d::Identity();
  reflectionFix(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  return svd.matrixU() * reflectionFix * svd.matrixV().transpose();
}

namespace
{
/// Points spread across their own axis by less than this fraction of their spread along it
/// (the smaller two singular values of the covariance against the largest) are nearly
/// collinear: the rotation about that axis is fixed by the pull to the identity below.
constexpr double kCollinearSpread = 0.01;
/// The pull's weight, relative to the covariance's largest singular value, for exactly
/// collinear points: small enough that the fit of the axis is not biased (by about 2e-6 rad),
/// large against rounding.
constexpr double kIdentityPull = 1e-6;
}

RigidFit FitRigidTransform(const Points& from, const Points& to)
{
  if (from.rows() != to.rows() || from.rows() == 0)
  {
    throw InputError("a rigid fit needs two non-empty point sets of the same size");
  }
  const Eigen::RowVector3d cFrom = from.colwise().mean();
  const Eigen::RowVector3d cTo = to.colwise().mean();
  Eigen::Matrix3d covariance = (to.rowwise() - cTo).transpose() * (from.rowwise() - cFrom);
  // Collinear points (an action line of two points, a straight polyline) fix no rotation about
  // their own axis: every twist about it fits as well, and rounding picked one at random (two
  // fits of the same line 2.5 rad apart, which moved the interpolated line by 12 mm halfway).
  // Of the rotations that fit, the one nearest the identity is taken, by adding a pull towards
  // it, w * trace(R), that fades continuously to nothing as the points spread across the axis.
  const Eigen::Vector3d spread = Eigen::JacobiSVD<Eigen::Matrix3d>(covariance).singularValues();
  if (spread(0) > 0)
  {
    const double across = std::max(0.0, 1.0 - (spread(1) + spread(2)) / (kCollinearSpread * spread(0)));
    covariance += kIdentityPull * spread(0) * across * across * Eigen::Matrix3d::Identity();
  }
  RigidFit fit;
  fit.transform.rotation = BestRotation(covariance);
  fit.transform.translation = cTo.transpose() - fit.transform.rotation * cFrom.transpose();
  const Points residual = to - fit.transform.Apply(from);
  const Eigen::VectorXd norms = residual.rowwise().norm();
  fit.rmsResidual = std::sqrt(norms.squaredNorm() / static_cast<double>(norms.size()));
  fit.maxResidual = norms.maxCoeff();
  return fit;
}

ScrewInterpolation::ScrewInterpolation(const RigidTransform& motion, const Eigen::Vector3d& centroid)
  : Rotation(motion.rotation)
  , Centroid(centroid)
{
  this->Rotation.normalize();
  if (this->Rotation.w() < 0)
  {
    this->Rotation.coeffs() *= -1; // shortest arc
  }
  const Eigen::AngleAxisd angleAxis(this->Rotation);
  this->Angle = angleAxis.angle();
  this->Axis = angleAxis.axis();

  const Eigen::Vector3d centroidMotion = motion.Apply(centroid) - centroid;
  this->Slide = this->Axis.dot(centroidMotion);
  this->CentroidOffset = centroidMotion - this->Slide * this->Axis;
  // Closed-form inverse of (I - R) in the plane normal to the axis:
  // q = b/2 + cot(angle/2)/2 * (axis x b).
  this->FixedPointOffset = Eigen::Vector3d::Zero();
  if (this->Angle > 0)
  {
    this->FixedPointOffset =
      0.5 * this->CentroidOffset + 0.5 / std::tan(0.5 * this->Angle) * this->Axis.cross(this->CentroidOffset);
  }
}

RigidTransform ScrewInterpolation::At(double s) const
{
  s = std::clamp(s, 0.0, 1.0);
  RigidTransform t;
  Eigen::Vector3d centroidMotion;
  // Below this angle the axis is meaningless; the motion is a translation.
  constexpr double smallestAngle = 1e-12;
  if (this->Angle < smallestAngle)
  {
    centroidMotion = s * (this->CentroidOffset + this->Slide * this->Axis);
  }
  else
  {
    const double sigma = s * this->Angle;
    t.rotation = Eigen::Quaterniond::Identity().slerp(s, this->Rotation).normalized().toRotationMatrix();
    // (I - R(sigma)) q, written so that it stays accurate for small angles.
    const double halfSin = std::sin(0.5 * sigma);
    centroidMotion = 2 * halfSin * halfSin * this->FixedPointOffset -
      std::sin(sigma) * this->Axis.cross(this->FixedPointOffset) + s * this->Slide * this->Axis;
  }
  // x(s) = R(s) (x - c) + c + centroidMotion(s)
  t.translation = this->Centroid + centroidMotion - t.rotation * this->Centroid;
  return t;
}
}
