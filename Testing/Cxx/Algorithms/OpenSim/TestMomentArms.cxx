// SPDX-License-Identifier: BSD-3-Clause
// Moment arms by tendon excursion against the closed form of a pin joint, across a conditional
// point's switch, and through a coupler.
#include "OpenSim/MomentArms.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace md::osim;

namespace
{
/// A femur on a pin about z at the origin; the path runs from (0.05, 0.1, 0) on the pelvis, by
/// `via` on the femur while the angle is in [0, 1], to (0, -0.3, 0) on the femur.
std::string PinModel(const std::string& via)
{
  return R"(<?xml version="1.0"?>
<OpenSimDocument Version="40000"><Model name="pin">
 <Ground name="ground"/>
 <BodySet><objects><Body name="pelvis"/><Body name="femur"/></objects></BodySet>
 <JointSet><objects>
  <WeldJoint name="ground_pelvis"><socket_parent_frame>/ground</socket_parent_frame><socket_child_frame>/bodyset/pelvis</socket_child_frame></WeldJoint>
  <PinJoint name="hip"><socket_parent_frame>/bodyset/pelvis</socket_parent_frame><socket_child_frame>/bodyset/femur</socket_child_frame>
   <coordinates><Coordinate name="flex"><range>-2 2</range></Coordinate></coordinates></PinJoint>
 </objects></JointSet>
 <ForceSet><objects><Thelen2003Muscle name="m"><GeometryPath name="path"><PathPointSet><objects>
  <PathPoint name="o"><socket_parent_frame>/bodyset/pelvis</socket_parent_frame><location>0.05 0.1 0</location></PathPoint>
  <ConditionalPathPoint name="v"><socket_parent_frame>/bodyset/femur</socket_parent_frame><location>)" +
    via +
    R"(</location><socket_coordinate>/jointset/hip/flex</socket_coordinate><range>0 1</range></ConditionalPathPoint>
  <PathPoint name="i"><socket_parent_frame>/bodyset/femur</socket_parent_frame><location>0 -0.3 0</location></PathPoint>
 </objects></PathPointSet></GeometryPath></Thelen2003Muscle></objects></ForceSet>
</Model></OpenSimDocument>)";
}

Eigen::Vector3d Rotated(double q, const Eigen::Vector3d& p)
{
  return Eigen::AngleAxisd(q, Eigen::Vector3d::UnitZ()) * p;
}

/// -dL/dq of the path through `points` (the first on the pelvis, the rest on the femur) in closed form.
double ClosedForm(double q, const std::vector<Eigen::Vector3d>& points)
{
  double dLdq = 0.0;
  for (size_t i = 1; i < points.size(); ++i)
  {
    const Eigen::Vector3d from = i == 1 ? points[0] : Rotated(q, points[i - 1]), to = Rotated(q, points[i]);
    const Eigen::Vector3d velocity =
      Eigen::Vector3d::UnitZ().cross(to) - (i == 1 ? Eigen::Vector3d::Zero() : Eigen::Vector3d::UnitZ().cross(from));
    dLdq += (to - from).normalized().dot(velocity);
  }
  return -dLdq;
}
}

TEST(MomentArms, APinJointsMomentArmIsTheClosedForms)
{
  const Model model = ParseModel(PinModel("0.1 -0.15 0"), "pin.osim");
  const int flex = model.FindCoordinate("flex");
  const Eigen::Vector3d origin(0.05, 0.1, 0), via(0.1, -0.15, 0), insertion(0, -0.3, 0);
  for (double q : { -1.0, -0.5, -0.1, 0.3, 0.8, 1.5 })
  {
    std::vector<double> pose = DefaultCoordinates(model);
    pose[flex] = q;
    const bool viaActive = q >= 0 && q <= 1;
    const std::vector<Eigen::Vector3d> points = viaActive ? std::vector<Eigen::Vector3d>{ origin, via, insertion }
                                                          : std::vector<Eigen::Vector3d>{ origin, insertion };
    EXPECT_NEAR(MomentArm(model, model.paths[0], pose, flex), ClosedForm(q, points), 1e-8) << q;
    const PathMoments moments = MomentsAt(model, pose, { flex });
    EXPECT_EQ(moments.momentArm[0][0], MomentArm(model, model.paths[0], pose, flex));
    EXPECT_NEAR(moments.length[0], PathLength(model, model.paths[0], pose), 1e-15);
  }
}

