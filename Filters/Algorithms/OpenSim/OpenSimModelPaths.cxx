// SPDX-License-Identifier: BSD-3-Clause
#include "OpenSim/OpenSimModelBuilder.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <sstream>

namespace md::osim::xml
{
void ModelBuilder::ReadQuadrant(Node wrap, WrapObject& w)
{
  Node quadrant = wrap.child("quadrant");
  std::string name = quadrant ? FirstWord(quadrant.text().get()) : "";
  if (name.empty() || name == "all" || name == "ALL" || name == "All" || name == "Unassigned")
  {
    w.quadrantSign = 0;
    return;
  }
  w.quadrantSign = name[0] == '-' ? -1 : 1;
  if (name[0] == '-' || name[0] == '+')
  {
    name.erase(0, 1);
  }
  const std::string axes = "xyzXYZ";
  const size_t axis = name.size() == 1 ? axes.find(name[0]) : std::string::npos;
  if (axis == std::string::npos)
  {
    this->reader.Fail(quadrant,
      "quadrant '" + std::string(FirstWord(quadrant.text().get())) +
        "' is not one of x, +x, -x, y, +y, -y, z, +z, -z or all");
  }
  w.quadrantAxis = static_cast<int>(axis % 3);
}

void ModelBuilder::ReadWrapObjects(Node modelNode)
{
  // The wrap objects of a body, of ground or of an offset frame (`offset` from its body).
  auto readSet = [&](Node owner, int body, const RigidTransform& offset) {
    for (Node wrap : owner.child("WrapObjectSet").child("objects").children())
    {
      if (wrap.type() != pugi::node_element)
      {
        continue;
      }
      const std::string type = wrap.name();
      WrapObject w;
      w.name = wrap.attribute("name").value();
      w.body = body;
      w.placement = Compose(offset,
        Offset(this->reader.Vector(wrap, "translation", Eigen::Vector3d::Zero()),
          this->reader.Vector(wrap, "xyz_body_rotation", Eigen::Vector3d::Zero())));
      if (type == "WrapCylinder")
      {
        w.shape = WrapShape::Cylinder;
        w.dimensions = { this->reader.Number(wrap, "radius", 0.05), this->reader.Number(wrap, "length", 0.1) };
      }
      else if (type == "WrapSphere")
      {
        w.shape = WrapShape::Sphere;
        w.dimensions = { this->reader.Number(wrap, "radius", 0.05) };
      }
      else if (type == "WrapEllipsoid")
      {
        w.shape = WrapShape::Ellipsoid;
        const Eigen::Vector3d r = this->reader.Vector(wrap, "dimensions", Eigen::Vector3d::Constant(0.05));
        w.dimensions = { r[0], r[1], r[2] };
      }
      else if (type == "WrapTorus")
      {
        w.shape = WrapShape::Torus;
        w.dimensions = { this->reader.Number(wrap, "outer_radius", 0.05),
          this->reader.Number(wrap, "inner_radius", 0.01) };
      }
      else
      {
        this->model.warnings.push_back(this->reader.Warn(wrap, "wrap object type not shown"));
        continue;
      }
      for (double d : w.dimensions)
      {
        if (!(d > 0))
        {
          this->reader.Fail(wrap, "wrap object dimensions must be positive");
        }
      }
      w.active = FirstWord(wrap.child("active").text().get()) != "false";
      this->ReadQuadrant(wrap, w);
      this->model.wrapObjects.push_back(w);
    }
  };
  readSet(modelNode.child("Ground"), 0, RigidTransform());
  for (Node body : modelNode.child("BodySet").child("objects").children("Body"))
  {
    readSet(body, std::max(0, this->model.FindBody(body.attribute("name").value())), RigidTransform());
  }
  // 4.x: offset frames may hold wrap objects too (each frame once: the map has it by name
  // and by path).
  std::set<const void*> seen;
  for (const auto& [name, frame] : this->frameNodes)
  {
    if (frame.child("WrapObjectSet") && seen.insert(frame.internal_object()).second)
    {
      const FrameOnBody placed = this->ResolveFrame(frame, name, Node());
      readSet(frame, placed.body, placed.offset);
    }
  }
}

int ModelBuilder::CoordinateOf(Node where, const std::string& reference)
{
  const std::string name = LastPathPart(reference);
  const int index = this->model.FindCoordinate(name);
  if (index < 0)
  {
    this->reader.Fail(where, "coordinate '" + reference + "' is not in the model");
  }
  return index;
}

void ModelBuilder::ReadCoupler(Node constraint)
{
  if (std::string(constraint.child("isDisabled").text().get()) == "true" ||
    std::string(constraint.child("isEnforced").text().get()) == "false")
  {
    return;
  }
  CoordinateCoupler c;
  c.name = constraint.attribute("name").value();
  const std::vector<std::string> independent = Words(constraint.child("independent_coordinate_names").text().get());
  if (independent.size() != 1)
  {
    this->reader.Fail(constraint,
      "a coupler with " + std::to_string(independent.size()) + " independent coordinates (one is supported)");
  }
  c.independent = this->CoordinateOf(constraint, independent[0]);
  c.dependent = this->CoordinateOf(constraint, constraint.child("dependent_coordinate_name").text().get());
  Node function = this->reader.FunctionChild(constraint, "coupled_coordinates_function");
  if (!function)
  {
    this->reader.Fail(constraint, "a coupler without a coupled_coordinates_function");
  }
  c.function = this->reader.ReadFunction(function);
  c.scale = this->reader.Number(constraint, "scale_factor", 1.0);
  this->model.couplers.push_back(c);
}

FrameOnBody ModelBuilder::PointFrame(Node point)
{
  if (point.child("socket_parent_frame"))
  {
    return this->ResolveFrame(point, point.child("socket_parent_frame").text().get(), Node());
  }
  const std::string body = FirstWord(point.child("body").text().get());
  if (body.empty())
  {
    this->reader.Fail(point, "the path point names no body");
  }
  const int index = this->model.FindBody(body);
  if (index < 0)
  {
    this->reader.Fail(point, "body '" + body + "' is not in the model");
  }
  return { index, RigidTransform() };
}

void ModelBuilder::ReadPath(Node force, Node geometryPath)
{
  Path path;
  path.name = force.attribute("name").value();
  path.type = force.name();
  const double unknown = MuscleProperties::kUnknown;
  path.muscle.maxIsometricForce = this->reader.Number(force, "max_isometric_force", unknown);
  path.muscle.optimalFiberLength = this->reader.Number(force, "optimal_fiber_length", unknown);
  path.muscle.tendonSlackLength = this->reader.Number(force, "tendon_slack_length", unknown);
  path.muscle.pennationAngle =
    this->reader.Number(force, "pennation_angle_at_optimal", this->reader.Number(force, "pennation_angle", unknown));
  for (Node pointNode : geometryPath.child("PathPointSet").child("objects").children())
  {
    if (pointNode.type() != pugi::node_element)
    {
      continue;
    }
    const std::string type = pointNode.name();
    if (!kPointTypes.count(type))
    {
      this->reader.Fail(pointNode, "unknown path point type '" + type + "'");
    }
    PathPoint p;
    p.name = pointNode.attribute("name").value();
    const FrameOnBody frame = this->PointFrame(pointNode);
    p.body = frame.body;
    p.frame = frame.offset;
    p.location = this->reader.Vector(pointNode, "location", Eigen::Vector3d::Zero());
    if (type == "ConditionalPathPoint")
    {
      p.kind = PathPointKind::Conditional;
      const std::vector<double> range = this->reader.Numbers(pointNode, "range", 2);
      p.rangeMin = range[0];
      p.rangeMax = range[1];
      const std::string coordinate = pointNode.child("socket_coordinate")
        ? pointNode.child("socket_coordinate").text().get()
        : pointNode.child("coordinate").text().get();
      p.coordinate = this->CoordinateOf(pointNode, FirstWord(coordinate.c_str()));
    }
    else if (type == "MovingPathPoint")
    {
      p.kind = PathPointKind::Moving;
      static const char* axis[3] = { "x", "y", "z" };
      for (int i = 0; i < 3; ++i)
      {
        const std::string locationName = std::string(axis[i]) + "_location";
        Node function = this->reader.FunctionChild(pointNode, locationName.c_str());
        p.locationFunction[i] = function ? this->reader.ReadFunction(function) : Function::Constant(p.location[i]);
        const std::string coordinateName = std::string(axis[i]) + "_coordinate";
        Node coordinate = pointNode.child(("socket_" + coordinateName).c_str());
        if (!coordinate)
        {
          coordinate = pointNode.child(coordinateName.c_str());
        }
        const std::string name = FirstWord(coordinate.text().get());
        if (!name.empty())
        {
          p.locationCoordinate[i] = this->CoordinateOf(pointNode, name);
        }
      }
    }
    path.points.push_back(p);
  }
  if (path.points.size() < 2)
  {
    this->reader.Fail(geometryPath, "a path needs at least 2 points");
  }
  for (Node wrap : geometryPath.child("PathWrapSet").child("objects").children("PathWrap"))
  {
    PathWrap w;
    w.name = FirstWord(wrap.child("wrap_object").text().get());
    if (w.name.empty())
    {
      continue;
    }
    w.wrapObject = this->model.FindWrapObject(w.name);
    if (w.wrapObject < 0)
    {
      this->reader.Fail(wrap, "wrap object '" + w.name + "' is not in the model (or is of a type not read)");
    }
    if (wrap.child("range"))
    {
      const std::vector<double> range = this->reader.Numbers(wrap, "range", 2);
      w.rangeStart = static_cast<int>(range[0]);
      w.rangeEnd = static_cast<int>(range[1]);
    }
    if (Node method = wrap.child("method"))
    {
      // As OpenSim: the three names in lower case, capitalised or upper case; "Unassigned" is
      // the default.
      using Method = EllipsoidWrapMethod;
      static const std::map<std::string, Method> kMethods = { { "hybrid", Method::Hybrid },
        { "Hybrid", Method::Hybrid }, { "HYBRID", Method::Hybrid }, { "Unassigned", Method::Hybrid },
        { "midpoint", Method::Midpoint }, { "Midpoint", Method::Midpoint }, { "MIDPOINT", Method::Midpoint },
        { "axial", Method::Axial }, { "Axial", Method::Axial }, { "AXIAL", Method::Axial } };
      const std::string name = FirstWord(method.text().get());
      const auto known = kMethods.find(name);
      if (known == kMethods.end())
      {
        this->reader.Fail(wrap, "wrapping method '" + name + "' is not one of hybrid, midpoint or axial");
      }
      w.method = known->second;
    }
    path.wraps.push_back(w);
  }
  this->model.paths.push_back(path);
}
}
