// SPDX-License-Identifier: BSD-3-Clause
// Paths over OpenSim's wrap cylinders, spheres, ellipsoids and tori against closed forms and
// opensim-core's golden cases; the model's wrap settings read and honoured; bad wrap settings named.
// (OpenSim's own lengths: TestOpenSimKinematics.cxx.)
#include "OpenSim/MomentArms.h"
#include "OpenSim/OpenSimKinematics.h"
#include "OpenSim/OpenSimWrapping.h"
#include "OpenSimTestModels.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

using namespace md::osim;
using md::osim::test::ExpectInputError;
using md::osim::test::kSmallModel;

namespace
{
/// The segment from p1 to p2 around the cylinder about z of radius r: a straight line from p1 to
/// its tangent point, the helix, the line from the other tangent point to p2. Built from the
/// helix: r1 = (r, 0, 0), turning by `angle` while rising `rise`; p1 and p2 lie back and on
/// along the helix's tangents at its ends, `out1` and `out2` away (near enough that the straight
/// segment cuts the cylinder on the helix's side: then the helix is the shorter way round).
struct HelixCase
{
  Eigen::Vector3d p1, p2;
  double length;
};

HelixCase Helix(double r, double angle, double rise, double out1, double out2)
{
  const double arc = std::hypot(r * angle, rise);
  const auto tangent = [&](double phi) -> Eigen::Vector3d {
    return Eigen::Vector3d(-r * angle * std::sin(phi), r * angle * std::cos(phi), rise) / arc;
  };
  const Eigen::Vector3d r1(r, 0, 0), r2(r * std::cos(angle), r * std::sin(angle), rise);
  return { r1 - out1 * tangent(0), r2 + out2 * tangent(angle), out1 + arc + out2 };
}
}

TEST(OpenSimWrapping, APathAcrossACylinderIsAnArcOfItsCircle)
{
  // Across the axis (no rise), OpenSim's tangent points are exact: the length is the two
  // tangents and the arc, with or without sliding the tangent points.
  for (double angle : { 0.3, 1.0, 2.0, 3.0 })
  {
    const double reach = 0.05 / std::tan(0.5 * angle); // beyond it the straight segment misses
    const HelixCase c = Helix(0.05, angle, 0.0, 0.5 * reach, 0.3 * reach);
    for (bool adjust : { false, true })
    {
      WrapResult result;
      const WrapAction action = WrapCylinderSegment(c.p1, c.p2, 0.05, 1.0, 0, 0, adjust, result);
      EXPECT_EQ(action, WrapAction::Mandatory) << angle;
      const double length = (result.r1 - c.p1).norm() + result.length + (c.p2 - result.r2).norm();
      EXPECT_NEAR(length, c.length, 1e-12) << angle << " " << adjust;
      EXPECT_NEAR(result.length, 0.05 * angle, 1e-12);
      // The surface points lie on the cylinder, from r1 to r2, no farther apart than asked.
      const md::Points surface = SurfacePoints(result, 0.002);
      ASSERT_GE(surface.rows(), 2);
      for (Eigen::Index i = 0; i < surface.rows(); ++i)
      {
        EXPECT_NEAR(surface.row(i).head<2>().norm(), 0.05, 1e-12);
        if (i > 0)
        {
          EXPECT_LE((surface.row(i) - surface.row(i - 1)).norm(), 0.002);
        }
      }
      EXPECT_LT((surface.row(0).transpose() - result.r1).norm(), 1e-12);
      EXPECT_LT((surface.bottomRows<1>().transpose() - result.r2).norm(), 1e-12);
    }
  }
}

TEST(OpenSimWrapping, APathAlongACylinderIsAHelix)
{
  // Rising along the axis the path is a helix: length sqrt((r angle)^2 + rise^2) over the
  // surface. OpenSim's first estimate of the tangent points (a path with one wrap object) is
  // close; slid to tangency within 0.1 degree (several wrap objects) it is closer.
  const HelixCase c = Helix(0.04, 1.5, 0.03, 0.02, 0.015);
  WrapResult first, slid;
  ASSERT_EQ(WrapCylinderSegment(c.p1, c.p2, 0.04, 1.0, 0, 0, false, first), WrapAction::Mandatory);
  ASSERT_EQ(WrapCylinderSegment(c.p1, c.p2, 0.04, 1.0, 0, 0, true, slid), WrapAction::Mandatory);
  const auto total = [&](const WrapResult& w) {
    return (w.r1 - c.p1).norm() + w.length + (c.p2 - w.r2).norm();
  };
  // The surface length is the helix's between the tangent points.
  const Eigen::Vector2d u = slid.r1.head<2>(), v = slid.r2.head<2>();
  const double turned = std::atan2(u.x() * v.y() - u.y() * v.x(), u.dot(v));
  EXPECT_NEAR(slid.length, std::hypot(0.04 * turned, slid.r2.z() - slid.r1.z()), 1e-12);
  EXPECT_NEAR(total(first), c.length, 1e-3 * c.length);
  EXPECT_NEAR(total(slid), c.length, 1e-5 * c.length);
  EXPECT_LT(std::abs(total(slid) - c.length), std::abs(total(first) - c.length));
  // The true path is the shortest over the surface: no estimate is shorter.
  EXPECT_GE(total(first), c.length - 1e-12);
  EXPECT_GE(total(slid), c.length - 1e-12);
}

