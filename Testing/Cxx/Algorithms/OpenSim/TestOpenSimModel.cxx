// SPDX-License-Identifier: BSD-3-Clause
// Reading a model: joints composed as Simbody composes them, wrap surfaces, muscle properties, bad
// input named.
#include "OpenSim/OpenSimKinematics.h"
#include "OpenSimTestModels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

using namespace md::osim;
using namespace md::osim::test;

namespace
{
Eigen::Matrix3d Rot(const Eigen::Vector3d& axis, double angle)
{
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}
}

TEST(OpenSimModel, JointsComposeAsSimbody)
{
  const Model model = ParseModel(kSmallModel, "small.osim");
  ASSERT_EQ(model.bodies.size(), 6u);
  ASSERT_EQ(model.coordinates.size(), 13u);
  EXPECT_EQ(model.coordinates[model.FindCoordinate("flex")].motionType, MotionType::Rotational);
  EXPECT_EQ(model.coordinates[model.FindCoordinate("add")].motionType, MotionType::Rotational); // slope -1
  EXPECT_EQ(model.coordinates[model.FindCoordinate("beta")].motionType, MotionType::Coupled);
  EXPECT_EQ(model.coordinates[model.FindCoordinate("tx")].motionType, MotionType::Translational);
  EXPECT_EQ(model.coordinates[model.FindCoordinate("sled_rz")].motionType, MotionType::Rotational);
  EXPECT_EQ(model.coordinates[model.FindCoordinate("sled_ty")].motionType, MotionType::Translational);
  EXPECT_EQ(model.bodies[model.FindBody("pelvis")].geometry.size(), 1u);
  EXPECT_EQ(model.bodies[model.FindBody("pelvis")].geometry[0].scale, Eigen::Vector3d(2, 2, 2));
  ASSERT_EQ(model.wrapObjects.size(), 1u);

  std::vector<double> q = DefaultCoordinates(model);
  auto set = [&](const char* name, double v) {
    q[model.FindCoordinate(name)] = v;
  };
  set("rx", 0.1);
  set("ry", -0.2);
  set("rz", 0.3);
  set("tx", 1);
  set("ty", 2);
  set("tz", 3);
  set("flex", 0.7);
  set("add", 0.4);
  set("knee_angle", -0.6);
  set("sled_rz", 0.5);
  set("sled_tx", 0.25);
  set("sled_ty", -1);
  ApplyCouplers(model, q);
  EXPECT_DOUBLE_EQ(q[model.FindCoordinate("beta")], 2 * 0.7 + 0.1);
  const std::vector<md::RigidTransform> poses = BodyPoses(model, q);

  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(), Z = Eigen::Vector3d::UnitZ();
  // FreeJoint: body-fixed X-Y-Z rotations, translation in the parent (ground) frame.
  const Eigen::Matrix3d Rp = Rot(X, 0.1) * Rot(Y, -0.2) * Rot(Z, 0.3);
  const Eigen::Vector3d tp(1, 2, 3);
  const md::RigidTransform& pelvis = poses[model.FindBody("pelvis")];
  EXPECT_LT((pelvis.rotation - Rp).norm(), 1e-14);
  EXPECT_LT((pelvis.translation - tp).norm(), 1e-14);
  // CustomJoint: R = Rz(flex) Rx(-add); translation along Y = 2 spline(flex), along X = 0.5 beta^2.
  const Function spline = Function::SimmSpline({ -2, 0, 1, 2 }, { 0, 0.01, 0.03, 0.02 });
  const double beta = 1.5;
  const Eigen::Matrix3d Rf = Rp * Rot(Z, 0.7) * Rot(X, -0.4);
  const Eigen::Vector3d tf = Rp * (Eigen::Vector3d(0.1, 0, 0) + 2 * spline(0.7) * Y + 0.5 * beta * beta * X) + tp;
  const md::RigidTransform& femur = poses[model.FindBody("femur")];
  EXPECT_LT((femur.rotation - Rf).norm(), 1e-14);
  EXPECT_LT((femur.translation - tf).norm(), 1e-14);
  // PinJoint about the offset frames' Z: femur * F * Rz(q) * inverse(B).
  const Eigen::Matrix3d RF = Rot(X, 0.3), RB = Rot(Y, 0.2);
  const Eigen::Matrix3d Rt = Rf * RF * Rot(Z, -0.6) * RB.transpose();
  const Eigen::Vector3d tt = Rf * Eigen::Vector3d(0, -0.4, 0) + tf - Rt * Eigen::Vector3d(0, 0.05, 0);
  const md::RigidTransform& tibia = poses[model.FindBody("tibia")];
  EXPECT_LT((tibia.rotation - Rt).norm(), 1e-14);
  EXPECT_LT((tibia.translation - tt).norm(), 1e-14);
  // PlanarJoint: rotation about Z, translations along X and Y; the welded body follows.
  const md::RigidTransform& sled = poses[model.FindBody("sled")];
  EXPECT_LT((sled.rotation - Rot(Z, 0.5)).norm(), 1e-14);
  EXPECT_LT((sled.translation - Eigen::Vector3d(0.25, -1, 0)).norm(), 1e-14);
  EXPECT_LT((poses[model.FindBody("glued")].translation - sled.translation).norm(), 1e-14);

  // The path: the conditional point is active for flex in [0, 1]; the moving point's x follows
  // the knee angle clamped to its range [-1, 0.5].
  const Path& path = model.paths[0];
  ASSERT_EQ(path.wraps.size(), 1u);
  EXPECT_EQ(path.wraps[0].name, "cyl");
  EXPECT_EQ(path.wraps[0].wrapObject, model.FindWrapObject("cyl"));
  // The path's own points (the points over the wrap cylinder aside, which lie on it).
  const auto pathPoints = [&](const PathGeometry& g, const md::RigidTransform& cylinderBody) {
    std::vector<int> kept;
    for (size_t i = 0; i < g.pointIndex.size(); ++i)
    {
      if (g.pointIndex[i] >= 0)
      {
        kept.push_back(static_cast<int>(i));
      }
      else
      {
        EXPECT_EQ(g.pointIndex[i], -1);
        const Eigen::Vector3d local = md::Inverse(cylinderBody).Apply(Eigen::Vector3d(g.points.row(Eigen::Index(i))));
        EXPECT_NEAR(local.head<2>().norm(), 0.1, 1e-12);
      }
    }
    return kept;
  };
  PathGeometry g = PathAt(model, path, q, poses);
  std::vector<int> kept = pathPoints(g, tibia);
  ASSERT_EQ(kept.size(), 3u);
  EXPECT_LT((g.points.row(kept[1]).transpose() - femur.Apply(Eigen::Vector3d(0.02, -0.1, 0))).norm(), 1e-14);
  EXPECT_LT((g.points.row(kept[2]).transpose() - tibia.Apply(Eigen::Vector3d(-0.06, -0.2, 0))).norm(), 1e-14);
  set("flex", 1.2);
  set("knee_angle", -3);
  ApplyCouplers(model, q);
  const std::vector<md::RigidTransform> poses2 = BodyPoses(model, q);
  g = PathAt(model, path, q, poses2);
  kept = pathPoints(g, poses2[model.FindBody("tibia")]);
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_EQ(g.pointIndex[kept[0]], 0);
  EXPECT_EQ(g.pointIndex[kept[1]], 2);
  EXPECT_LT(
    (g.points.row(kept[1]).transpose() - poses2[model.FindBody("tibia")].Apply(Eigen::Vector3d(-0.1, -0.2, 0))).norm(),
    1e-14);
}

