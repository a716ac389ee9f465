// SPDX-License-Identifier: BSD-3-Clause
// OpenSim model reading and forward kinematics: functions, joints, paths, motions, bad input,
// and OpenSim's own computed muscle lengths as the external oracle (skipped without the data).
#include "OpenSimKinematics.h"
#include "OpenSimMotion.h"
#include "RealData.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>

using namespace md::osim;

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

std::string WriteTemporary(const std::string& name, const std::string& text)
{
  const std::string path = testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

std::string ExpectInputError(const std::function<void()>& action)
{
  try
  {
    action();
  }
  catch (const md::InputError& e)
  {
    return e.what();
  }
  ADD_FAILURE() << "no InputError";
  return "";
}

Eigen::Matrix3d Rot(const Eigen::Vector3d& axis, double angle)
{
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

/// A 4.x model: ground -> (FreeJoint) pelvis -> (CustomJoint, rotations Z then X, translation
/// along Y by a SimmSpline) femur -> (PinJoint with offset frames) tibia, a PlanarJoint and a
/// WeldJoint, a coupler, one muscle with a conditional and a moving point.
const char* kSmallModel = R"(<?xml version="1.0"?>
<OpenSimDocument Version="40000">
 <Model name="small">
  <Ground name="ground"/>
  <BodySet><objects>
   <Body name="pelvis"><attached_geometry><Mesh name="m"><mesh_file>pelvis.vtp</mesh_file><scale_factors>2 2 2</scale_factors></Mesh></attached_geometry></Body>
   <Body name="femur"/>
   <Body name="tibia">
    <WrapObjectSet><objects><WrapCylinder name="cyl"><xyz_body_rotation>0 0 0</xyz_body_rotation><translation>0 0 0</translation><radius>0.1</radius><length>0.5</length></WrapCylinder></objects></WrapObjectSet>
   </Body>
   <Body name="sled"/>
   <Body name="glued"/>
  </objects></BodySet>
  <JointSet><objects>
   <FreeJoint name="ground_pelvis">
    <socket_parent_frame>/ground</socket_parent_frame><socket_child_frame>/bodyset/pelvis</socket_child_frame>
    <coordinates><Coordinate name="rx"/><Coordinate name="ry"/><Coordinate name="rz"/><Coordinate name="tx"/><Coordinate name="ty"/><Coordinate name="tz"/></coordinates>
   </FreeJoint>
   <CustomJoint name="hip">
    <socket_parent_frame>pelvis_offset</socket_parent_frame><socket_child_frame>/bodyset/femur</socket_child_frame>
    <coordinates><Coordinate name="flex"><range>-2 2</range></Coordinate><Coordinate name="add"/><Coordinate name="beta"/></coordinates>
    <frames><PhysicalOffsetFrame name="pelvis_offset"><socket_parent>/bodyset/pelvis</socket_parent><translation>0.1 0 0</translation><orientation>0 0 0</orientation></PhysicalOffsetFrame></frames>
    <SpatialTransform>
     <TransformAxis name="rotation1"><coordinates>flex</coordinates><axis>0 0 1</axis><LinearFunction name="function"><coefficients>1 0</coefficients></LinearFunction></TransformAxis>
     <TransformAxis name="rotation2"><coordinates>add</coordinates><axis>1 0 0</axis><LinearFunction name="function"><coefficients>-1 0</coefficients></LinearFunction></TransformAxis>
     <TransformAxis name="rotation3"><coordinates></coordinates><axis>0 1 0</axis><Constant name="function"><value>0</value></Constant></TransformAxis>
     <TransformAxis name="translation1"><coordinates>flex</coordinates><axis>0 1 0</axis>
      <MultiplierFunction name="function"><SimmSpline name="function"><x>-2 0 1 2</x><y>0 0.01 0.03 0.02</y></SimmSpline><scale>2</scale></MultiplierFunction></TransformAxis>
     <TransformAxis name="translation2"><coordinates>beta</coordinates><axis>1 0 0</axis><PolynomialFunction name="function"><coefficients>0.5 0 0</coefficients></PolynomialFunction></TransformAxis>
     <TransformAxis name="translation3"><axis>0 0 1</axis></TransformAxis>
    </SpatialTransform>
   </CustomJoint>
   <PinJoint name="knee">
    <socket_parent_frame>femur_offset</socket_parent_frame><socket_child_frame>tibia_offset</socket_child_frame>
    <coordinates><Coordinate name="knee_angle"><range>-1 0.5</range></Coordinate></coordinates>
    <frames>
     <PhysicalOffsetFrame name="femur_offset"><socket_parent>/bodyset/femur</socket_parent><translation>0 -0.4 0</translation><orientation>0.3 0 0</orientation></PhysicalOffsetFrame>
     <PhysicalOffsetFrame name="tibia_offset"><socket_parent>/bodyset/tibia</socket_parent><translation>0 0.05 0</translation><orientation>0 0.2 0</orientation></PhysicalOffsetFrame>
    </frames>
   </PinJoint>
   <PlanarJoint name="slide">
    <socket_parent_frame>/ground</socket_parent_frame><socket_child_frame>/bodyset/sled</socket_child_frame>
    <coordinates><Coordinate name="sled_rz"/><Coordinate name="sled_tx"/><Coordinate name="sled_ty"/></coordinates>
   </PlanarJoint>
   <WeldJoint name="glue">
    <socket_parent_frame>/bodyset/sled</socket_parent_frame><socket_child_frame>/bodyset/glued</socket_child_frame>
   </WeldJoint>
  </objects></JointSet>
  <ConstraintSet><objects>
   <CoordinateCouplerConstraint name="c"><coupled_coordinates_function><LinearFunction><coefficients>2 0.1</coefficients></LinearFunction></coupled_coordinates_function>
    <independent_coordinate_names>flex</independent_coordinate_names><dependent_coordinate_name>beta</dependent_coordinate_name><scale_factor>1</scale_factor></CoordinateCouplerConstraint>
  </objects></ConstraintSet>
  <ForceSet><objects>
   <Thelen2003Muscle name="m1"><GeometryPath name="path"><PathPointSet><objects>
    <PathPoint name="o"><socket_parent_frame>/bodyset/pelvis</socket_parent_frame><location>0 0.1 0</location></PathPoint>
    <ConditionalPathPoint name="c"><socket_parent_frame>/bodyset/femur</socket_parent_frame><location>0.02 -0.1 0</location><socket_coordinate>/jointset/hip/flex</socket_coordinate><range>0 1</range></ConditionalPathPoint>
    <MovingPathPoint name="mv"><socket_parent_frame>/bodyset/tibia</socket_parent_frame><location>0 0 0</location>
     <x_location><LinearFunction name="function"><coefficients>0.1 0</coefficients></LinearFunction></x_location><socket_x_coordinate>../../../../../jointset/knee/knee_angle</socket_x_coordinate>
     <y_location><Constant name="function"><value>-0.2</value></Constant></y_location>
     <z_location><Constant name="function"><value>0</value></Constant></z_location></MovingPathPoint>
   </objects></PathPointSet>
   <PathWrapSet><objects><PathWrap name="w"><wrap_object>cyl</wrap_object></PathWrap></objects></PathWrapSet>
   </GeometryPath></Thelen2003Muscle>
  </objects></ForceSet>
 </Model>
</OpenSimDocument>)";
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
  EXPECT_EQ(path.wrapObjects, std::vector<std::string>{ "cyl" });
  PathGeometry g = PathAt(model, path, q, poses);
  ASSERT_EQ(g.points.rows(), 3);
  EXPECT_LT((g.points.row(1).transpose() - femur.Apply(Eigen::Vector3d(0.02, -0.1, 0))).norm(), 1e-14);
  EXPECT_LT((g.points.row(2).transpose() - tibia.Apply(Eigen::Vector3d(-0.06, -0.2, 0))).norm(), 1e-14);
  set("flex", 1.2);
  set("knee_angle", -3);
  ApplyCouplers(model, q);
  const std::vector<md::RigidTransform> poses2 = BodyPoses(model, q);
  g = PathAt(model, path, q, poses2);
  ASSERT_EQ(g.points.rows(), 2);
  EXPECT_EQ(g.pointIndex, (std::vector<int>{ 0, 2 }));
  EXPECT_LT(
    (g.points.row(1).transpose() - poses2[model.FindBody("tibia")].Apply(Eigen::Vector3d(-0.1, -0.2, 0))).norm(),
    1e-14);
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

TEST(OpenSimMotion, ReadsAndMapsColumns)
{
  const Model model = ParseModel(kSmallModel, "small.osim");
  const std::string path = WriteTemporary("m.mot",
    "walk\nversion=1\nnRows=2\nnColumns=4\ninDegrees=yes\nendheader\n"
    "time\t/jointset/hip/flex/value\t/jointset/hip/flex/speed\ttx\n0\t10\t1\t0.5\n0.1\t20\t1\t0.25\n");
  const MotionTable table = ReadMotion(path);
  EXPECT_TRUE(table.inDegrees);
  ASSERT_EQ(table.times.size(), 2u);
  const CoordinateTrajectory t = MapMotion(model, table);
  EXPECT_NEAR(t.frames[1][model.FindCoordinate("flex")], 20 * M_PI / 180, 1e-15);
  EXPECT_DOUBLE_EQ(t.frames[1][model.FindCoordinate("tx")], 0.25); // translational: not converted
  EXPECT_NEAR(t.frames[1][model.FindCoordinate("beta")], 2 * 20 * M_PI / 180 + 0.1, 1e-15);
  ASSERT_EQ(t.warnings.size(), 1u); // the coordinates the motion lacks
  EXPECT_NE(t.warnings[0].find("knee_angle"), std::string::npos);

  // A SIMM motion file (no version line) is in degrees; a .sto without inDegrees is in radians.
  EXPECT_TRUE(ReadMotion(WriteTemporary("s.mot", "x\nendheader\ntime flex\n0 1\n")).inDegrees);
  EXPECT_FALSE(ReadMotion(WriteTemporary("s.sto", "x\nversion=1\nendheader\ntime flex\n0 1\n")).inDegrees);

  std::vector<double> q = DefaultCoordinates(model);
  SetCoordinates(model, "flex=90, tx=2;knee_angle=-45", true, q);
  EXPECT_NEAR(q[model.FindCoordinate("flex")], M_PI / 2, 1e-15);
  EXPECT_DOUBLE_EQ(q[model.FindCoordinate("tx")], 2);
  EXPECT_NE(ExpectInputError([&] { SetCoordinates(model, "elbow=3", true, q); }).find("'elbow' is not a coordinate"),
    std::string::npos);
}

TEST(OpenSimMotion, BadMotionsAreNamed)
{
  const Model model = ParseModel(kSmallModel, "small.osim");
  std::string e = ExpectInputError([] { ReadMotion(WriteTemporary("nt.mot", "endheader\nflex tx\n1 2\n")); });
  EXPECT_NE(e.find("not 'time'"), std::string::npos) << e;
  EXPECT_NE(e.find("nt.mot"), std::string::npos) << e;
  e = ExpectInputError([] { ReadMotion(WriteTemporary("nan.mot", "endheader\ntime flex\n0 1\n0.1 nan\n")); });
  EXPECT_NE(e.find("line 4"), std::string::npos) << e;
  EXPECT_NE(e.find("column 'flex'"), std::string::npos) << e;
  e = ExpectInputError([] { ReadMotion(WriteTemporary("nh.mot", "time flex\n0 1\n")); });
  EXPECT_NE(e.find("endheader"), std::string::npos) << e;
  e = ExpectInputError([] { ReadMotion(WriteTemporary("back.mot", "endheader\ntime flex\n0 1\n0 2\n")); });
  EXPECT_NE(e.find("does not come after"), std::string::npos) << e;
  const MotionTable extra = ReadMotion(WriteTemporary("x.mot", "endheader\ntime flex elbow\n0 1 2\n"));
  e = ExpectInputError([&] { MapMotion(model, extra); });
  EXPECT_NE(e.find("column 'elbow' names no coordinate"), std::string::npos) << e;
  MotionOptions options;
  options.ignoreUnknownColumns = true;
  const CoordinateTrajectory t = MapMotion(model, extra, options);
  EXPECT_NE(t.warnings[0].find("elbow"), std::string::npos);
}

namespace
{
/// Every muscle's polyline length at every frame of a motion, against OpenSim's lengths.
struct LengthComparison
{
  std::map<std::string, std::vector<double>> difference; ///< ours - OpenSim's, per frame
};

LengthComparison CompareLengths(const std::string& folder, const std::string& modelFile, const std::string& motionFile,
  const std::string& lengthsFile)
{
  const Model model = ReadModel(folder + "/" + modelFile);
  MotionOptions options;
  options.ignoreUnknownColumns = true;
  const CoordinateTrajectory trajectory = MapMotion(model, ReadMotion(folder + "/" + motionFile), options);
  const MotionTable lengths = ReadMotion(folder + "/" + lengthsFile);
  EXPECT_EQ(lengths.times.size(), trajectory.times.size());
  LengthComparison result;
  for (size_t column = 0; column < lengths.labels.size(); ++column)
  {
    // "/forceset/<muscle>|length"
    std::string name = lengths.labels[column];
    name = name.substr(name.rfind('/') + 1);
    name = name.substr(0, name.find('|'));
    const int p = model.FindPath(name);
    EXPECT_GE(p, 0) << name;
    if (p < 0)
    {
      continue;
    }
    for (size_t k = 0; k < trajectory.frames.size(); ++k)
    {
      const std::vector<md::RigidTransform> poses = BodyPoses(model, trajectory.frames[k]);
      const double ours = PolylineLength(PathAt(model, model.paths[p], trajectory.frames[k], poses).points);
      result.difference[name].push_back(ours - lengths.rows[k][column]);
    }
  }
  return result;
}
}

TEST(OpenSimOracle, Gait10dof18muscLengthsEqualOpenSims)
{
  const std::string folder = RealDataFile("opensim/gait10dof18musc_walk/walk_gait1018_subject01.osim");
  if (folder.empty())
  {
    GTEST_SKIP() << "OpenSim data not found: set MUSCLEDEFORMATION_DATA_DIR to the folder holding opensim/";
  }
  const LengthComparison c = CompareLengths(folder.substr(0, folder.rfind('/')), "walk_gait1018_subject01.osim",
    "walk_gait1018_state_reference.mot", "std_testGeometryPathWrapping_walk_gait1018_muscle_lengths.sto");
  ASSERT_EQ(c.difference.size(), 18u);
  double worst = 0;
  for (const auto& [name, differences] : c.difference)
  {
    ASSERT_EQ(differences.size(), 151u);
    for (size_t k = 0; k < differences.size(); ++k)
    {
      EXPECT_LE(std::abs(differences[k]), 1e-6) << name << " frame " << k;
      worst = std::max(worst, std::abs(differences[k]));
    }
  }
  std::printf("gait10dof18musc: largest |length - OpenSim's| over 18 muscles x 151 frames: %.3g m\n", worst);
}

TEST(OpenSimOracle, Rajagopal2016LengthsEqualOpenSimsWhereNotWrapping)
{
  const std::string file = RealDataFile("opensim/rajagopal2016_walk_armless_18musc/subject_walk_armless_18musc.osim");
  if (file.empty())
  {
    GTEST_SKIP() << "OpenSim data not found: set MUSCLEDEFORMATION_DATA_DIR to the folder holding opensim/";
  }
  const LengthComparison c = CompareLengths(file.substr(0, file.rfind('/')), "subject_walk_armless_18musc.osim",
    "subject_walk_armless_coordinates.mot", "std_testGeometryPathWrapping_subject_walk_armless_muscle_lengths.sto");
  ASSERT_EQ(c.difference.size(), 18u);
  double worst = 0;
  for (const auto& [name, differences] : c.difference)
  {
    ASSERT_EQ(differences.size(), 238u);
    const std::string muscle = name.substr(0, name.size() - 2);
    size_t equal = 0;
    for (size_t k = 0; k < differences.size(); ++k)
    {
      // Wrapping only lengthens a path: the polyline is never longer than OpenSim's path.
      EXPECT_LE(differences[k], 1e-6) << name << " frame " << k;
      equal += std::abs(differences[k]) <= 1e-6;
    }
    if (muscle == "soleus" || muscle == "tib_ant" || muscle == "bifemsh" || muscle == "rect_fem" || muscle == "vas_int")
    {
      // No wrap object, or one this motion never touches: equal on every frame.
      EXPECT_EQ(equal, differences.size()) << name;
      for (double d : differences)
      {
        worst = std::max(worst, std::abs(d));
      }
    }
    else if (muscle != "med_gas")
    {
      // glut_max2, psoas, semimem wrap on part of the motion and equal OpenSim's elsewhere.
      EXPECT_GE(equal, differences.size() / 5) << name;
    }
  }
  std::printf("rajagopal2016: largest |length - OpenSim's| where no path wraps: %.3g m\n", worst);
}

TEST(OpenSimOracle, Gait2392LoadsAndPlays)
{
  const std::string file = RealDataFile("opensim/gait2392_walk_forward/subject01_simbody_adjusted.osim");
  if (file.empty())
  {
    GTEST_SKIP() << "OpenSim data not found: set MUSCLEDEFORMATION_DATA_DIR to the folder holding opensim/";
  }
  const Model model = ReadModel(file);
  EXPECT_EQ(model.version, 40000);
  EXPECT_EQ(model.paths.size(), 92u);
  EXPECT_EQ(model.joints.size(), 12u);
  EXPECT_EQ(model.coordinates.size(), 23u);
  const CoordinateTrajectory trajectory =
    MapMotion(model, ReadMotion(file.substr(0, file.rfind('/')) + "/subject01_walk1_Kinematics_q.mot"));
  ASSERT_EQ(trajectory.frames.size(), 175u);
  const int femur = model.FindBody("femur_r"), tibia = model.FindBody("tibia_r");
  for (const std::vector<double>& q : trajectory.frames)
  {
    const std::vector<md::RigidTransform> poses = BodyPoses(model, q);
    // The knee stays a knee: the tibia's origin within 0.5 m of the femur's.
    EXPECT_LT((poses[tibia].translation - poses[femur].translation).norm(), 0.5);
    for (const Path& path : model.paths)
    {
      const PathGeometry g = PathAt(model, path, q, poses);
      ASSERT_GE(g.points.rows(), 2) << path.name;
      ASSERT_TRUE(g.points.allFinite()) << path.name;
      const double length = PolylineLength(g.points);
      ASSERT_GT(length, 0.02) << path.name;
      ASSERT_LT(length, 1.0) << path.name;
    }
  }
}

TEST(OpenSimOracle, LhdlFemurFollowsTheTransformsTable)
{
  const std::string file = RealDataFile("lhdl_hip_r/LHDL_hip_r.osim");
  if (file.empty())
  {
    GTEST_SKIP() << "real data not found: set MUSCLEDEFORMATION_DATA_DIR to the folder holding lhdl_hip_r";
  }
  const std::string folder = file.substr(0, file.rfind('/'));
  const Model model = ReadModel(file);
  const md::TriangleMesh femur = ReadSurface(folder + "/femur_r.vtk");
  std::vector<double> rest = DefaultCoordinates(model);
  SetCoordinates(model, "hip_flexion_r=1.5760 hip_adduction_r=-4.7269 hip_rotation_r=-5.2899", true, rest);
  const md::RigidTransform restFemur = BodyPoses(model, rest)[model.FindBody("femur_r")];
  const md::RigidTransform restPelvis = BodyPoses(model, rest)[model.FindBody("pelvis")];
  // The CSV: motion,frame,time,flexion,adduction,rotation,r00..r22,tx,ty,tz (mm).
  std::ifstream csv(folder + "/femur_transforms.csv");
  std::string line;
  std::getline(csv, line);
  std::map<std::string, CoordinateTrajectory> motions;
  MotionOptions options;
  options.ignoreUnknownColumns = true;
  for (const char* name : { "hip_flexion", "hip_adduction" })
  {
    motions[name] = MapMotion(model, ReadMotion(folder + "/kinematics/" + name + ".mot"), options);
  }
  size_t frames = 0;
  double worst = 0;
  md::RigidTransform scanInverse;
  while (std::getline(csv, line))
  {
    std::vector<std::string> fields;
    std::stringstream stream(line);
    std::string field;
    while (std::getline(stream, field, ','))
    {
      fields.push_back(field);
    }
    md::RigidTransform expected;
    for (int i = 0; i < 9; ++i)
    {
      expected.rotation(i / 3, i % 3) = std::stod(fields[6 + i]);
    }
    expected.translation << std::stod(fields[15]), std::stod(fields[16]), std::stod(fields[17]);
    if (fields[0] == "scan_pose_RP")
    {
      // The table's own placement at the scan pose's coordinates as printed (4 decimals): not
      // quite the identity (t_z = -0.001 mm). Frames are compared relative to it.
      scanInverse.rotation = expected.rotation.transpose();
      scanInverse.translation = -scanInverse.rotation * expected.translation;
      continue;
    }
    if (!motions.count(fields[0]))
    {
      continue;
    }
    expected.translation += expected.rotation * scanInverse.translation;
    expected.rotation = expected.rotation * scanInverse.rotation;
    const size_t frame = std::stoul(fields[1]);
    const CoordinateTrajectory& t = motions[fields[0]];
    ASSERT_LT(frame, t.frames.size());
    const md::RigidTransform now = BodyPoses(model, t.frames[frame])[model.FindBody("femur_r")];
    // The scans are in the pelvis's frame (the model places the pelvis in ground by its joint's
    // child offset). Rest to current in that frame, in mm: x -> pelvis^-1(now(rest^-1(pelvis(x)))).
    const Eigen::Matrix3d Rg = now.rotation * restFemur.rotation.transpose();
    const Eigen::Vector3d tg = now.translation - Rg * restFemur.translation;
    const Eigen::Matrix3d R = restPelvis.rotation.transpose() * Rg * restPelvis.rotation;
    const Eigen::Vector3d tmm =
      1000.0 * restPelvis.rotation.transpose() * (Rg * restPelvis.translation + tg - restPelvis.translation);
    for (Eigen::Index i = 0; i < femur.points.rows(); ++i)
    {
      const Eigen::Vector3d x = femur.points.row(i).transpose();
      worst = std::max(worst, (R * x + tmm - expected.Apply(x)).norm());
    }
    ++frames;
  }
  EXPECT_EQ(frames, motions["hip_flexion"].frames.size() + motions["hip_adduction"].frames.size());
  EXPECT_LE(worst, 1e-3);
  std::printf("LHDL femur over %zu frames: largest distance to the CSV's placement %.3g mm\n", frames, worst);
}
