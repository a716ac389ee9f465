// SPDX-License-Identifier: BSD-3-Clause
#include "OpenSim/OpenSimFunction.h"

#include "Common/MeshTypes.h"

#include <algorithm>
#include <cmath>

namespace md::osim
{
namespace
{
void CheckKnots(const std::vector<double>& x, const std::vector<double>& y, const char* what)
{
  if (x.size() != y.size())
  {
    throw InputError(std::string(what) + " has " + std::to_string(x.size()) + " x values but " +
      std::to_string(y.size()) + " y values");
  }
  if (x.size() < 2)
  {
    throw InputError(std::string(what) + " needs at least 2 knots, it has " + std::to_string(x.size()));
  }
  for (size_t i = 0; i < x.size(); ++i)
  {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i]))
    {
      throw InputError(std::string(what) + " has a non-finite knot (number " + std::to_string(i + 1) + ")");
    }
    if (i > 0 && !(x[i] > x[i - 1]))
    {
      throw InputError(std::string(what) + " has x values that do not increase (knots " + std::to_string(i) + " and " +
        std::to_string(i + 1) + ")");
    }
  }
}

/// Knot spacing h_i = x_i+1 - x_i and the slope of each span.
void Spans(
  const std::vector<double>& x, const std::vector<double>& y, std::vector<double>& h, std::vector<double>& slope)
{
  h.resize(x.size() - 1);
  slope.resize(x.size() - 1);
  for (size_t i = 0; i + 1 < x.size(); ++i)
  {
    h[i] = x[i + 1] - x[i];
    slope[i] = (y[i + 1] - y[i]) / h[i];
  }
}

/// Solves the tridiagonal system with diagonal `diagonal`, symmetric off-diagonal `off`
/// (off[i] couples unknowns i and i+1) and right-hand side `rhs`, in place (Thomas algorithm).
void SolveTridiagonal(std::vector<double>& diagonal, const std::vector<double>& off, std::vector<double>& rhs)
{
  const size_t n = diagonal.size();
  for (size_t i = 1; i < n; ++i)
  {
    const double factor = off[i - 1] / diagonal[i - 1];
    diagonal[i] -= factor * off[i - 1];
    rhs[i] -= factor * rhs[i - 1];
  }
  rhs[n - 1] /= diagonal[n - 1];
  for (size_t j = n - 1; j-- > 0;)
  {
    rhs[j] = (rhs[j] - off[j] * rhs[j + 1]) / diagonal[j];
  }
}
}

Function Function::Constant(double value)
{
  Function f;
  f.kind = Kind::Constant;
  f.a = { value };
  return f;
}

Function Function::Linear(double slope, double intercept)
{
  Function f;
  f.kind = Kind::Linear;
  f.a = { slope, intercept };
  return f;
}

Function Function::Polynomial(std::vector<double> coefficients)
{
  if (coefficients.empty())
  {
    throw InputError("PolynomialFunction has no coefficients");
  }
  Function f;
  f.kind = Kind::Polynomial;
  f.a = std::move(coefficients);
  return f;
}

Function Function::Multiplier(const Function& inner, double scale)
{
  Function f;
  f.kind = Kind::Multiplier;
  f.scale = scale;
  f.inner = std::make_shared<const Function>(inner);
  return f;
}

Function Function::WithKnots(Kind kind, std::vector<double> x, std::vector<double> y)
{
  CheckKnots(x, y, KindName(kind));
  Function f;
  f.kind = kind;
  f.b.assign(x.size(), 0.0);
  f.c.assign(x.size(), 0.0);
  f.d.assign(x.size(), 0.0);
  f.x = std::move(x);
  f.y = std::move(y);
  return f;
}

Function Function::PiecewiseLinear(std::vector<double> knotsX, std::vector<double> knotsY)
{
  Function f = WithKnots(Kind::PiecewiseLinear, std::move(knotsX), std::move(knotsY));
  std::vector<double> h;
  Spans(f.x, f.y, h, f.b);
  f.b.push_back(f.b.back());
  return f;
}