TEST(OpenSimModel, AMusclesPropertiesAreReadAndAnActuatorHasNone)
{
  // The small model's muscle gives none; one that does, the older pennation_angle, and a path
  // actuator.
  std::string text = kSmallModel;
  const std::string end = "</GeometryPath></Thelen2003Muscle>";
  const size_t at = text.find(end);
  ASSERT_NE(at, std::string::npos);
  const std::string path =
    text.substr(text.rfind("<GeometryPath", at), at - text.rfind("<GeometryPath", at)) + "</GeometryPath>";
  text.replace(at, end.size(),
    "</GeometryPath><max_isometric_force>900</max_isometric_force><optimal_fiber_length>0.12</optimal_fiber_length>"
    "<tendon_slack_length>0.3</tendon_slack_length><pennation_angle_at_optimal>0.2</pennation_angle_at_optimal>"
    "</Thelen2003Muscle><Schutte1993Muscle_Deprecated name=\"old\">" +
      path +
      "<max_isometric_force>100</max_isometric_force><optimal_fiber_length>0.1</optimal_fiber_length>"
      "<tendon_slack_length>0.2</tendon_slack_length><pennation_angle>0.05</pennation_angle>"
      "</Schutte1993Muscle_Deprecated><PathActuator name=\"motor\">" +
      path + "<optimal_force>10</optimal_force></PathActuator>");
  const Model model = ParseModel(text, "small.osim");
  ASSERT_EQ(model.paths.size(), 3u);
  const md::MuscleProperties& m1 = model.paths[0].muscle;
  EXPECT_TRUE(m1.Known());
  EXPECT_EQ(m1.maxIsometricForce, 900);
  EXPECT_EQ(m1.optimalFiberLength, 0.12);
  EXPECT_EQ(m1.tendonSlackLength, 0.3);
  EXPECT_EQ(m1.pennationAngle, 0.2);
  EXPECT_EQ(model.paths[1].type, "Schutte1993Muscle_Deprecated");
  EXPECT_EQ(model.paths[1].muscle.pennationAngle, 0.05);
  EXPECT_TRUE(model.paths[1].muscle.Known());
  EXPECT_EQ(model.paths[2].type, "PathActuator");
  EXPECT_FALSE(model.paths[2].muscle.Known());
  EXPECT_TRUE(std::isnan(model.paths[2].muscle.maxIsometricForce));
  // A property that is not a number is refused, named.
  std::string bad = text;
  bad.replace(bad.find("<max_isometric_force>900"), 24, "<max_isometric_force>x");
  EXPECT_NE(
    ExpectInputError([&] { ParseModel(bad, "small.osim"); }).find("'x' is not a finite number"), std::string::npos);
}

