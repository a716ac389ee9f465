#include "MeanValueCoordinates.h"

#include <Eigen/LU>

#include <cmath>
#include <vector>

namespace md
{
MeanValueCoordinateCalculator::MeanValueCoordinateCalculator(const TriangleMesh& cage)
  : Cage(cage)
{
  if (cage.points.rows() < 4 || cage.triangles.rows() < 4)
  {
    throw InputError("mean value coordinates need a closed cage of at least 4 points");
  }
  this->Centre = cage.points.colwise().mean().transpose();
  this->Centred = cage.points.rowwise() - this->Centre.transpose();
  this->Size = (cage.points.colwise().maxCoeff() - cage.points.colwise().minCoeff()).norm();
  Eigen::Matrix4d gram = Eigen::Matrix4d::Zero();
  gram.topLeftCorner<3, 3>() = this->Centred.transpose() * this->Centred;
  gram.topRightCorner<3, 1>() = this->Centred.colwise().sum().transpose();
  gram.bottomLeftCorner<1, 3>() = this->Centred.colwise().sum();
  gram(3, 3) = static_cast<double>(cage.points.rows());
  this->ConstraintGramInverse = gram.inverse();
}

void MeanValueCoordinateCalculator::Compute(const Eigen::Vector3d& x, Eigen::Ref<Eigen::RowVectorXd> weights) const
{
  const TriangleMesh& cage = this->Cage;
  const Eigen::Index n = cage.points.rows();
  weights.setZero();
  const double onCage = 1e-12 * this->Size;

  std::vector<Eigen::Vector3d> toPoint(static_cast<size_t>(n)); // p_j - x
  std::vector<double> distance(static_cast<size_t>(n));
  for (Eigen::Index j = 0; j < n; ++j)
  {
    toPoint[j] = cage.points.row(j).transpose() - x;
    distance[j] = toPoint[j].norm();
    if (distance[j] <= onCage)
    {
      weights(j) = 1.0;
      return;
    }
  }

  for (Eigen::Index t = 0; t < cage.triangles.rows(); ++t)
  {
    const std::int64_t p[3] = { cage.triangles(t, 0), cage.triangles(t, 1), cage.triangles(t, 2) };
    const Eigen::Vector3d& a = toPoint[p[0]];
    const Eigen::Vector3d normal = (toPoint[p[1]] - a).cross(toPoint[p[2]] - a); // the triangle's own normal
    const double normalLength = normal.norm();
    if (normalLength == 0)
    {
      continue; // degenerate triangle: no solid angle
    }
    const double signedDistance = normal.dot(a) / normalLength; // of x below the plane
    if (std::abs(signedDistance) <= onCage)
    {
      // x in the triangle's plane: barycentric weights when inside the triangle,
      // no share otherwise.
      double area[3];
      for (int i = 0; i < 3; ++i)
      {
        area[i] = toPoint[p[(i + 1) % 3]].cross(toPoint[p[(i + 2) % 3]]).dot(normal) / normalLength;
      }
      const double total = area[0] + area[1] + area[2];
      if (area[0] >= -onCage * normalLength && area[1] >= -onCage * normalLength &&
        area[2] >= -onCage * normalLength)
      {
        weights.setZero();
        for (int i = 0; i < 3; ++i)
        {
          weights(p[i]) = std::max(0.0, area[i]) / total;
        }
        weights /= weights.sum();
        return;
      }
      continue;
    }
    // det(e1, e2, e3) of the unit directions, from the signed distance.
    const double determinant =
      signedDistance * normalLength / (distance[p[0]] * distance[p[1]] * distance[p[2]]);
    Eigen::Vector3d unit[3], cross[3];
    for (int i = 0; i < 3; ++i)
    {
      unit[i] = toPoint[p[i]] / distance[p[i]];
    }
    Eigen::Vector3d mean = Eigen::Vector3d::Zero(); // integral of u over the spherical triangle
    for (int i = 0; i < 3; ++i)
    {
      const Eigen::Vector3d& u1 = unit[(i + 1) % 3];
      const Eigen::Vector3d& u2 = unit[(i + 2) % 3];
      cross[i] = u1.cross(u2);
      const double sine = cross[i].norm();
      const double angle = 2.0 * std::asin(std::min(1.0, 0.5 * (u1 - u2).norm()));
      if (sine > 0)
      {
        mean += (0.5 * angle / sine) * cross[i];
      }
    }
    for (int i = 0; i < 3; ++i)
    {
      weights(p[i]) += cross[i].dot(mean) / (determinant * distance[p[i]]);
    }
  }
  weights /= weights.sum();

  // Minimum-norm correction so that sum w = 1 and sum w (p - c) = x - c exactly.
  Eigen::Vector4d residual;
  residual.head<3>() = (x - this->Centre) - (weights * this->Centred).transpose();
  residual(3) = 1.0 - weights.sum();
  const Eigen::Vector4d multiplier = this->ConstraintGramInverse * residual;
  weights += (this->Centred * multiplier.head<3>()).transpose();
  weights.array() += multiplier(3);
}

WeightMatrix MeanValueCoordinateCalculator::Compute(const Points& points) const
{
  WeightMatrix weights(points.rows(), this->Cage.points.rows());
  const auto n = static_cast<long>(points.rows());
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i)
  {
    this->Compute(points.row(i).transpose(), weights.row(i));
  }
  return weights;
}

WeightMatrix MeanValueCoordinates(const TriangleMesh& cage, const Points& points)
{
  return MeanValueCoordinateCalculator(cage).Compute(points);
}
}