TEST(OpenSimWrapping, QuadrantEndsAndInsideDecideWhetherAPathWraps)
{
  // A segment passing the cylinder on its -y side, clear of it.
  const Eigen::Vector3d below1(-0.3, -0.08, 0), below2(0.3, -0.08, 0);
  WrapResult result;
  EXPECT_EQ(WrapCylinderSegment(below1, below2, 0.05, 1.0, 0, 0, false, result), WrapAction::NoWrap);
  // Constrained to +y, it goes over the +y side all the same (OpenSim's rule: with both ends
  // off the wrapping side, the path may be taken over it; the least lengthening decides).
  EXPECT_EQ(WrapCylinderSegment(below1, below2, 0.05, 1.0, 1, 1, false, result), WrapAction::Wrapped);
  EXPECT_GT(SurfacePoints(result, 0.002).col(1).maxCoeff(), 0.049);
  // Ends on either side of y = 0, the segment passing below, clear: over +y it may wrap (the
  // segment with the least lengthening is chosen among those that may), over -y it does not.
  const Eigen::Vector3d a(-0.3, 0.02, 0), b(0.3, -0.2, 0);
  EXPECT_EQ(WrapCylinderSegment(a, b, 0.05, 1.0, 1, 1, false, result), WrapAction::Wrapped);
  EXPECT_GT(SurfacePoints(result, 0.002).col(1).maxCoeff(), 0.049);
  EXPECT_EQ(WrapCylinderSegment(a, b, 0.05, 1.0, 1, -1, false, result), WrapAction::NoWrap);
  // Cutting through: mandatory over all of it and over its side the segment cuts.
  const Eigen::Vector3d c1(-0.3, 0.01, 0), c2(0.3, 0.01, 0);
  EXPECT_EQ(WrapCylinderSegment(c1, c2, 0.05, 1.0, 0, 0, false, result), WrapAction::Mandatory);
  EXPECT_GT(result.r1.y(), 0.0);
  EXPECT_EQ(WrapCylinderSegment(c1, c2, 0.05, 1.0, 1, 1, false, result), WrapAction::Mandatory);
  // An end inside; tangent points beyond both ends of a short cylinder.
  EXPECT_EQ(
    WrapCylinderSegment(Eigen::Vector3d(0.01, 0, 0), c2, 0.05, 1.0, 0, 0, false, result), WrapAction::InsideRadius);
  EXPECT_EQ(WrapCylinderSegment(
              Eigen::Vector3d(-0.3, 0.01, 0.5), Eigen::Vector3d(0.3, 0.01, 0.5), 0.05, 0.2, 0, 0, false, result),
    WrapAction::NoWrap);
}

TEST(OpenSimWrapping, TheSmallModelsPathWrapsOverItsCylinderOrEllipsoidUnlessInactive)
{
  std::string withEllipsoid = kSmallModel;
  const std::string cylinder = "<radius>0.1</radius><length>0.5</length></WrapCylinder>";
  withEllipsoid.replace(
    withEllipsoid.find(cylinder), cylinder.size(), "<dimensions>0.1 0.1 0.25</dimensions></WrapEllipsoid>");
  withEllipsoid.replace(withEllipsoid.find("<WrapCylinder "), 14, "<WrapEllipsoid ");
  for (const std::string& text : { std::string(kSmallModel), withEllipsoid })
  {
    Model model = ParseModel(text, "small.osim");
    const std::string what = model.wrapObjects[0].shape == WrapShape::Ellipsoid ? "ellipsoid" : "cylinder";
    const Path& path = model.paths[0];
    std::vector<double> q = DefaultCoordinates(model);
    // A pose whose straight path cuts the tibia's wrap object (radius 0.1 about the tibia's z).
    const std::vector<md::RigidTransform> poses = BodyPoses(model, q);
    const PathGeometry wrapped = PathAt(model, path, q, poses);
    model.wrapObjects[0].active = false;
    const PathGeometry straight = PathAt(model, path, q, poses);
    EXPECT_EQ(std::count(straight.pointIndex.begin(), straight.pointIndex.end(), -1), 0) << what;
    EXPECT_NEAR(straight.length, md::osim::PolylineLength(straight.points), 1e-15) << what;
    // Active, it wraps: wrapping only lengthens the path, and the drawn points measure what is
    // reported.
    EXPECT_GT(std::count(wrapped.pointIndex.begin(), wrapped.pointIndex.end(), -1), 1) << what;
    EXPECT_GT(wrapped.length, straight.length) << what;
    EXPECT_NEAR(md::osim::PolylineLength(wrapped.points), wrapped.length, 1e-4 * wrapped.length) << what;
  }
}

