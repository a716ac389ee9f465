// SPDX-License-Identifier: BSD-3-Clause
#include "Geometry/ConvexProjection.h"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>

namespace md
{
std::optional<Eigen::Vector3d> FeasiblePointAlongRay(
  const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, const std::vector<HalfSpace>& halfSpaces)
{
  // Each half-space bounds the ray parameter s from below or from above.
  double lowest = 0, highest = std::numeric_limits<double>::infinity();
  for (const HalfSpace& h : halfSpaces)
  {
    const double rate = h.normal.dot(direction);
    const double gap = h.offset - h.normal.dot(origin); // need rate * s >= gap
    if (std::abs(rate) < 1e-300)
    {
      if (gap > 0)
      {
        return std::nullopt;
      }
      continue;
    }
    if (rate > 0)
    {
      lowest = std::max(lowest, gap / rate);
    }
    else
    {
      highest = std::min(highest, gap / rate);
    }
  }
  if (lowest > highest)
  {
    return std::nullopt;
  }
  return Eigen::Vector3d(origin + lowest * direction);
}

std::optional<Eigen::Vector3d> ProjectOntoPolyhedron(
  const Eigen::Vector3d& target, const std::vector<HalfSpace>& halfSpaces, const Eigen::Vector3d& feasibleStart)
{
  const int n = static_cast<int>(halfSpaces.size());
  Eigen::Vector3d x = feasibleStart;
  std::vector<int> working; // indices of the active half-spaces, linearly independent
  const double scale = std::max(1.0, (target - feasibleStart).norm());
  const double tolerance = kDegenerateShare * scale;
  for (int i = 0; i < n && working.size() < 3; ++i)
  {
    if (std::abs(halfSpaces[i].normal.dot(x) - halfSpaces[i].offset) > tolerance)
    {
      continue;
    }
    // Keep only independent constraints (normals are unit vectors).
    const Eigen::Vector3d& normal = halfSpaces[i].normal;
    bool independent = true;
    if (working.size() == 1)
    {
      independent = halfSpaces[working[0]].normal.cross(normal).norm() > 1e-9;
    }
    else if (working.size() == 2)
    {
      independent = std::abs(halfSpaces[working[0]].normal.cross(halfSpaces[working[1]].normal).dot(normal)) > 1e-9;
    }
    if (independent)
    {
      working.push_back(i);
    }
  }

  constexpr int mostIterations = 100;
  for (int iteration = 0; iteration < mostIterations; ++iteration)
  {
    // Minimiser of |y - target| on the working set's planes, and the multipliers
    // lambda of target - y = -sum lambda_i n_i (lambda >= 0 at the optimum).
    const auto m = static_cast<Eigen::Index>(working.size());
    Eigen::Vector3d y = target;
    // At most three constraints are active in 3D: fixed-capacity matrices.
    using Rows = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor, 3, 3>;
    using Column = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;
    Column lambda(m);
    if (m > 0)
    {
      Rows a(m, 3);
      Column b(m);
      for (Eigen::Index k = 0; k < m; ++k)
      {
        a.row(k) = halfSpaces[working[k]].normal.transpose();
        b(k) = halfSpaces[working[k]].offset;
      }
      const Column rhs = b - a * target;
      if (m == 1)
      {
        lambda(0) = rhs(0) / a.row(0).squaredNorm();
      }
      else if (m == 2)
      {
        const Eigen::Matrix2d gram = a * a.transpose();
        lambda = gram.inverse() * rhs;
      }
      else
      {
        const Eigen::Matrix3d gram = a * a.transpose();
        lambda = gram.inverse() * rhs;
      }
      y = target + a.transpose() * lambda;
    }
    const Eigen::Vector3d step = y - x;
    if (step.norm() <= tolerance)
    {
      // Stationary on the working set: optimal unless a multiplier is negative.
      Eigen::Index worst = -1;
      double mostNegative = -1e-14;
      for (Eigen::Index k = 0; k < m; ++k)
      {
        if (lambda(k) < mostNegative)
        {
          mostNegative = lambda(k);
          worst = k;
        }
      }
      if (worst < 0)
      {
        return x;
      }
      working.erase(working.begin() + worst);
      continue;
    }
    // Longest move towards y that keeps every other half-space satisfied.
    double length = 1.0;
    int blocking = -1;
    const double noise = 1e-14 * step.norm();
    for (int i = 0; i < n; ++i)
    {
      const double rate = halfSpaces[i].normal.dot(step);
      if (rate >= -noise || std::find(working.begin(), working.end(), i) != working.end())
      {
        continue;
      }
      const double allowed = (halfSpaces[i].offset - halfSpaces[i].normal.dot(x)) / rate;
      if (allowed < length)
      {
        length = std::max(0.0, allowed);
        blocking = i;
      }
    }
    x += length * step;
    if (blocking >= 0)
    {
      if (working.size() == 3)
      {
        return std::nullopt; // a fourth active plane: degenerate, give up
      }
      working.push_back(blocking);
    }
  }
  return std::nullopt;
}
}
