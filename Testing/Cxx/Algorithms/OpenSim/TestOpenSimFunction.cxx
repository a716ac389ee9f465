// SPDX-License-Identifier: BSD-3-Clause
// OpenSim's functions: SimmSpline as OpenSim evaluates it, and the other kinds.
#include "OpenSim/OpenSimFunction.h"
#include "OpenSimTestModels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

using namespace md::osim;
using namespace md::osim::test;

namespace
{
double Derivative(const Function& f, double x, double h = 1e-6)
{
  return (f(x + h) - f(x - h)) / (2 * h);
}

double SecondDerivative(const Function& f, double x, double h = 1e-4)
{
  return (f(x + h) - 2 * f(x) + f(x - h)) / (h * h);
}
}

TEST(OpenSimFunction, SimmSplineReproducesCubicsAndExtendsLinearly)
{
  // OpenSim's end conditions match the third derivative of the end cubics: a cubic is exact.
  auto cubic = [](double x) {
    return 0.3 * x * x * x - x * x + 2 * x - 1;
  };
  std::vector<double> x = { -2, -1.2, -0.1, 0.5, 1.7, 3 }, y;
  for (double v : x)
  {
    y.push_back(cubic(v));
  }
  const Function spline = Function::SimmSpline(x, y);
  for (double v = -2; v <= 3; v += 0.05)
  {
    EXPECT_NEAR(spline(v), cubic(v), 1e-12) << v;
  }
  // Outside the knots: straight on with the end slopes.
  auto slope = [](double x) {
    return 0.9 * x * x - 2 * x + 2;
  };
  EXPECT_NEAR(spline(4), cubic(3) + slope(3), 1e-12);
  EXPECT_NEAR(spline(-3), cubic(-2) - slope(-2), 1e-12);
  // A natural spline is not the same: its second derivative vanishes at the ends.
  const Function natural = Function::NaturalCubicSpline(x, y);
  EXPECT_GT(std::abs(natural(-1.6) - cubic(-1.6)), 1e-3);
  EXPECT_NEAR(SecondDerivative(natural, -2 + 2e-4), 0.0, 2e-2);
  for (size_t i = 0; i < x.size(); ++i)
  {
    EXPECT_NEAR(natural(x[i]), y[i], 1e-12);
  }
}

TEST(OpenSimFunction, SimmSplineIsSmoothThroughUnevenKnots)
{
  const std::vector<double> x = { -2.0944, -1.74533, -1.39626, -1.0472, -0.698132, -0.349066, -0.174533, 0.197344,
    0.337395, 0.490178, 1.52146, 2.0944 };
  const std::vector<double> y = { -0.0032, 0.00179, 0.00411, 0.0041, 0.00212, -0.001, -0.0031, -0.005227, -0.005435,
    -0.005574, -0.005435, -0.00525 };
  const Function f = Function::SimmSpline(x, y);
  for (size_t i = 0; i < x.size(); ++i)
  {
    EXPECT_NEAR(f(x[i]), y[i], 1e-15);
  }
  for (size_t i = 1; i + 1 < x.size(); ++i)
  {
    // C1 and C2 at the inner knots.
    EXPECT_NEAR(Derivative(f, x[i] - 1e-7, 1e-7), Derivative(f, x[i] + 1e-7, 1e-7), 1e-5) << i;
    EXPECT_NEAR(SecondDerivative(f, x[i] - 2e-4, 1e-4), SecondDerivative(f, x[i] + 2e-4, 1e-4), 1e-2) << i;
  }
  // Two knots: a line.
  const Function line = Function::SimmSpline({ 0, 2 }, { 1, 5 });
  EXPECT_DOUBLE_EQ(line(1), 3);
  EXPECT_DOUBLE_EQ(line(3), 7);
}

TEST(OpenSimFunction, OtherKinds)
{
  EXPECT_DOUBLE_EQ(Function::Constant(3)(7), 3);
  EXPECT_DOUBLE_EQ(Function::Linear(2, 1)(3), 7);
  EXPECT_DOUBLE_EQ(Function::Polynomial({ 2, -1, 3 })(2), 2 * 4 - 2 + 3); // highest power first
  EXPECT_DOUBLE_EQ(Function::Multiplier(Function::Linear(1, 1), 0.5)(3), 2);
  const Function pl = Function::PiecewiseLinear({ 0, 1, 3 }, { 0, 2, 3 });
  EXPECT_DOUBLE_EQ(pl(0.5), 1);
  EXPECT_DOUBLE_EQ(pl(2), 2.5);
  EXPECT_DOUBLE_EQ(pl(5), 4);
  EXPECT_DOUBLE_EQ(pl(-1), -2);
  EXPECT_NE(ExpectInputError([] {
    Function::SimmSpline({ 0, 0, 1 }, { 1, 2, 3 });
  }).find("do not increase"),
    std::string::npos);
  EXPECT_NE(ExpectInputError([] {
    Function::SimmSpline({ 0, 1 }, { 1 });
  }).find("2 x values but 1"),
    std::string::npos);
}