TEST(OpenSimWrapping, BadWrapSettingsAreNamed)
{
  std::string text = kSmallModel;
  text.replace(text.find("<radius>0.1</radius>"), 20, "<radius>0.1</radius><quadrant>w</quadrant>");
  std::string e = ExpectInputError([&] { ParseModel(text, "small.osim"); });
  EXPECT_NE(e.find("quadrant 'w'"), std::string::npos) << e;
  EXPECT_NE(e.find("'cyl'"), std::string::npos) << e;

  text = kSmallModel;
  text.replace(text.find("<radius>0.1</radius>"), 20, "<radius>-0.1</radius>");
  e = ExpectInputError([&] { ParseModel(text, "small.osim"); });
  EXPECT_NE(e.find("must be positive"), std::string::npos) << e;
  EXPECT_NE(e.find("'cyl'"), std::string::npos) << e;

  text = kSmallModel;
  text.replace(text.find("<wrap_object>cyl</wrap_object>"), 30, "<wrap_object>cylinder</wrap_object>");
  e = ExpectInputError([&] { ParseModel(text, "small.osim"); });
  EXPECT_NE(e.find("wrap object 'cylinder' is not in the model"), std::string::npos) << e;
  EXPECT_NE(e.find("PathWrap 'w'"), std::string::npos) << e;

  text = kSmallModel;
  text.replace(
    text.find("<wrap_object>cyl</wrap_object>"), 30, "<wrap_object>cyl</wrap_object><method>spiral</method>");
  e = ExpectInputError([&] { ParseModel(text, "small.osim"); });
  EXPECT_NE(e.find("wrapping method 'spiral' is not one of hybrid, midpoint or axial"), std::string::npos) << e;
  EXPECT_NE(e.find("PathWrap 'w'"), std::string::npos) << e;
  for (const auto& [name, method] : std::vector<std::pair<std::string, EllipsoidWrapMethod>>{
         { "hybrid", EllipsoidWrapMethod::Hybrid }, { "Unassigned", EllipsoidWrapMethod::Hybrid },
         { "Midpoint", EllipsoidWrapMethod::Midpoint }, { "AXIAL", EllipsoidWrapMethod::Axial } })
  {
    text = kSmallModel;
    text.replace(
      text.find("<wrap_object>cyl</wrap_object>"), 30, "<wrap_object>cyl</wrap_object><method>" + name + "</method>");
    EXPECT_EQ(ParseModel(text, "small.osim").paths[0].wraps[0].method, method) << name;
  }

  // Each quadrant name OpenSim accepts.
  for (const auto& [name, axis, sign] : std::vector<std::tuple<std::string, int, int>>{
         { "x", 0, 1 }, { "+X", 0, 1 }, { "-y", 1, -1 }, { "Z", 2, 1 }, { "-z", 2, -1 }, { "all", 0, 0 } })
  {
    text = kSmallModel;
    text.replace(text.find("<radius>0.1</radius>"), 20, "<radius>0.1</radius><quadrant>" + name + "</quadrant>");
    const Model m = ParseModel(text, "small.osim");
    EXPECT_EQ(m.wrapObjects[0].quadrantSign, sign) << name;
    if (sign != 0)
    {
      EXPECT_EQ(m.wrapObjects[0].quadrantAxis, axis) << name;
    }
  }
}

TEST(OpenSimWrapping, ANearbyPosesPathTakesTheOthersPointCount)
{
  PathGeometry path, like;
  path.points.resize(3, 3);
  path.points << 0, 0, 0, 1, 0, 0, 1, 1, 0; // length 2
  like.points.resize(5, 3);
  like.points << 0, 0, 0, 0.5, 0, 0, 1, 0, 0, 2, 0, 0, 4, 0, 0; // shares 0, 1/8, 1/4, 1/2, 1
  const md::Points same = PointsLike(path, path);
  EXPECT_EQ(same, path.points);
  const md::Points moved = PointsLike(path, like);
  ASSERT_EQ(moved.rows(), 5);
  const Eigen::Vector3d expected[5] = { { 0, 0, 0 }, { 0.25, 0, 0 }, { 0.5, 0, 0 }, { 1, 0, 0 }, { 1, 1, 0 } };
  for (int k = 0; k < 5; ++k)
  {
    EXPECT_LT((moved.row(k).transpose() - expected[k]).norm(), 1e-15) << k;
  }
}

