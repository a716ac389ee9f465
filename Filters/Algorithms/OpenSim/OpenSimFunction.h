// SPDX-License-Identifier: BSD-3-Clause
// Functions of one coordinate as OpenSim's model files define them: the
// displacements of a CustomJoint's axes, the locations of moving path points,
// coordinate couplers. Plain C++, no XML here (OpenSimModel reads them).
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace md::osim
{
/// One OpenSim function y = f(x). Immutable once made; cheap to copy.
class Function
{
public:
  enum class Kind
  {
    Constant,
    Linear,
    SimmSpline,
    NaturalCubicSpline,
    PiecewiseLinear,
    Polynomial,
    Multiplier
  };

  /// f(x) = value. The default function (an axis without one) is Constant(0).
  static Function Constant(double value);
  /// f(x) = slope x + intercept (OpenSim's LinearFunction, coefficients "slope intercept").
  static Function Linear(double slope, double intercept);
  /// OpenSim's SimmSpline: the cubic spline of Forsythe, Malcolm and Moler, whose end conditions
  /// match the third derivatives of the cubics through the first and last four knots (divided
  /// differences); two knots give a line. Outside the knots it extends linearly with the end
  /// slopes. Throws InputError unless x has at least 2 strictly increasing values and |y| = |x|.
  static Function SimmSpline(std::vector<double> x, std::vector<double> y);
  /// Natural cubic spline (zero second derivative at both ends), extended linearly outside.
  static Function NaturalCubicSpline(std::vector<double> x, std::vector<double> y);
  /// Straight segments between the knots, extended linearly with the end segments' slopes.
  static Function PiecewiseLinear(std::vector<double> x, std::vector<double> y);
  /// Polynomial with coefficients from the highest power down (OpenSim's order).
  static Function Polynomial(std::vector<double> coefficients);
  /// scale * inner(x) (OpenSim's MultiplierFunction).
  static Function Multiplier(const Function& inner, double scale);

  double operator()(double x) const;

  Kind GetKind() const { return this->kind; }
  /// The slope of a Linear function (0 for other kinds).
  double Slope() const { return this->kind == Kind::Linear ? this->a[0] : 0.0; }
  /// Name of the kind as in OpenSim's files, for messages.
  static const char* KindName(Kind kind);

private:
  Function() = default;
  /// A function of `kind` on checked knots, with zero cubic pieces to fill in.
  static Function WithKnots(Kind kind, std::vector<double> x, std::vector<double> y);
  double EvaluateSpline(double x) const;

  Kind kind = Kind::Constant;
  double scale = 1.0;
  // Knots (splines, piecewise linear) or coefficients (a: constant, linear, polynomial).
  std::vector<double> x, y;
  // Cubic pieces y_k + b_k dx + c_k dx^2 + d_k dx^3 on [x_k, x_k+1].
  std::vector<double> a, b, c, d;
  std::shared_ptr<const Function> inner;
};
}