Function Function::SimmSpline(std::vector<double> knotsX, std::vector<double> knotsY)
{
  Function f = WithKnots(Kind::SimmSpline, std::move(knotsX), std::move(knotsY));
  const std::vector<double>& x = f.x;
  const std::vector<double>& y = f.y;
  const size_t n = x.size();
  if (n == 2)
  {
    f.b[0] = f.b[1] = (y[1] - y[0]) / (x[1] - x[0]);
  }
  else
  {
    // sigma_i = s''(x_i) / 6 from the continuity of the first derivative at the inner knots and,
    // at the ends, third derivatives equal to those of the cubics through the end four knots.
    std::vector<double> h, slope;
    Spans(x, y, h, slope);
    std::vector<double> diagonal(n), sigma(n, 0.0);
    diagonal[0] = -h[0];
    diagonal[n - 1] = -h[n - 2];
    for (size_t i = 1; i + 1 < n; ++i)
    {
      diagonal[i] = 2.0 * (h[i - 1] + h[i]);
      sigma[i] = slope[i] - slope[i - 1];
    }
    if (n > 3)
    {
      const double thirdLeft = (sigma[2] / (x[3] - x[1]) - sigma[1] / (x[2] - x[0])) / (x[3] - x[0]);
      const double thirdRight =
        (sigma[n - 2] / (x[n - 1] - x[n - 3]) - sigma[n - 3] / (x[n - 2] - x[n - 4])) / (x[n - 1] - x[n - 4]);
      sigma[0] = thirdLeft * h[0] * h[0];
      sigma[n - 1] = -thirdRight * h[n - 2] * h[n - 2];
    }
    SolveTridiagonal(diagonal, h, sigma);
    for (size_t i = 0; i + 1 < n; ++i)
    {
      f.b[i] = slope[i] - h[i] * (sigma[i + 1] + 2.0 * sigma[i]);
      f.c[i] = 3.0 * sigma[i];
      f.d[i] = (sigma[i + 1] - sigma[i]) / h[i];
    }
    f.b[n - 1] = slope[n - 2] + h[n - 2] * (sigma[n - 2] + 2.0 * sigma[n - 1]);
    f.c[n - 1] = 3.0 * sigma[n - 1];
    f.d[n - 1] = f.d[n - 2];
  }
  return f;
}

Function Function::NaturalCubicSpline(std::vector<double> knotsX, std::vector<double> knotsY)
{
  Function f = WithKnots(Kind::NaturalCubicSpline, std::move(knotsX), std::move(knotsY));
  const std::vector<double>& x = f.x;
  const std::vector<double>& y = f.y;
  const size_t n = x.size();
  std::vector<double> h, slope;
  Spans(x, y, h, slope);
  // Second derivatives m_i, zero at both ends; the inner ones from a tridiagonal system.
  std::vector<double> m(n, 0.0);
  if (n > 2)
  {
    std::vector<double> diagonal(n - 2), off(n - 2, 0.0), rhs(n - 2);
    for (size_t i = 1; i + 1 < n; ++i)
    {
      diagonal[i - 1] = 2.0 * (h[i - 1] + h[i]);
      rhs[i - 1] = 6.0 * (slope[i] - slope[i - 1]);
      if (i + 2 < n)
      {
        off[i - 1] = h[i];
      }
    }
    SolveTridiagonal(diagonal, off, rhs);
    std::copy(rhs.begin(), rhs.end(), m.begin() + 1);
  }
  for (size_t i = 0; i + 1 < n; ++i)
  {
    f.b[i] = slope[i] - h[i] * (2.0 * m[i] + m[i + 1]) / 6.0;
    f.c[i] = m[i] / 2.0;
    f.d[i] = (m[i + 1] - m[i]) / (6.0 * h[i]);
  }
  const size_t last = n - 2;
  f.b[n - 1] = f.b[last] + 2.0 * f.c[last] * h[last] + 3.0 * f.d[last] * h[last] * h[last];
  return f;
}

double Function::EvaluateSpline(double at) const
{
  const size_t n = this->x.size();
  if (at < this->x[0])
  {
    return this->y[0] + (at - this->x[0]) * this->b[0];
  }
  if (at > this->x[n - 1])
  {
    return this->y[n - 1] + (at - this->x[n - 1]) * this->b[n - 1];
  }
  // The piece [x_k, x_k+1] holding `at` (the last piece for the last knot).
  size_t k = static_cast<size_t>(std::upper_bound(this->x.begin(), this->x.end(), at) - this->x.begin());
  k = std::min(k == 0 ? 0 : k - 1, n - 2);
  const double dx = at - this->x[k];
  return this->y[k] + dx * (this->b[k] + dx * (this->c[k] + dx * this->d[k]));
}

double Function::operator()(double at) const
{
  switch (this->kind)
  {
    case Kind::Constant:
      return this->a[0];
    case Kind::Linear:
      return this->a[0] * at + this->a[1];
    case Kind::Polynomial:
    {
      double value = 0.0;
      for (double coefficient : this->a)
      {
        value = value * at + coefficient;
      }
      return value;
    }
    case Kind::Multiplier:
      return this->scale * (*this->inner)(at);
    case Kind::SimmSpline:
    case Kind::NaturalCubicSpline:
    case Kind::PiecewiseLinear:
      return this->EvaluateSpline(at);
  }
  return 0.0;
}

const char* Function::KindName(Kind kind)
{
  switch (kind)
  {
    case Kind::Constant:
      return "Constant";
    case Kind::Linear:
      return "LinearFunction";
    case Kind::SimmSpline:
      return "SimmSpline";
    case Kind::NaturalCubicSpline:
      return "NaturalCubicSpline";
    case Kind::PiecewiseLinear:
      return "PiecewiseLinearFunction";
    case Kind::Polynomial:
      return "PolynomialFunction";
    case Kind::Multiplier:
      return "MultiplierFunction";
  }
  return "Function";
}
}