TEST(OpenSimWrapping, APathOverAPulleyOnTheJointAxisHasItsRadiusAsMomentArm)
{
  // A cylinder of radius 0.05 on ground about the pin joint's axis (z through the origin), the
  // path from ground over it to the turning arm: each radian of the joint winds 0.05 of the path
  // on or off the pulley, wherever the tangent points are. Positive (shortening as q grows) where
  // the path goes round the +x side, negative round the -x side.
  const std::string model = R"(<?xml version="1.0"?>
<OpenSimDocument Version="40000"><Model name="pulley"><Ground name="ground">
  <WrapObjectSet><objects><WrapCylinder name="pulley"><radius>0.05</radius><length>0.5</length></WrapCylinder></objects></WrapObjectSet>
 </Ground>
 <BodySet><objects><Body name="arm"/></objects></BodySet>
 <JointSet><objects><PinJoint name="pin"><socket_parent_frame>/ground</socket_parent_frame><socket_child_frame>/bodyset/arm</socket_child_frame>
  <coordinates><Coordinate name="q"><range>-3 3</range></Coordinate></coordinates></PinJoint></objects></JointSet>
 <ForceSet><objects><PathSpring name="s"><GeometryPath name="path"><PathPointSet><objects>
  <PathPoint name="o"><socket_parent_frame>/ground</socket_parent_frame><location>0 0.3 0</location></PathPoint>
  <PathPoint name="i"><socket_parent_frame>/bodyset/arm</socket_parent_frame><location>0.02 -0.3 0</location></PathPoint>
 </objects></PathPointSet>
 <PathWrapSet><objects><PathWrap name="w"><wrap_object>pulley</wrap_object></PathWrap></objects></PathWrapSet>
 </GeometryPath></PathSpring></objects></ForceSet>
</Model></OpenSimDocument>)";
  const Model m = ParseModel(model, "pulley.osim");
  ASSERT_EQ(m.paths.size(), 1u);
  const int q = m.FindCoordinate("q");
  const auto at = [&](double angle) {
    std::vector<double> coordinates = DefaultCoordinates(m);
    coordinates[static_cast<size_t>(q)] = angle;
    return coordinates;
  };
  for (double angle : { -0.4, -0.1, 0.0, 0.1, 0.2 })
  {
    const std::vector<double> coordinates = at(angle);
    const PathGeometry g = PathAt(m, m.paths[0], coordinates, BodyPoses(m, coordinates));
    double side = 0;
    for (size_t i = 0; i < g.pointIndex.size(); ++i)
    {
      side += g.pointIndex[i] == -1 ? g.points(Eigen::Index(i), 0) : 0.0;
    }
    ASSERT_NE(side, 0.0) << angle; // it wraps
    EXPECT_NEAR(MomentArm(m, m.paths[0], coordinates, q, 1e-4), side > 0 ? 0.05 : -0.05, 1e-9) << angle;
  }
  // The same pulley on an offset frame of the arm (moved along its axis, turned about it: the
  // same surface) gives the same path.
  std::string onFrame = model;
  onFrame.replace(
    onFrame.find("<WrapObjectSet>"), onFrame.find("</WrapObjectSet>") + 16 - onFrame.find("<WrapObjectSet>"), "");
  onFrame.replace(onFrame.find("<Body name=\"arm\"/>"), 18,
    "<Body name=\"arm\"><components><PhysicalOffsetFrame "
    "name=\"arm_offset\"><socket_parent>/bodyset/arm</socket_parent>"
    "<translation>0 0 0.05</translation><orientation>0 0 0.3</orientation><WrapObjectSet><objects><WrapCylinder "
    "name=\"pulley\"><radius>0.05</radius><length>0.5</length></WrapCylinder></objects></WrapObjectSet>"
    "</PhysicalOffsetFrame></components></Body>");
  const Model framed = ParseModel(onFrame, "pulley_on_frame.osim");
  ASSERT_EQ(framed.wrapObjects.size(), 1u);
  EXPECT_EQ(framed.wrapObjects[0].body, framed.FindBody("arm"));
  for (double angle : { -0.4, 0.0, 0.2 })
  {
    const std::vector<double> coordinates = at(angle);
    EXPECT_NEAR(PathAt(framed, framed.paths[0], coordinates, BodyPoses(framed, coordinates)).length,
      PathAt(m, m.paths[0], coordinates, BodyPoses(m, coordinates)).length, 1e-12)
      << angle;
  }
  // Turned far enough, the straight path clears the pulley.
  const PathGeometry clear = PathAt(m, m.paths[0], at(0.5), BodyPoses(m, at(0.5)));
  EXPECT_EQ(std::count(clear.pointIndex.begin(), clear.pointIndex.end(), -1), 0);
  EXPECT_NEAR(clear.length, md::osim::PolylineLength(clear.points), 1e-15);
}