TEST(MomentArms, AtAConditionalPointsSwitchTheArmIsThatOfThePathAsItIs)
{
  // The via point comes at q = 0 (-1e-5, OpenSim's slack): within one step of it, the difference
  // is taken on the side where the path has the same points. A central one would mix the two
  // paths' lengths (a length jump of about 0.03 over 2e-4: an arm of about -150).
  const Model model = ParseModel(PinModel("0.1 -0.15 0"), "pin.osim");
  const int flex = model.FindCoordinate("flex");
  const Eigen::Vector3d origin(0.05, 0.1, 0), via(0.1, -0.15, 0), insertion(0, -0.3, 0);
  for (double q : { 0.00004, -0.00006, 0.99996, 1.00004 })
  {
    std::vector<double> pose = DefaultCoordinates(model);
    pose[flex] = q;
    const bool viaActive = q >= -1e-5 && q <= 1 + 1e-5;
    const std::vector<Eigen::Vector3d> points = viaActive ? std::vector<Eigen::Vector3d>{ origin, via, insertion }
                                                          : std::vector<Eigen::Vector3d>{ origin, insertion };
    EXPECT_NEAR(MomentArm(model, model.paths[0], pose, flex), ClosedForm(q, points), 1e-5) << q;
  }
}

TEST(MomentArms, OnlyTheCoordinatesThatMoveAreMoving)
{
  CoordinateTrajectory trajectory;
  trajectory.times = { 0, 1, 2 };
  trajectory.frames = { { 0.5, 1.0, 0.0 }, { 0.5, 1.2, 0.0 }, { 0.5, 1.0, 1e-3 } };
  EXPECT_EQ(MovingCoordinates(trajectory), (std::vector<int>{ 1, 2 }));
  EXPECT_TRUE(MovingCoordinates(CoordinateTrajectory{}).empty());
}

TEST(MomentArms, AFadingConditionalPointMakesThePathContinuous)
{
  // The via point is active for q in [0, 1]. Faded over 0.2 rad, the path is OpenSim's wherever
  // the point is active, the straight path 0.2 beyond its range, and continuous in between.
  const Model model = ParseModel(PinModel("0.1 -0.15 0"), "pin.osim");
  const int flex = model.FindCoordinate("flex");
  auto length = [&](double q, double fade) {
    std::vector<double> pose = DefaultCoordinates(model);
    pose[flex] = q;
    const PathGeometry g = PathAt(model, model.paths[0], pose, BodyPoses(model, pose), fade);
    return std::make_pair(PolylineLength(g.points), g.points.rows());
  };
  EXPECT_EQ(length(0.5, 0.2), length(0.5, 0.0));
  EXPECT_EQ(length(0.5, 0.2).second, 3);
  EXPECT_EQ(length(-0.5, 0.0).second, 2);
  EXPECT_EQ(length(-0.5, 0.2).second, 3); // the point kept, on the straight segment
  EXPECT_NEAR(length(-0.5, 0.2).first, length(-0.5, 0.0).first, 1e-12);
  EXPECT_NEAR(length(-0.21, 0.2).first, length(-0.21, 0.0).first, 1e-12);
  // OpenSim's length jumps at the range's end; the faded one moves by no more than its slope says.
  EXPECT_GT(std::abs(length(-0.011, 0.0).first - length(0.0, 0.0).first), 0.01);
  double largestStep = 0;
  for (double q = -0.3; q < 0.1; q += 0.001)
  {
    largestStep = std::max(largestStep, std::abs(length(q + 0.001, 0.2).first - length(q, 0.2).first));
  }
  EXPECT_LT(largestStep, 0.001);
}

TEST(MomentArms, APathAtANearbyPoseCanKeepThePointsAndFadesOfThisOne)
{
  // At q = -0.1 the via point (active on [0, 1]) is half faded over 0.2 rad. Stepped by +-0.01
  // with the conditions of q, the path keeps that weight: its length changes only as the bodies
  // move, and the central difference is the moment arm of the path as it is at q.
  const Model model = ParseModel(PinModel("0.1 -0.15 0"), "pin.osim");
  const int flex = model.FindCoordinate("flex");
  const double fade = 0.2, step = 0.01;
  std::vector<double> q = DefaultCoordinates(model);
  q[flex] = -0.1;
  const auto lengthAt = [&](double delta, const std::vector<double>* conditionsAt) {
    const std::vector<double> moved = MovedCoordinate(model, q, flex, delta);
    return PolylineLength(PathAt(model, model.paths[0], moved, BodyPoses(model, moved), fade, conditionsAt).points);
  };
  EXPECT_EQ(lengthAt(0.0, &q), lengthAt(0.0, nullptr));
  const double held = -(lengthAt(step, &q) - lengthAt(-step, &q)) / (2 * step);
  const double fading = -(lengthAt(step, nullptr) - lengthAt(-step, nullptr)) / (2 * step);
  // The held path is the fixed polyline o -> (the point at weight 1/2 on its segment) -> i, its
  // points on the femur moving rigidly: its excursion, by a finer difference of the same path.
  const double fine = -(lengthAt(1e-5, &q) - lengthAt(-1e-5, &q)) / 2e-5;
  EXPECT_NEAR(held, fine, 1e-5);
  // Letting the weight follow q adds the fade's own slope: a different, larger number here.
  EXPECT_GT(std::abs(fading - held), 0.01);
  // The coupled-coordinate rule of MomentArm: a coordinate moved alone.
  EXPECT_EQ(MovedCoordinate(model, q, flex, 0.25)[flex], -0.1 + 0.25);
}