TEST(OpenSimModel, WrapSurfacesAreClosedAndOutward)
{
  for (WrapShape shape : { WrapShape::Cylinder, WrapShape::Sphere, WrapShape::Ellipsoid, WrapShape::Torus })
  {
    WrapObject w;
    w.shape = shape;
    w.dimensions = shape == WrapShape::Cylinder ? std::vector<double>{ 0.1, 0.4 }
      : shape == WrapShape::Sphere              ? std::vector<double>{ 0.1 }
      : shape == WrapShape::Ellipsoid           ? std::vector<double>{ 0.1, 0.2, 0.3 }
                                                : std::vector<double>{ 0.2, 0.05 };
    const md::TriangleMesh mesh = WrapSurface(w, 64);
    double volume = 0;
    for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
    {
      const Eigen::Vector3d a = mesh.points.row(mesh.triangles(t, 0)), b = mesh.points.row(mesh.triangles(t, 1)),
                            c = mesh.points.row(mesh.triangles(t, 2));
      volume += a.dot(b.cross(c)) / 6;
    }
    const double expected = shape == WrapShape::Cylinder ? M_PI * 0.01 * 0.4
      : shape == WrapShape::Sphere                       ? 4.0 / 3 * M_PI * 1e-3
      : shape == WrapShape::Ellipsoid                    ? 4.0 / 3 * M_PI * 0.006
                                                         : 2 * M_PI * M_PI * 0.2 * 0.05 * 0.05;
    EXPECT_NEAR(volume / expected, 1.0, 0.02) << static_cast<int>(shape);
  }
}