namespace
{
/// opensim-core's testGeometryPathWrapping model: `object` (an opening tag and its size; closed
/// here) on ground, turned by `rotation`, with `quadrant`; a pin joint about z at the origin; a
/// path from ground (0.4, 0.5, 0) to the pinned body's `insert`, over the object.
std::string PulleyModel(
  const std::string& object, const std::string& rotation, const std::string& quadrant, const std::string& insert)
{
  const std::string type = object.substr(1, object.find(' ') - 1);
  return R"(<?xml version="1.0"?>
<OpenSimDocument Version="40000"><Model name="perpendicular"><Ground name="ground">
  <WrapObjectSet><objects>)" +
    object + "<xyz_body_rotation>" + rotation + "</xyz_body_rotation><quadrant>" + quadrant + "</quadrant></" + type +
    R"(></objects></WrapObjectSet>
 </Ground>
 <BodySet><objects><Body name="body"/></objects></BodySet>
 <JointSet><objects><PinJoint name="pin"><socket_parent_frame>/ground</socket_parent_frame><socket_child_frame>/bodyset/body</socket_child_frame>
  <coordinates><Coordinate name="q_pin"/></coordinates></PinJoint></objects></JointSet>
 <ForceSet><objects><PathSpring name="spring1"><GeometryPath name="path"><PathPointSet><objects>
  <PathPoint name="origin"><socket_parent_frame>/ground</socket_parent_frame><location>0.4 0.5 0</location></PathPoint>
  <PathPoint name="insert"><socket_parent_frame>/bodyset/body</socket_parent_frame><location>)" +
    insert + R"(</location></PathPoint>
 </objects></PathPointSet>
 <PathWrapSet><objects><PathWrap name="w"><wrap_object>pulley1</wrap_object></PathWrap></objects></PathWrapSet>
 </GeometryPath></PathSpring></objects></ForceSet>
</Model></OpenSimDocument>)";
}
}

TEST(OpenSimWrapping, OpenSimsOwnPerpendicularCasesHaveTheirGoldenValues)
{
  // opensim-core's testGeometryPathWrapping, "WrapCylinder", "WrapSphere" and "WrapEllipsoid"
  // (testSingleWrapObjectPerpendicular): a wrap object of radius 0.5 on ground, turned as that
  // test turns it, and with quadrant +y; a path from ground (r - 0.1, r, 0) to a pin-jointed
  // body's (-r, r, 0). Over a quarter turn of the pin its moment arm is -r (OpenSim asserts to
  // 1e-4) and its length 2r - 0.1 plus the part of a quarter circle wound on (to 1e-6).
  const double r = 0.5;
  const std::string cylinder = "<WrapCylinder name=\"pulley1\"><radius>0.5</radius><length>1</length>";
  const std::string sphere = "<WrapSphere name=\"pulley1\"><radius>0.5</radius>";
  const std::string ellipsoid = "<WrapEllipsoid name=\"pulley1\"><dimensions>0.5 0.5 0.5</dimensions>";
  const std::vector<std::string> aboutZ = { "0 0 0", "0 0 1.5707963267948966", "0 0 3.141592653589793",
    "0 0 -1.5707963267948966" };
  std::vector<std::tuple<std::string, std::string, std::string>> cases;
  for (const std::string& rotation : aboutZ)
  {
    cases.emplace_back(cylinder, rotation, "all");
    cases.emplace_back(sphere, rotation, "all");
    cases.emplace_back(ellipsoid, rotation, "all");
  }
  for (const std::string& rotation : { "0 1.5707963267948966 0", "0 3.141592653589793 0", "0 -1.5707963267948966 0",
         "1.5707963267948966 0 0", "3.141592653589793 0 0", "-1.5707963267948966 0 0" })
  {
    cases.emplace_back(sphere, rotation, "all");
  }
  cases.emplace_back(cylinder, "0 0 0", "+y");
  cases.emplace_back(sphere, "0 0 0", "+y");
  cases.emplace_back(ellipsoid, "0 0 0", "+y");
  for (const auto& [object, rotation, quadrant] : cases)
  {
    const std::string type = object.substr(1, object.find(' ') - 1);
    const Model m = ParseModel(PulleyModel(object, rotation, quadrant, "-0.5 0.5 0"), "perpendicular.osim");
    const int q = m.FindCoordinate("q_pin");
    constexpr int kSteps = 50;
    for (int i = 0; i <= kSteps; ++i)
    {
      std::vector<double> coordinates = DefaultCoordinates(m);
      coordinates[static_cast<size_t>(q)] = i * M_PI / (2 * kSteps);
      const double length = PathAt(m, m.paths[0], coordinates, BodyPoses(m, coordinates)).length;
      const std::string what = type + " " + rotation + " " + quadrant + " step " + std::to_string(i);
      EXPECT_NEAR(length, 2 * r - 0.1 + 0.25 * 2 * M_PI * r * i / kSteps, 1e-6) << what;
      EXPECT_NEAR(MomentArm(m, m.paths[0], coordinates, q, 1e-6), -r, 1e-4) << what;
    }
  }
}

