// SPDX-License-Identifier: BSD-3-Clause
#include "Geometry/MeanValueCoordinates.h"

#include <Eigen/LU>

#include <array>
#include <cmath>
#include <map>
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

  // The cage's edges, each once, and for each triangle the edge opposite each corner.
  std::map<std::pair<std::int64_t, std::int64_t>, Eigen::Index> index;
  std::vector<std::array<std::int64_t, 2>> edges;
  this->TriangleEdges.resize(cage.triangles.rows(), 3);
  for (Eigen::Index t = 0; t < cage.triangles.rows(); ++t)
  {
    for (int i = 0; i < 3; ++i)
    {
      const std::int64_t a = cage.triangles(t, (i + 1) % 3), b = cage.triangles(t, (i + 2) % 3);
      const auto [entry, added] =
        index.emplace(std::make_pair(std::min(a, b), std::max(a, b)), static_cast<Eigen::Index>(edges.size()));
      if (added)
      {
        edges.push_back({ a, b });
      }
      this->TriangleEdges(t, i) = entry->second;
    }
  }
  this->Edges.resize(static_cast<Eigen::Index>(edges.size()), 2);
  for (size_t e = 0; e < edges.size(); ++e)
  {
    this->Edges(static_cast<Eigen::Index>(e), 0) = edges[e][0];
    this->Edges(static_cast<Eigen::Index>(e), 1) = edges[e][1];
  }
}

void MeanValueCoordinateCalculator::Compute(const Eigen::Vector3d& x, Eigen::Ref<Eigen::RowVectorXd> weights) const
{
  const TriangleMesh& cage = this->Cage;
  const Eigen::Index n = cage.points.rows();
  weights.setZero();
  const double onCage = kDegenerateShare * this->Size; // on a face to rounding

  // Per cage point: p_j - x, its length and direction; per cage edge: the
  // angle it subtends at x and the cross product of its directions (each
  // edge serves the two triangles on either side). Buffers per thread:
  // this runs for every point of a muscle.
  thread_local Points toPoint, unit, edgeCross;
  thread_local Eigen::VectorXd distance, edgeAngle;
  toPoint.resize(n, 3);
  unit.resize(n, 3);
  distance.resize(n);
  for (Eigen::Index j = 0; j < n; ++j)
  {
    toPoint.row(j) = cage.points.row(j) - x.transpose();
    distance(j) = toPoint.row(j).norm();
    if (distance(j) <= onCage)
    {
      weights(j) = 1.0;
      return;
    }
    unit.row(j) = toPoint.row(j) / distance(j);
  }
  const Eigen::Index edges = this->Edges.rows();
  edgeCross.resize(edges, 3);
  edgeAngle.resize(edges);
  for (Eigen::Index e = 0; e < edges; ++e)
  {
    const auto u1 = unit.row(this->Edges(e, 0)), u2 = unit.row(this->Edges(e, 1));
    edgeCross.row(e) = u1.cross(u2);
    edgeAngle(e) = 2.0 * std::asin(std::min(1.0, 0.5 * (u1 - u2).norm()));
  }

  for (Eigen::Index t = 0; t < cage.triangles.rows(); ++t)
  {
    const std::int64_t p[3] = { cage.triangles(t, 0), cage.triangles(t, 1), cage.triangles(t, 2) };
    const Eigen::Vector3d a = toPoint.row(p[0]).transpose();
    const Eigen::Vector3d normal =
      (toPoint.row(p[1]).transpose() - a).cross(toPoint.row(p[2]).transpose() - a); // the triangle's own normal
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
        area[i] = toPoint.row(p[(i + 1) % 3]).cross(toPoint.row(p[(i + 2) % 3])).dot(normal.transpose()) / normalLength;
      }
      const double total = area[0] + area[1] + area[2];
      if (area[0] >= -onCage * normalLength && area[1] >= -onCage * normalLength && area[2] >= -onCage * normalLength)
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
    const double determinant = signedDistance * normalLength / (distance(p[0]) * distance(p[1]) * distance(p[2]));
    Eigen::Vector3d cross[3];
    Eigen::Vector3d mean = Eigen::Vector3d::Zero(); // integral of u over the spherical triangle
    for (int i = 0; i < 3; ++i)
    {
      // The edge opposite corner i, from corner i + 1 to corner i + 2.
      const Eigen::Index edge = this->TriangleEdges(t, i);
      const double sign = this->Edges(edge, 0) == p[(i + 1) % 3] ? 1.0 : -1.0;
      cross[i] = sign * edgeCross.row(edge).transpose();
      const double sine = cross[i].norm();
      if (sine > 0)
      {
        mean += (0.5 * edgeAngle(edge) / sine) * cross[i];
      }
    }
    for (int i = 0; i < 3; ++i)
    {
      weights(p[i]) += cross[i].dot(mean) / (determinant * distance(p[i]));
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
