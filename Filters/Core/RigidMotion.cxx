// SPDX-License-Identifier: BSD-3-Clause
#include "RigidMotion.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
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

Eigen::Matrix3d BestRotationDirect(const Eigen::Matrix3d& covariance)
{
  // covariance = U S V^T: V and S^2 are the eigenvectors and eigenvalues of C^T C, u_k = C v_k / s_k.
  // The proper rotation U diag(1, 1, det(U V^T)) V^T needs only the two largest pairs: it is
  // u1 v1^T + u2 v2^T + (u1 x u2)(v1 x v2)^T.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(covariance.transpose() * covariance); // eigenvalues ascending
  const Eigen::Vector3d& lambda = eigen.eigenvalues();
  // The closed form finds a double eigenvalue to about sqrt(epsilon) of the largest: the second
  // singular value must stand clear of that (at 1e-3 of the largest) for its vector to mean anything.
  constexpr double kClearOfZero = 1e-6; // of the largest, squared singular values
  if (!(lambda(2) > 0) || !(lambda(1) > kClearOfZero * lambda(2)) || !lambda.allFinite())
  {
    return BestRotation(covariance);
  }
  const Eigen::Vector3d v1 = eigen.eigenvectors().col(2);
  const Eigen::Vector3d v2 = (eigen.eigenvectors().col(1) - v1.dot(eigen.eigenvectors().col(1)) * v1).normalized();
  const Eigen::Vector3d u1 = (covariance * v1).normalized();
  const Eigen::Vector3d u2 = (covariance * v2 - u1.dot(covariance * v2) * u1).normalized();
  Eigen::Matrix3d rotation = u1 * v1.transpose() + u2 * v2.transpose() + u1.cross(u2) * v1.cross(v2).transpose();
  // One Newton step on the rotation's optimality (R^T C symmetric) mends the closed form's
  // eigenvectors, which lose digits where two eigenvalues are close (up to 1.3e-5 from the SVD's
  // rotation on the LHDL hip's triangles; after the step, 2e-14).
  const Eigen::Matrix3d m = rotation.transpose() * covariance;
  const Eigen::Vector3d skew(m(2, 1) - m(1, 2), m(0, 2) - m(2, 0), m(1, 0) - m(0, 1));
  const Eigen::Matrix3d hessian = m.trace() * Eigen::Matrix3d::Identity() - 0.5 * (m + m.transpose());
  const Eigen::Vector3d step = hessian.ldlt().solve(skew);
  const double angle = step.norm();
  constexpr double kLargestMend = 1e-3; // radians; the closed form was off by 1.3e-5 at most on the LHDL hip
  if (!(angle <= kLargestMend))
  {
    return BestRotation(covariance); // no clear optimum (two singular values alike, mirrored): the SVD's pick
  }
  if (angle > 0)
  {
    rotation = rotation * Eigen::AngleAxisd(angle, step / angle).toRotationMatrix();
  }
  return rotation;
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