TEST(OpenSimWrapping, OpenSimsEllipsoidLengthCaseIsAQuarterOfTheEllipse)
{
  // opensim-core's testGeometryPathWrapping, "WrapEllipsoid", "Wrapping length": an ellipsoid of
  // radii (r / cos(angle), r, 1), r = 0.5, for angles from 0 to 80 degrees; the path from
  // (r - 0.1, r, 0) to (-a, -r, 0) runs along y = r to the ellipse's top, over a quarter of the
  // ellipse x^2/a^2 + y^2/r^2 = 1 and down x = -a. OpenSim asserts Ramanujan's perimeter to 1e-4;
  // here the quarter is also integrated, to 1e-9.
  const double r = 0.5;
  for (int degrees = 0; degrees <= 80; degrees += 5)
  {
    const double a = r / std::cos(degrees * M_PI / 180);
    std::ostringstream object, insert;
    object.precision(17);
    insert.precision(17);
    object << "<WrapEllipsoid name=\"pulley1\"><dimensions>" << a << " " << r << " 1</dimensions>";
    insert << -a << " " << -r << " 0";
    const Model m = ParseModel(PulleyModel(object.str(), "0 0 0", "all", insert.str()), "ellipse.osim");
    const std::vector<double> q = DefaultCoordinates(m);
    const double length = PathAt(m, m.paths[0], q, BodyPoses(m, q)).length;
    const double h = (a - r) * (a - r) / ((a + r) * (a + r));
    const double ramanujan = M_PI * (a + r) * (1 + 3 * h / (10 + std::sqrt(4 - 3 * h)));
    EXPECT_NEAR(length, 2 * r - 0.1 + ramanujan / 4, 1e-4) << degrees;
    // The quarter's length by Simpson's rule over the parameter (x, y) = (a sin t, r cos t).
    constexpr int kIntervals = 20000;
    double quarter = 0.0;
    for (int i = 0; i <= kIntervals; ++i)
    {
      const double t = 0.5 * M_PI * i / kIntervals;
      const double weight = i == 0 || i == kIntervals ? 1.0 : i % 2 == 1 ? 4.0 : 2.0;
      quarter += weight * std::hypot(a * std::cos(t), r * std::sin(t));
    }
    quarter *= 0.5 * M_PI / kIntervals / 3.0;
    EXPECT_NEAR(length, 2 * r - 0.1 + quarter, 1e-9) << degrees;
  }
}

TEST(OpenSimWrapping, APathOverASphereIsAnArcOfAGreatCircle)
{
  // A great circle in a tilted plane: r1 on it, the arc turning by `angle`, the ends back and on
  // along its tangents (near enough that the segment cuts the sphere on the arc's side). The
  // tangent points are exact: the length is the tangents' and the arc's, R angle.
  const double radius = 0.03;
  const Eigen::Vector3d normal = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  const Eigen::Vector3d u = normal.unitOrthogonal(), v = normal.cross(u);
  for (double angle : { 0.4, 1.2, 2.5 })
  {
    const double reach = radius / std::tan(0.5 * angle);
    const auto at = [&](double phi) -> Eigen::Vector3d {
      return radius * (std::cos(phi) * u + std::sin(phi) * v);
    };
    const auto tangent = [&](double phi) -> Eigen::Vector3d {
      return -std::sin(phi) * u + std::cos(phi) * v;
    };
    const Eigen::Vector3d p1 = at(0) - 0.6 * reach * tangent(0), p2 = at(angle) + 0.4 * reach * tangent(angle);
    WrapResult result;
    ASSERT_EQ(WrapSphereSegment(p1, p2, radius, 0, 0, result), WrapAction::Wrapped) << angle;
    EXPECT_LT((result.r1 - at(0)).norm(), 1e-12) << angle;
    EXPECT_LT((result.r2 - at(angle)).norm(), 1e-12) << angle;
    EXPECT_NEAR(result.length, radius * angle, 1e-12) << angle;
    const md::Points surface = SurfacePoints(result, 0.002);
    for (Eigen::Index i = 0; i < surface.rows(); ++i)
    {
      EXPECT_NEAR(surface.row(i).norm(), radius, 1e-12);
      EXPECT_NEAR(surface.row(i).dot(normal), 0.0, 1e-12);
    }
  }
  // An end inside; a segment clear of the sphere.
  WrapResult result;
  EXPECT_EQ(WrapSphereSegment(Eigen::Vector3d(0.01, 0, 0), Eigen::Vector3d(0.3, 0, 0), radius, 0, 0, result),
    WrapAction::InsideRadius);
  EXPECT_EQ(WrapSphereSegment(Eigen::Vector3d(-0.3, 0.05, 0), Eigen::Vector3d(0.3, 0.05, 0), radius, 0, 0, result),
    WrapAction::NoWrap);
}

