// SPDX-License-Identifier: BSD-3-Clause
#include "Geometry/RigidMotion.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>

namespace md
{
std::string NotARigidMotion(const RigidTransform& t)
{
  if (!t.rotation.allFinite() || !t.translation.allFinite())
  {
    return "its rotation or translation holds NaN or infinite values";
  }
  const double offOrthonormal =
    (t.rotation.transpose() * t.rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (offOrthonormal > kRotationTolerance)
  {
    return "its R (R00 ... R22) is not a rotation: R^T R differs from the identity by " +
      std::to_string(offOrthonormal) + " (a scaling or shear; at most " + std::to_string(kRotationTolerance) +
      " is taken)";
  }
  if (t.rotation.determinant() < 0)
  {
    return "its R (R00 ... R22) is a reflection (determinant -1), not a rotation";
  }
  return "";
}

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
/// The cofactor matrix: det(X) X^-T where X is invertible.
Eigen::Matrix3d Cofactor(const Eigen::Matrix3d& x)
{
  Eigen::Matrix3d cofactor;
  for (int i = 0; i < 3; ++i)
  {
    for (int j = 0; j < 3; ++j)
    {
      const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      cofactor(i, j) = x(i1, j1) * x(i2, j2) - x(i1, j2) * x(i2, j1);
    }
  }
  return cofactor;
}
}

int SignUnderBestRotation(const Eigen::Matrix3d& covariance, const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
  // With C = U diag(s1, s2, s3) V^T, U and V proper rotations and s3 of det C's sign, R = U V^T,
  // and C's cofactor matrix is U diag(s2 s3, s1 s3, s1 s2) V^T. So M = C + cof(C) / |C|_F has the
  // same U and V and singular values (s1 + s2 s3 / |C|, s2 + s1 s3 / |C|, s3 + s1 s2 / |C|), the
  // first two >= 0 (|C| >= s1 >= s2 >= |s3|): where det M > 0 all are, and R is M's polar factor.
  // A muscle's local covariances are near rank 2 (the edges lie near the surface: s3 near 0),
  // where M is far better conditioned than C; scaled Newton steps X <- (z X + X^-T / z) / 2 keep
  // the polar factor and bring the singular values together.
  // With X = R S and S's eigenvalues within [L, U], |X / k - R| = |S / k - I| <= e = (U - L) / (U + L)
  // for k = (U + L) / 2: so b . (R a) has the sign of b . (X a) where that exceeds e k |a| |b|.
  // The bounds: the eigenvalues of X^T X lie within sqrt(2/3) d of their mean, d being the
  // Frobenius distance of X^T X from that mean times I (the deviations sum to zero).
  const double size = covariance.norm();
  if (!(size > 0) || !std::isfinite(size))
  {
    return 0;
  }
  Eigen::Matrix3d x = covariance + Cofactor(covariance) / size;
  // Far from singular (a condition number of at most about 1e4): rounding stays far below the
  // margin, and the best rotation is unique (C's two largest singular values clear of zero and
  // of each other's negatives).
  constexpr double kLeastDeterminant = 1e-4; // of |M|_F^3
  if (!(x.determinant() > kLeastDeterminant * std::pow(x.norm(), 3)))
  {
    return 0;
  }
  const double scale = a.norm() * b.norm();
  constexpr int kNewtonSteps = 3;
  for (int step = 0;; ++step)
  {
    const Eigen::Matrix3d product = x.transpose() * x;
    const double mean = product.trace() / 3;
    const double spread =
      std::sqrt((product - mean * Eigen::Matrix3d::Identity()).squaredNorm() * (2.0 / 3.0)) + 1e-12 * mean;
    if (mean - spread > 0)
    {
      const double upper = std::sqrt(mean + spread), lower = std::sqrt(mean - spread);
      const double reach = (upper - lower) / (upper + lower) + 1e-7; // + rounding, with a wide margin
      const double value = b.dot(x * a) / (0.5 * (upper + lower));
      if (std::abs(value) > reach * scale)
      {
        return value > 0 ? 1 : -1;
      }
    }
    if (step == kNewtonSteps)
    {
      return 0;
    }
    const Eigen::Matrix3d inverseTransposed = Cofactor(x) / x.determinant();
    const double z = std::sqrt(std::sqrt(inverseTransposed.squaredNorm() / x.squaredNorm()));
    x = 0.5 * (z * x + inverseTransposed / z);
  }
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
