// SPDX-License-Identifier: BSD-3-Clause
#include "OpenSim/OpenSimModelBuilder.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <sstream>

namespace md::osim::xml
{
/// Body-fixed X-Y-Z rotation, as OpenSim's orientations and 3.x transforms.
Eigen::Matrix3d BodyFixedXYZ(const Eigen::Vector3d& angles)
{
  return (Eigen::AngleAxisd(angles[0], Eigen::Vector3d::UnitX()) *
    Eigen::AngleAxisd(angles[1], Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(angles[2], Eigen::Vector3d::UnitZ()))
    .toRotationMatrix();
}

RigidTransform Offset(const Eigen::Vector3d& translation, const Eigen::Vector3d& orientation)
{
  RigidTransform t;
  t.rotation = BodyFixedXYZ(orientation);
  t.translation = translation;
  return t;
}

std::string LastPathPart(std::string path)
{
  while (!path.empty() && path.back() == '/')
  {
    path.pop_back();
  }
  const size_t slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

/// The first word of `text`, or "" when it has none.
std::string FirstWord(const char* text)
{
  std::istringstream stream(text);
  std::string word;
  stream >> word;
  return word;
}

std::vector<std::string> Words(const char* text)
{
  std::istringstream stream(text);
  std::vector<std::string> words;
  std::string word;
  while (stream >> word)
  {
    words.push_back(word);
  }
  return words;
}

Node FirstElement(Node parent, const std::set<std::string>& types)
{
  for (Node child : parent.children())
  {
    if (types.count(child.name()))
    {
      return child;
    }
  }
  return Node();
}

ModelBuilder::ModelBuilder(const Reader& reader, Model& model)
  : reader(reader)
  , model(model)
{
}

void ModelBuilder::Build(Node document)
{
  Node modelNode = document.child("Model");
  if (!modelNode)
  {
    this->reader.Fail(document, "no <Model> element");
  }
  this->model.name = modelNode.attribute("name").value();
  this->v4 = this->model.version >= 40000;
  this->model.bodies.push_back(Body{ "ground", {} });
  Node ground = modelNode.child("Ground");
  if (ground)
  {
    this->ReadBodyExtras(ground, 0);
  }
  for (Node body : modelNode.child("BodySet").child("objects").children("Body"))
  {
    const std::string name = body.attribute("name").value();
    if (name == "ground")
    {
      continue; // 3.x ground: read with the other bodies below
    }
    if (name.empty())
    {
      this->reader.Fail(body, "a body without a name");
    }
    if (this->model.FindBody(name) >= 0)
    {
      this->reader.Fail(body, "a second body named '" + name + "'");
    }
    this->model.bodies.push_back(Body{ name, {} });
  }
  // Joints: 4.x in the JointSet, 3.x inside their child body.
  std::vector<Node> jointNodes;
  std::vector<int> jointChild;
  if (this->v4)
  {
    for (Node joint : modelNode.child("JointSet").child("objects").children())
    {
      if (joint.type() == pugi::node_element)
      {
        jointNodes.push_back(joint);
        jointChild.push_back(-1);
      }
    }
  }
  int bodyIndex = 0;
  for (Node body : modelNode.child("BodySet").child("objects").children("Body"))
  {
    const int index = std::string(body.attribute("name").value()) == "ground" ? 0 : ++bodyIndex;
    if (index > 0 || !this->v4)
    {
      this->ReadBodyExtras(body, index);
    }
    for (Node joint : body.child("Joint").children())
    {
      if (joint.type() == pugi::node_element)
      {
        jointNodes.push_back(joint);
        jointChild.push_back(index);
      }
    }
  }
  this->CollectFrames(modelNode);
  for (size_t j = 0; j < jointNodes.size(); ++j)
  {
    this->ReadJoint(jointNodes[j], jointChild[j]);
  }
  this->OrderJoints(modelNode);
  this->ReadWrapObjects(modelNode);
  for (Node constraint : modelNode.child("ConstraintSet").child("objects").children())
  {
    if (constraint.type() != pugi::node_element)
    {
      continue;
    }
    if (std::string(constraint.name()) == "CoordinateCouplerConstraint")
    {
      this->ReadCoupler(constraint);
    }
    else
    {
      this->model.warnings.push_back(
        this->reader.Warn(constraint, "constraint type not honoured; the coordinates are taken as given"));
    }
  }
  for (Node force : modelNode.child("ForceSet").child("objects").children())
  {
    Node path = force.child("GeometryPath");
    if (path)
    {
      this->ReadPath(force, path);
    }
  }
}

void ModelBuilder::ReadBodyExtras(Node body, int index)
{
  Body& target = this->model.bodies[index];
  // 3.x: VisibleObject with a GeometrySet (or older geometry_files) and overall scale factors.
  Node visible = body.child("VisibleObject");
  if (visible)
  {
    const Eigen::Vector3d overallScale = this->reader.Vector(visible, "scale_factors", Eigen::Vector3d::Ones());
    const std::vector<double> overall = this->reader.Numbers(visible, "transform");
    RigidTransform overallPlacement;
    if (overall.size() == 6)
    {
      overallPlacement = Offset({ overall[3], overall[4], overall[5] }, { overall[0], overall[1], overall[2] });
    }
    for (Node display : visible.child("GeometrySet").child("objects").children("DisplayGeometry"))
    {
      Geometry g;
      g.file = FirstWord(display.child("geometry_file").text().get());
      g.scale = overallScale.cwiseProduct(this->reader.Vector(display, "scale_factors", Eigen::Vector3d::Ones()));
      const std::vector<double> t = this->reader.Numbers(display, "transform");
      g.placement = overallPlacement;
      if (t.size() == 6)
      {
        g.placement = Compose(overallPlacement, Offset({ t[3], t[4], t[5] }, { t[0], t[1], t[2] }));
      }
      if (!g.file.empty())
      {
        target.geometry.push_back(g);
      }
    }
    for (const std::string& file : Words(visible.child("geometry_files").text().get()))
    {
      Geometry g;
      g.file = file;
      g.scale = overallScale;
      g.placement = overallPlacement;
      target.geometry.push_back(g);
    }
  }
  // 4.x: attached_geometry meshes on the body.
  for (Node mesh : body.child("attached_geometry").children("Mesh"))
  {
    Geometry g;
    g.file = mesh.child("mesh_file").text().get();
    g.scale = this->reader.Vector(mesh, "scale_factors", Eigen::Vector3d::Ones());
    if (!g.file.empty())
    {
      target.geometry.push_back(g);
    }
  }
}

void ModelBuilder::CollectFrames(Node modelNode)
{
  std::function<void(Node, const std::string&)> visit = [&](Node node, const std::string& path) {
    for (Node child : node.children())
    {
      if (child.type() != pugi::node_element)
      {
        continue;
      }
      const std::string name = child.attribute("name").value();
      std::string childPath = path;
      if (!name.empty())
      {
        childPath += "/" + name;
      }
      if (std::string(child.name()) == "PhysicalOffsetFrame")
      {
        this->frameNodes[childPath] = child;
        this->frameNodes.emplace(name, child);
      }
      visit(child,
        std::string(child.name()) == "objects" || child.name() == std::string("frames") ||
            child.name() == std::string("components")
          ? path
          : childPath);
    }
  };
  // Paths as OpenSim 4 writes them: /jointset/<joint>/<frame>, /bodyset/<body>/<frame>.
  for (Node joint : modelNode.child("JointSet").child("objects").children())
  {
    visit(joint, "/jointset/" + std::string(joint.attribute("name").value()));
  }
  for (Node body : modelNode.child("BodySet").child("objects").children("Body"))
  {
    visit(body, "/bodyset/" + std::string(body.attribute("name").value()));
  }
  visit(modelNode.child("ComponentSet"), "");
}

FrameOnBody ModelBuilder::ResolveFrame(Node where, const std::string& reference, Node scope, int depth)
{
  if (depth > 16)
  {
    this->reader.Fail(where, "frame '" + reference + "' refers to itself");
  }
  const std::string last = LastPathPart(reference);
  if (reference == "/ground" || last == "ground")
  {
    return { 0, RigidTransform() };
  }
  if (reference.rfind("/bodyset/", 0) == 0 || reference.find('/') == std::string::npos)
  {
    const int body = this->model.FindBody(last);
    if (body >= 0)
    {
      return { body, RigidTransform() };
    }
  }
  Node frame;
  if (scope)
  {
    for (Node candidate : scope.child("frames").children("PhysicalOffsetFrame"))
    {
      if (last == candidate.attribute("name").value())
      {
        frame = candidate;
      }
    }
  }
  if (!frame)
  {
    auto found = this->frameNodes.find(reference);
    if (found == this->frameNodes.end())
    {
      found = this->frameNodes.find(last);
    }
    if (found != this->frameNodes.end())
    {
      frame = found->second;
    }
  }
  if (!frame)
  {
    const int body = this->model.FindBody(last);
    if (body >= 0)
    {
      return { body, RigidTransform() };
    }
    this->reader.Fail(where, "no body or frame named '" + reference + "'");
  }
  std::string parent = frame.child("socket_parent").text().get();
  if (parent.empty() || parent == "..")
  {
    // A frame inside a body's components sits on that body.
    Node owner = frame.parent();
    while (owner && std::string(owner.name()) != "Body")
    {
      owner = owner.parent();
    }
    if (!owner)
    {
      this->reader.Fail(frame, "the frame names no parent (socket_parent)");
    }
    parent = owner.attribute("name").value();
  }
  const FrameOnBody base = this->ResolveFrame(frame, parent, Node(), depth + 1);
  const RigidTransform own = Offset(this->reader.Vector(frame, "translation", Eigen::Vector3d::Zero()),
    this->reader.Vector(frame, "orientation", Eigen::Vector3d::Zero()));
  return { base.body, Compose(base.offset, own) };
}

int ModelBuilder::AddCoordinate(Node coordinateNode, const std::string& jointName)
{
  Coordinate c;
  c.name = coordinateNode.attribute("name").value();
  c.joint = jointName;
  if (c.name.empty())
  {
    this->reader.Fail(coordinateNode, "a coordinate without a name");
  }
  if (this->model.FindCoordinate(c.name) >= 0)
  {
    this->reader.Fail(coordinateNode, "a second coordinate named '" + c.name + "'");
  }
  c.defaultValue = this->reader.Number(coordinateNode, "default_value", 0.0);
  const std::vector<double> range = this->reader.Numbers(coordinateNode, "range");
  if (range.size() == 2)
  {
    c.rangeMin = std::min(range[0], range[1]);
    c.rangeMax = std::max(range[0], range[1]);
  }
  this->model.coordinates.push_back(c);
  return static_cast<int>(this->model.coordinates.size()) - 1;
}

void ModelBuilder::ReadJoint(Node joint, int childFromBody)
{
  const std::string type = joint.name();
  const std::string name = joint.attribute("name").value();
  if (!kJointTypes.count(type))
  {
    this->reader.Fail(joint,
      "unknown joint type '" + type +
        "' (supported: CustomJoint, PinJoint, WeldJoint, BallJoint, UniversalJoint, SliderJoint, "
        "PlanarJoint, FreeJoint, GimbalJoint)");
  }
  Joint j;
  j.name = name;
  j.type = type;
  std::vector<int> coordinates;
  if (this->v4)
  {
    for (Node c : joint.child("coordinates").children("Coordinate"))
    {
      coordinates.push_back(this->AddCoordinate(c, name));
    }
    const FrameOnBody parent = this->ResolveFrame(joint, joint.child("socket_parent_frame").text().get(), joint);
    const FrameOnBody child = this->ResolveFrame(joint, joint.child("socket_child_frame").text().get(), joint);
    j.parentBody = parent.body;
    j.parentOffset = parent.offset;
    j.childBody = child.body;
    j.childOffset = child.offset;
  }
  else
  {
    for (Node c : joint.child("CoordinateSet").child("objects").children("Coordinate"))
    {
      coordinates.push_back(this->AddCoordinate(c, name));
    }
    const std::string parentName = FirstWord(joint.child("parent_body").text().get());
    j.parentBody = this->model.FindBody(parentName);
    if (j.parentBody < 0)
    {
      this->reader.Fail(joint, "parent body '" + parentName + "' is not in the model");
    }
    j.childBody = childFromBody;
    j.parentOffset = Offset(this->reader.Vector(joint, "location_in_parent", Eigen::Vector3d::Zero()),
      this->reader.Vector(joint, "orientation_in_parent", Eigen::Vector3d::Zero()));
    j.childOffset = Offset(this->reader.Vector(joint, "location", Eigen::Vector3d::Zero()),
      this->reader.Vector(joint, "orientation", Eigen::Vector3d::Zero()));
  }
  if (std::string(joint.child("reverse").text().get()) == "true")
  {
    this->model.warnings.push_back(this->reader.Warn(joint, "reversed joints are read as not reversed"));
  }
  if (j.childBody <= 0)
  {
    this->reader.Fail(joint, "the joint's child is ground or not a body");
  }
  // Default axes: rotations about X, Y, Z, translations along X, Y, Z, all constant 0.
  for (int i = 0; i < 6; ++i)
  {
    j.axes[i].axis = Eigen::Vector3d::Unit(i % 3);
  }
  auto needs = [&](size_t count) {
    if (coordinates.size() != count)
    {
      this->reader.Fail(joint,
        "a " + type + " has " + std::to_string(count) + " coordinate(s), this one " +
          std::to_string(coordinates.size()));
    }
  };
  auto drive = [&](int axis, int coordinate, MotionType motion) {
    j.axes[axis].coordinate = coordinates[coordinate];
    j.axes[axis].function = Function::Linear(1.0, 0.0);
    this->model.coordinates[coordinates[coordinate]].motionType = motion;
  };
  // Pin and planar joints turn about the joint frame's z.
  auto rotateAboutZFirst = [&]() {
    j.axes[0].axis = Eigen::Vector3d::UnitZ();
    j.axes[1].axis = Eigen::Vector3d::UnitX();
    j.axes[2].axis = Eigen::Vector3d::UnitY();
  };
  if (type == "CustomJoint")
  {
    this->ReadSpatialTransform(joint, j, coordinates);
  }
  else if (type == "PinJoint")
  {
    needs(1);
    rotateAboutZFirst();
    drive(0, 0, MotionType::Rotational);
  }
  else if (type == "WeldJoint")
  {
    needs(0);
  }
  else if (type == "SliderJoint")
  {
    needs(1);
    drive(3, 0, MotionType::Translational);
  }
  else if (type == "UniversalJoint")
  {
    needs(2);
    drive(0, 0, MotionType::Rotational);
    drive(1, 1, MotionType::Rotational);
  }
  else if (type == "BallJoint" || type == "GimbalJoint")
  {
    needs(3);
    for (int i = 0; i < 3; ++i)
    {
      drive(i, i, MotionType::Rotational);
    }
  }
  else if (type == "PlanarJoint")
  {
    needs(3);
    rotateAboutZFirst();
    drive(0, 0, MotionType::Rotational);
    drive(3, 1, MotionType::Translational);
    drive(4, 2, MotionType::Translational);
  }
  else if (type == "FreeJoint")
  {
    needs(6);
    for (int i = 0; i < 6; ++i)
    {
      drive(i, i, i < 3 ? MotionType::Rotational : MotionType::Translational);
    }
  }
  for (const Joint& other : this->model.joints)
  {
    if (other.childBody == j.childBody)
    {
      this->reader.Fail(joint,
        "body '" + this->model.bodies[j.childBody].name + "' is already the child of joint '" + other.name +
          "' (closed kinematic loops are not supported)");
    }
  }
  this->model.joints.push_back(j);
}

void ModelBuilder::ReadSpatialTransform(Node joint, Joint& j, const std::vector<int>& jointCoordinates)
{
  static const char* axisNames[6] = { "rotation1", "rotation2", "rotation3", "translation1", "translation2",
    "translation3" };
  Node transform = joint.child("SpatialTransform");
  if (!transform)
  {
    this->reader.Fail(joint, "a CustomJoint without a SpatialTransform");
  }
  std::vector<MotionType> motion(this->model.coordinates.size(), MotionType::Coupled);
  std::vector<bool> decided(this->model.coordinates.size(), false);
  for (Node axisNode : transform.children("TransformAxis"))
  {
    const std::string axisName = axisNode.attribute("name").value();
    int index = -1;
    for (int i = 0; i < 6; ++i)
    {
      if (axisName == axisNames[i])
      {
        index = i;
      }
    }
    if (index < 0)
    {
      this->reader.Fail(axisNode, "a TransformAxis must be named rotation1-3 or translation1-3");
    }
    TransformAxis& axis = j.axes[index];
    const Eigen::Vector3d direction = this->reader.Vector(axisNode, "axis", axis.axis);
    if (!(direction.norm() > 1e-12))
    {
      this->reader.Fail(axisNode, "the axis has zero length");
    }
    axis.axis = direction.normalized();
    const std::vector<std::string> names = Words(axisNode.child("coordinates").text().get());
    if (names.size() > 1)
    {
      this->reader.Fail(axisNode, "functions of several coordinates are not supported");
    }
    if (names.size() == 1)
    {
      axis.coordinate = this->model.FindCoordinate(names[0]);
      if (axis.coordinate < 0 ||
        std::find(jointCoordinates.begin(), jointCoordinates.end(), axis.coordinate) == jointCoordinates.end())
      {
        this->reader.Fail(axisNode, "coordinate '" + names[0] + "' is not a coordinate of this joint");
      }
    }
    Node functionNode = this->reader.FunctionChild(axisNode, "function");
    if (!functionNode)
    {
      functionNode = FirstElement(axisNode, kFunctionTypes);
    }
    if (functionNode)
    {
      axis.function = this->reader.ReadFunction(functionNode);
    }
    else if (axis.coordinate >= 0)
    {
      axis.function = Function::Linear(1.0, 0.0);
    }
    if (axis.coordinate >= 0)
    {
      const bool pure = axis.function.GetKind() == Function::Kind::Linear &&
        (axis.function.Slope() == 1.0 || axis.function.Slope() == -1.0);
      MotionType& m = motion[axis.coordinate];
      if (pure)
      {
        m = index < 3 ? MotionType::Rotational : MotionType::Translational;
        decided[axis.coordinate] = true;
      }
      else if (!decided[axis.coordinate])
      {
        m = MotionType::Coupled;
      }
    }
  }
  for (int c : jointCoordinates)
  {
    this->model.coordinates[c].motionType = motion[c];
  }
}

void ModelBuilder::OrderJoints(Node modelNode)
{
  std::vector<Joint> ordered;
  std::vector<bool> placed(this->model.bodies.size(), false);
  placed[0] = true;
  bool progress = true;
  while (progress)
  {
    progress = false;
    for (const Joint& j : this->model.joints)
    {
      if (placed[j.parentBody] && !placed[j.childBody])
      {
        ordered.push_back(j);
        placed[j.childBody] = true;
        progress = true;
      }
    }
  }
  for (size_t b = 1; b < placed.size(); ++b)
  {
    if (!placed[b])
    {
      this->reader.Fail(modelNode, "body '" + this->model.bodies[b].name + "' is not connected to ground by joints");
    }
  }
  this->model.joints = ordered;
}
}