namespace
{
/// Segments that cut the ellipsoid of `radii` about the origin: from a point 1.5-3 of its
/// largest radius out, through a point inside it (at `least` to `most` of the way out from the
/// centre), to a point outside beyond (deterministic).
std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> CuttingSegments(
  const Eigen::Vector3d& radii, int count, double least = 0.0, double most = 0.6)
{
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto direction = [&]() {
    Eigen::Vector3d d;
    do
    {
      d = Eigen::Vector3d(unit(random), unit(random), unit(random));
    }
    while (d.norm() < 0.1 || d.norm() > 1.0);
    return Eigen::Vector3d(d.normalized());
  };
  const auto outside = [&](const Eigen::Vector3d& x) {
    return x.cwiseQuotient(radii).squaredNorm() > 1.1;
  };
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> segments;
  while (static_cast<int>(segments.size()) < count)
  {
    const Eigen::Vector3d p1 = (2.25 + 0.75 * unit(random)) * radii.maxCoeff() * direction();
    const Eigen::Vector3d through = (least + (most - least) * std::abs(unit(random))) * radii.cwiseProduct(direction());
    const Eigen::Vector3d p2 = p1 + (2.0 + 0.5 * unit(random)) * (through - p1);
    if (outside(p1) && outside(p2))
    {
      segments.emplace_back(p1, p2);
    }
  }
  return segments;
}
}

TEST(OpenSimWrapping, AnEllipsoidOfEqualRadiiWrapsAsASphere)
{
  // Each method finds the plane through the centre (the great circle's): the tangent points and
  // the arc are the sphere's.
  const double radius = 0.04;
  for (const EllipsoidWrapMethod method :
    { EllipsoidWrapMethod::Hybrid, EllipsoidWrapMethod::Midpoint, EllipsoidWrapMethod::Axial })
  {
    for (const auto& [p1, p2] : CuttingSegments(Eigen::Vector3d::Constant(radius), 40))
    {
      WrapResult sphere, ellipsoid;
      ASSERT_NE(WrapSphereSegment(p1, p2, radius, 0, 0, sphere), WrapAction::NoWrap);
      ASSERT_EQ(WrapEllipsoidSegment(p1, p2, Eigen::Vector3d::Constant(radius), 0, 0, method, ellipsoid),
        WrapAction::Mandatory);
      EXPECT_LT((ellipsoid.r1 - sphere.r1).norm(), 1e-12);
      EXPECT_LT((ellipsoid.r2 - sphere.r2).norm(), 1e-12);
      EXPECT_NEAR(ellipsoid.length, sphere.length, 1e-12);
      const md::Points surface = SurfacePoints(ellipsoid, 0.002);
      for (Eigen::Index i = 0; i < surface.rows(); ++i)
      {
        EXPECT_NEAR(surface.row(i).norm(), radius, 1e-12);
      }
    }
  }
}

TEST(OpenSimWrapping, APathOverAnEllipsoidFollowsItsSectionFromTangentToTangent)
{
  // A triaxial ellipsoid; segments that cut it in any direction, by each method. The tangent
  // points are on the ellipsoid, in one plane with p1 and p2 (the wrap's), and the lines to them
  // touch it; the surface path lies on the ellipsoid in that plane, its drawn points measure the
  // length, and the wrapped path is longer than the straight one. Where the segment cuts the
  // ellipsoid no deeper than halfway to its centre, a small move of an end moves the length by at
  // most that much. (Deeper, the wrap's plane may turn fast with the ends, in OpenSim as here:
  // the ellipsoid's point nearest a point near an ellipse's medial axis does.)
  const Eigen::Vector3d radii(0.05, 0.03, 0.02);
  const auto level = [&](const Eigen::Vector3d& x) {
    return x.cwiseQuotient(radii).squaredNorm() - 1.0;
  };
  const auto normalAt = [&](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(x.cwiseQuotient(radii.cwiseAbs2()).normalized());
  };
  int shallow = 0;
  for (const EllipsoidWrapMethod method :
    { EllipsoidWrapMethod::Hybrid, EllipsoidWrapMethod::Midpoint, EllipsoidWrapMethod::Axial })
  {
    int index = 0;
    for (const auto& [p1, p2] : CuttingSegments(radii, 60, 0.0, 0.95))
    {
      const std::string what =
        "method " + std::to_string(static_cast<int>(method)) + " segment " + std::to_string(index++);
      WrapResult result;
      ASSERT_EQ(WrapEllipsoidSegment(p1, p2, radii, 0, 0, method, result), WrapAction::Mandatory) << what;
      EXPECT_NEAR(level(result.r1), 0.0, 1e-12) << what;
      EXPECT_NEAR(level(result.r2), 0.0, 1e-12) << what;
      const Eigen::Vector3d plane = (p1 - p2).cross(result.r1 - p2).normalized();
      EXPECT_NEAR(plane.dot(result.r2 - p2), 0.0, 1e-12) << what;
      EXPECT_NEAR(normalAt(result.r1).dot((p1 - result.r1).normalized()), 0.0, 1e-9) << what;
      EXPECT_NEAR(normalAt(result.r2).dot((p2 - result.r2).normalized()), 0.0, 1e-9) << what;
      const md::Points surface = SurfacePoints(result, 0.0001);
      double drawn = 0.0;
      for (Eigen::Index i = 0; i < surface.rows(); ++i)
      {
        const Eigen::Vector3d x = surface.row(i).transpose();
        EXPECT_NEAR(level(x), 0.0, 1e-12) << what;
        EXPECT_NEAR(plane.dot(x - p2), 0.0, 1e-12) << what;
        drawn += i > 0 ? (surface.row(i) - surface.row(i - 1)).norm() : 0.0;
      }
      EXPECT_NEAR(drawn, result.length, 1e-4 * result.length) << what;
      const double wrapped = (result.r1 - p1).norm() + result.length + (p2 - result.r2).norm();
      EXPECT_GT(wrapped, (p2 - p1).norm()) << what;
      // How near the segment's line comes to the centre, in radii.
      const Eigen::Vector3d s1 = p1.cwiseQuotient(radii), s2 = p2.cwiseQuotient(radii);
      if ((s1 - s1.dot((s2 - s1).normalized()) * (s2 - s1).normalized()).norm() < 0.5)
      {
        continue;
      }
      ++shallow;
      WrapResult moved;
      const Eigen::Vector3d nudge(1e-7, -1e-7, 1e-7);
      ASSERT_EQ(WrapEllipsoidSegment(p1 + nudge, p2, radii, 0, 0, method, moved), WrapAction::Mandatory) << what;
      const double movedWrapped = (moved.r1 - p1 - nudge).norm() + moved.length + (p2 - moved.r2).norm();
      EXPECT_NEAR(movedWrapped, wrapped, 1e-6) << what;
    }
  }
  EXPECT_GE(shallow, 60);
  // An end inside; a segment clear of the ellipsoid; p1 and p2 in one direction from its centre.
  WrapResult result;
  const auto wrap = [&](const Eigen::Vector3d& p1, const Eigen::Vector3d& p2) {
    return WrapEllipsoidSegment(p1, p2, radii, 0, 0, EllipsoidWrapMethod::Hybrid, result);
  };
  EXPECT_EQ(wrap(Eigen::Vector3d(0.04, 0, 0), Eigen::Vector3d(0.3, 0.1, 0)), WrapAction::InsideRadius);
  EXPECT_EQ(wrap(Eigen::Vector3d(-0.3, 0.035, 0), Eigen::Vector3d(0.3, 0.035, 0)), WrapAction::NoWrap);
  EXPECT_EQ(wrap(Eigen::Vector3d(0.1, 0, 0), Eigen::Vector3d(0.2, 0, 0)), WrapAction::NoWrap);
}

