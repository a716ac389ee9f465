// SPDX-License-Identifier: BSD-3-Clause
#include "Deformation/VolumeConstrainedSolver.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace md
{
SparseMatrix CotangentLaplacian(const TriangleMesh& mesh, std::optional<double> largestCotangent)
{
  const Eigen::Index n = mesh.points.rows();
  std::vector<Eigen::Triplet<double>> cotangents; // c_ij, summed by setFromTriplets
  std::vector<Eigen::Triplet<double>> adjacency;  // 1 per edge end, for the uniform fallback
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      const std::int64_t i = mesh.triangles(t, (k + 1) % 3), j = mesh.triangles(t, (k + 2) % 3);
      const Eigen::Vector3d apex = mesh.points.row(mesh.triangles(t, k)).transpose();
      const Eigen::Vector3d u = mesh.points.row(i).transpose() - apex;
      const Eigen::Vector3d v = mesh.points.row(j).transpose() - apex;
      const double sine = u.cross(v).norm();
      double cotangent = sine > 0 ? u.dot(v) / sine : 0.0;
      if (largestCotangent)
      {
        cotangent = std::clamp(cotangent, 0.0, *largestCotangent);
      }
      cotangents.emplace_back(i, j, cotangent);
      cotangents.emplace_back(j, i, cotangent);
      adjacency.emplace_back(i, j, 0.5); // each edge is seen from two triangles
      adjacency.emplace_back(j, i, 0.5);
    }
  }
  SparseMatrix c(n, n), a(n, n);
  c.setFromTriplets(cotangents.begin(), cotangents.end());
  a.setFromTriplets(adjacency.begin(), adjacency.end());
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index i = 0; i < n; ++i)
  {
    double sum = 0;
    bool usable = true;
    for (SparseMatrix::InnerIterator it(c, i); it; ++it)
    {
      sum += it.value();
    }
    usable = sum > 1e-12;
    const SparseMatrix& weights = usable ? c : a;
    double total = 0;
    for (SparseMatrix::InnerIterator it(weights, i); it; ++it)
    {
      total += it.value();
    }
    entries.emplace_back(i, i, -1.0);
    for (SparseMatrix::InnerIterator it(weights, i); it; ++it)
    {
      entries.emplace_back(i, it.col(), it.value() / total);
    }
  }
  SparseMatrix laplacian(n, n);
  laplacian.setFromTriplets(entries.begin(), entries.end());
  return laplacian;
}

double EnclosedVolume(const Points& points, const Triangles& triangles, Points* gradient)
{
  if (gradient)
  {
    gradient->setZero(points.rows(), 3);
  }
  double sixTimes = 0;
  for (Eigen::Index t = 0; t < triangles.rows(); ++t)
  {
    const Eigen::Vector3d a = points.row(triangles(t, 0)).transpose();
    const Eigen::Vector3d b = points.row(triangles(t, 1)).transpose();
    const Eigen::Vector3d c = points.row(triangles(t, 2)).transpose();
    sixTimes += a.cross(b).dot(c);
    if (gradient)
    {
      gradient->row(triangles(t, 0)) += b.cross(c).transpose() / 6.0;
      gradient->row(triangles(t, 1)) += c.cross(a).transpose() / 6.0;
      gradient->row(triangles(t, 2)) += a.cross(b).transpose() / 6.0;
    }
  }
  return sixTimes / 6.0;
}

VolumeConstrainedSolver::VolumeConstrainedSolver(const SparseMatrix& rows, const Triangles& triangles)
  : Rows(rows)
  , Faces(triangles)
{
  this->NormalMatrix = Eigen::MatrixXd::Zero(rows.cols(), rows.cols());
  this->AddToNormal(Eigen::MatrixXd(rows));
}

VolumeConstrainedSolver::VolumeConstrainedSolver(const VolumeConstrainedSolver& base, const Eigen::MatrixXd& extraRows)
  : Faces(base.Faces)
  , NormalMatrix(base.NormalMatrix)
{
  SparseMatrix extra = extraRows.sparseView();
  this->Rows.resize(base.Rows.rows() + extra.rows(), base.Rows.cols());
  this->Rows.reserve(base.Rows.nonZeros() + extra.nonZeros());
  this->Rows.topRows(base.Rows.rows()) = base.Rows;
  this->Rows.bottomRows(extra.rows()) = extra;
  this->AddToNormal(extraRows);
}

void VolumeConstrainedSolver::AddToNormal(const Eigen::MatrixXd& rows)
{
  this->NormalMatrix.selfadjointView<Eigen::Lower>().rankUpdate(rows.transpose());
  this->NormalMatrix = this->NormalMatrix.selfadjointView<Eigen::Lower>();
  this->Factor();
}

void VolumeConstrainedSolver::Factor()
{
  this->Normal.compute(this->NormalMatrix);
  // A singular system shows as a pivot that is only rounding.
  const Eigen::VectorXd pivots = this->Normal.vectorD();
  const double largest = pivots.size() ? pivots.cwiseAbs().maxCoeff() : 0.0;
  if (this->Normal.info() != Eigen::Success || pivots.size() == 0 || pivots.minCoeff() <= 1e-14 * largest)
  {
    throw InputError("the deformation's least-squares system is singular: nothing fixes the muscle's position "
                     "(are there action-line rows?)");
  }
  // A hull point that the rows hardly fix (a pivot far below the others)
  // would take steps of rounding noise: a tiny damping holds it instead. The
  // steps' fixed point, where L^T r + J^T lambda = 0, does not change.
  if (pivots.minCoeff() <= 1e-9 * largest)
  {
    Eigen::MatrixXd damped = this->NormalMatrix;
    damped.diagonal().array() += 1e-9 * largest;
    this->Normal.compute(damped);
  }
}

Points VolumeConstrainedSolver::Step(const Points& x, const Points& targets, double targetVolume, double alpha) const
{
  Points gradient;
  const double volume = EnclosedVolume(x, this->Faces, &gradient);
  return this->Step(x, targets, volume - targetVolume, gradient, alpha);
}

Points VolumeConstrainedSolver::Step(
  const Points& x, const Points& targets, double volumeError, const Points& gradient, double alpha) const
{
  const Points residual = this->Rows * x - targets;
  const Points pulled = this->Rows.transpose() * residual; // L^T r
  // A applied column by column (the three coordinates share L).
  const Eigen::MatrixXd aPulled = this->Normal.solve(Eigen::MatrixXd(pulled));
  if (gradient.rows() == 0)
  {
    return x - alpha * aPulled;
  }
  const Eigen::MatrixXd aGradient = this->Normal.solve(Eigen::MatrixXd(gradient));
  const double jaj = (gradient.array() * aGradient.array()).sum();
  const double jalr = (gradient.array() * aPulled.array()).sum();
  const double lambda = (volumeError / alpha - jalr) / jaj;
  return x - alpha * (aPulled + lambda * aGradient);
}
}
