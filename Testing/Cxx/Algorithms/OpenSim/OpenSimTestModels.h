// SPDX-License-Identifier: BSD-3-Clause
// What the OpenSim tests share: a small model that uses every kind of joint and path point, a
// file written for a test, and the InputError an action throws.
#pragma once

#include "Common/MeshTypes.h"

#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <string>

namespace md::osim::test
{
inline std::string WriteTemporary(const std::string& name, const std::string& text)
{
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

inline std::string ExpectInputError(const std::function<void()>& action)
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

/// A 4.x model: ground -> (FreeJoint) pelvis -> (CustomJoint, rotations Z then X, translation
/// along Y by a SimmSpline) femur -> (PinJoint with offset frames) tibia, a PlanarJoint and a
/// WeldJoint, a coupler, one muscle with a conditional and a moving point.
inline const char* const kSmallModel = R"(<?xml version="1.0"?>
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