TEST(OpenSimWrapping, APathThroughATorusWrapsTheInsideOfItsTube)
{
  // A ring of radius 0.1 about z with a tube of 0.02; a segment in the plane y = 0 from above to
  // below, passing through the tube near its inner side. In that plane the tube's section is a
  // circle about (0.1, 0, 0), and OpenSim's cylinder along the ring's tangent there is exact: the
  // path is the two tangents to the circle and the arc between them on the side facing the
  // torus's centre.
  const Eigen::Vector3d centre(0.1, 0, 0);
  const double tube = 0.02;
  for (const double x : { 0.085, 0.09, 0.095 })
  {
    const Eigen::Vector3d p1(x, 0, 0.1), p2(x, 0, -0.12);
    WrapResult result;
    ASSERT_EQ(WrapTorusSegment(p1, p2, 0.1, tube, 0, 0, false, result), WrapAction::Mandatory) << x;
    const auto tangentLength = [&](const Eigen::Vector3d& p) {
      return std::sqrt((p - centre).squaredNorm() - tube * tube);
    };
    // The arc: the angle between the ends' directions from the centre (the short way, here
    // through -x, the inner side), less each end's tangent angle.
    const Eigen::Vector3d d1 = (p1 - centre).normalized(), d2 = (p2 - centre).normalized();
    const double between = std::acos(d1.dot(d2));
    const double arc = between - std::acos(tube / (p1 - centre).norm()) - std::acos(tube / (p2 - centre).norm());
    const double expected = tangentLength(p1) + tube * arc + tangentLength(p2);
    const double length = (result.r1 - p1).norm() + result.length + (p2 - result.r2).norm();
    EXPECT_NEAR(length, expected, 1e-12) << x;
    EXPECT_NEAR(result.length, tube * arc, 1e-12) << x;
    // On the tube, on its inner side, in the plane.
    const md::Points surface = SurfacePoints(result, 0.002);
    for (Eigen::Index i = 0; i < surface.rows(); ++i)
    {
      EXPECT_NEAR((surface.row(i).transpose() - centre).norm(), tube, 1e-12);
      EXPECT_LT(surface(i, 0), 0.1 + 1e-12);
      EXPECT_NEAR(surface(i, 1), 0.0, 1e-12);
    }
  }
  // A segment through the hole, clear of the tube, does not wrap.
  WrapResult result;
  EXPECT_EQ(
    WrapTorusSegment(Eigen::Vector3d(0.02, 0, 0.1), Eigen::Vector3d(0.02, 0, -0.1), 0.1, tube, 0, 0, false, result),
    WrapAction::NoWrap);
}