TEST(OpenSimModel, BadInputIsNamed)
{
  std::string e =
    ExpectInputError([] { ParseModel("<OpenSimDocument Version=\"40000\"><Model><BodySet>", "bad.osim"); });
  EXPECT_NE(e.find("bad.osim"), std::string::npos) << e;
  EXPECT_NE(e.find("malformed XML"), std::string::npos) << e;

  std::string text = kSmallModel;
  text.replace(text.find("<PinJoint name=\"knee\">"), 22, "<HingeJoint name=\"knee\">");
  text.replace(text.find("</PinJoint>"), 11, "</HingeJoint>");
  e = ExpectInputError([&] { ParseModel(text, "small.osim"); });
  EXPECT_NE(e.find("unknown joint type 'HingeJoint'"), std::string::npos) << e;
  EXPECT_NE(e.find("line "), std::string::npos) << e;
  EXPECT_NE(e.find("'knee'"), std::string::npos) << e;

  text = kSmallModel;
  text.replace(text.find("<PolynomialFunction name=\"function\">"), 35, "<GCVSpline name=\"function\">");
  text.replace(text.find("</PolynomialFunction>"), 21, "</GCVSpline>");
  e = ExpectInputError([&] { ParseModel(text, "small.osim"); });
  EXPECT_NE(e.find("unknown function type 'GCVSpline'"), std::string::npos) << e;
  EXPECT_NE(e.find("TransformAxis 'translation2'"), std::string::npos) << e;

  text = kSmallModel;
  text.replace(text.find("<socket_parent_frame>/bodyset/femur</socket_parent_frame><location>0.02"), 52,
    "<socket_parent_frame>/bodyset/femr</socket_parent_frame>");
  e = ExpectInputError([&] { ParseModel(text, "small.osim"); });
  EXPECT_NE(e.find("no body or frame named '/bodyset/femr'"), std::string::npos) << e;
  EXPECT_NE(e.find("ConditionalPathPoint 'c'"), std::string::npos) << e;

  e = ExpectInputError([] { ReadModel("/nonexistent/model.osim"); });
  EXPECT_NE(e.find("cannot be opened"), std::string::npos) << e;
}

TEST(OpenSimModel, DeepNestingAndHugeNumbersAreRefusedNotOverflowed)
{
  // 20,000 elements nested in a body, 10,000 nested multiplier functions: the walks of the model
  // would overflow the stack; refused before any of them.
  std::string deep = kSmallModel;
  const std::string body = "<Body name=\"femur\"/>";
  ASSERT_NE(deep.find(body), std::string::npos);
  std::string nested;
  for (int i = 0; i < 20000; ++i)
  {
    nested += "<a>";
  }
  for (int i = 0; i < 20000; ++i)
  {
    nested += "</a>";
  }
  deep.replace(deep.find(body), body.size(), "<Body name=\"femur\">" + nested + "</Body>");
  std::string e = ExpectInputError([&] { ParseModel(deep, "deep.osim"); });
  EXPECT_NE(e.find("deep.osim"), std::string::npos) << e;
  EXPECT_NE(e.find("nested more than 256 deep"), std::string::npos) << e;
  // 250 deep is a model still (OpenSim's own nest about 12 deep).
  std::string shallow = kSmallModel;
  shallow.replace(shallow.find(body), body.size(),
    "<Body name=\"femur\">" + nested.substr(0, 3 * 240) + nested.substr(nested.size() - 4 * 240) + "</Body>");
  EXPECT_NO_THROW(ParseModel(shallow, "shallow.osim"));
  // A number beyond +-1e12 in the geometry: named where it is.
  std::string huge = kSmallModel;
  const std::string offset = "<translation>0.1 0 0</translation>";
  ASSERT_NE(huge.find(offset), std::string::npos);
  huge.replace(huge.find(offset), offset.size(), "<translation>1e300 0 0</translation>");
  e = ExpectInputError([&] { ParseModel(huge, "huge.osim"); });
  EXPECT_NE(e.find("'1e300' is beyond the +-1e12"), std::string::npos) << e;
  EXPECT_NE(e.find("PhysicalOffsetFrame 'pelvis_offset'"), std::string::npos) << e;
}
