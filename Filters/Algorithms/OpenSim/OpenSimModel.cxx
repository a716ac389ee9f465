// SPDX-License-Identifier: BSD-3-Clause
#include "OpenSim/OpenSimModel.h"

#include <pugixml.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

namespace md::osim
{
namespace
{
template<typename Item>
int IndexOfName(const std::vector<Item>& items, const std::string& name)
{
  for (size_t i = 0; i < items.size(); ++i)
  {
    if (items[i].name == name)
    {
      return static_cast<int>(i);
    }
  }
  return -1;
}
}

int Model::FindBody(const std::string& bodyName) const
{
  return IndexOfName(this->bodies, bodyName);
}

int Model::FindCoordinate(const std::string& coordinateName) const
{
  return IndexOfName(this->coordinates, coordinateName);
}

int Model::FindPath(const std::string& pathName) const
{
  return IndexOfName(this->paths, pathName);
}

int Model::FindWrapObject(const std::string& wrapName) const
{
  return IndexOfName(this->wrapObjects, wrapName);
}

namespace
{
using Node = pugi::xml_node;

const std::set<std::string> kFunctionTypes = { "Constant", "LinearFunction", "SimmSpline", "NaturalCubicSpline",
  "PiecewiseLinearFunction", "PolynomialFunction", "MultiplierFunction" };
const std::set<std::string> kJointTypes = { "CustomJoint", "PinJoint", "WeldJoint", "BallJoint", "UniversalJoint",
  "SliderJoint", "PlanarJoint", "FreeJoint", "GimbalJoint" };
/// The deepest nesting of elements read: OpenSim's own models nest about 12 deep.
constexpr size_t kMaxElementDepth = 256;
const std::set<std::string> kPointTypes = { "PathPoint", "ConditionalPathPoint", "MovingPathPoint" };

/// Finds the first element nested deeper than kMaxElementDepth.
struct DepthLimit : pugi::xml_tree_walker
{
  Node tooDeep;
  bool for_each(Node& node) override
  {
    if (node.type() == pugi::node_element && static_cast<size_t>(this->depth()) >= kMaxElementDepth)
    {
      this->tooDeep = node;
      return false;
    }
    return true;
  }
};

/// Reads the document and says where things are for messages.
class Reader
{
public:
  Reader(const std::string& text, const std::string& fileName)
    : text(text)
    , fileName(fileName)
  {
  }

  [[noreturn]] void Fail(Node node, const std::string& problem) const
  {
    std::string where = "OpenSim model '" + this->fileName + "'";
    if (node)
    {
      where += ", line " + std::to_string(this->Line(node)) + ", " + Describe(node);
    }
    throw InputError(where + ": " + problem);
  }

  std::string Warn(Node node, const std::string& problem) const
  {
    return Describe(node) + " (line " + std::to_string(this->Line(node)) + "): " + problem;
  }

  /// "CustomJoint 'knee_r' > TransformAxis 'rotation1'": the named elements down to `node`.
  static std::string Describe(Node node)
  {
    std::vector<std::string> parts;
    for (Node n = node; n && n.type() == pugi::node_element; n = n.parent())
    {
      const char* name = n.attribute("name").value();
      if (*name || n == node)
      {
        parts.push_back(std::string(n.name()) + (*name ? std::string(" '") + name + "'" : ""));
      }
      if (parts.size() == 3)
      {
        break;
      }
    }
    std::string out;
    for (size_t i = parts.size(); i-- > 0;)
    {
      out += parts[i] + (i ? " > " : "");
    }
    return out;
  }

  size_t Line(Node node) const
  {
    const ptrdiff_t offset = node.offset_debug();
    if (offset < 0)
    {
      return 0;
    }
    return 1 +
      static_cast<size_t>(
        std::count(this->text.begin(), this->text.begin() + std::min<ptrdiff_t>(offset, this->text.size()), '\n'));
  }

  std::vector<double> Numbers(Node node, const char* child, size_t expected = 0) const
  {
    Node element = node.child(child);
    std::vector<double> values;
    if (!element)
    {
      return values;
    }
    std::istringstream stream(element.text().get());
    std::string token;
    while (stream >> token)
    {
      char* end = nullptr;
      const double value = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0' || !std::isfinite(value))
      {
        this->Fail(element, "'" + token + "' is not a finite number");
      }
      if (std::abs(value) > kLargestValue)
      {
        this->Fail(element, "'" + token + "' is beyond the +-1e12 a model's geometry can hold");
      }
      values.push_back(value);
    }
    if (expected && values.size() != expected)
    {
      this->Fail(element, "expected " + std::to_string(expected) + " numbers, found " + std::to_string(values.size()));
    }
    return values;
  }

  Eigen::Vector3d Vector(Node node, const char* child, const Eigen::Vector3d& fallback) const
  {
    if (!node.child(child))
    {
      return fallback;
    }
    const std::vector<double> v = this->Numbers(node, child, 3);
    return Eigen::Vector3d(v[0], v[1], v[2]);
  }

  double Number(Node node, const char* child, double fallback) const
  {
    if (!node.child(child))
    {
      return fallback;
    }
    return this->Numbers(node, child, 1)[0];
  }

  /// `make()`, whose complaints (knots that do not increase, ...) are told with this node's place
  /// in the file.
  template<typename Make>
  Function Located(Node node, Make make) const
  {
    try
    {
      return make();
    }
    catch (const InputError& e)
    {
      this->Fail(node, e.what());
    }
  }

  Function ReadFunction(Node node) const
  {
    const std::string type = node.name();
    if (type == "Constant")
    {
      return Function::Constant(this->Number(node, "value", 0.0));
    }
    if (type == "LinearFunction")
    {
      const std::vector<double> c = this->Numbers(node, "coefficients", 2);
      return Function::Linear(c[0], c[1]);
    }
    if (type == "SimmSpline" || type == "NaturalCubicSpline" || type == "PiecewiseLinearFunction")
    {
      std::vector<double> x = this->Numbers(node, "x"), y = this->Numbers(node, "y");
      return this->Located(node, [&]() {
        if (type == "SimmSpline")
        {
          return Function::SimmSpline(std::move(x), std::move(y));
        }
        if (type == "NaturalCubicSpline")
        {
          return Function::NaturalCubicSpline(std::move(x), std::move(y));
        }
        return Function::PiecewiseLinear(std::move(x), std::move(y));
      });
    }
    if (type == "PolynomialFunction")
    {
      const std::vector<double> coefficients = this->Numbers(node, "coefficients");
      return this->Located(node, [&]() { return Function::Polynomial(coefficients); });
    }
    if (type == "MultiplierFunction")
    {
      Node inner = this->FunctionChild(node, "function");
      if (!inner)
      {
        this->Fail(node, "MultiplierFunction without a function");
      }
      return Function::Multiplier(this->ReadFunction(inner), this->Number(node, "scale", 1.0));
    }
    this->Fail(node,
      "unknown function type '" + type +
        "' (supported: Constant, LinearFunction, SimmSpline, NaturalCubicSpline, "
        "PiecewiseLinearFunction, PolynomialFunction, MultiplierFunction)");
  }

  /// The function element of `owner` for its property `property`: 3.x wraps it
  /// (<property><SimmSpline>), 4.x names it (<SimmSpline name="property">). Empty when absent;
  /// ReadFunction says so when the element is no known function.
  Node FunctionChild(Node owner, const char* property) const
  {
    Node wrapper = owner.child(property);
    if (wrapper)
    {
      Node first = wrapper.first_child();
      while (first && first.type() != pugi::node_element)
      {
        first = first.next_sibling();
      }
      if (!first)
      {
        return Node();
      }
      return first;
    }
    for (Node child : owner.children())
    {
      if (std::strcmp(child.attribute("name").value(), property) == 0)
      {
        return child;
      }
    }
    return Node();
  }

  const std::string& text;
  std::string fileName;
};

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

/// A frame fixed on a body (4.x PhysicalOffsetFrame, or a body itself).
struct FrameOnBody
{
  int body = -1;
  RigidTransform offset;
};

class ModelBuilder
{
public:
  ModelBuilder(const Reader& reader, Model& model)
    : reader(reader)
    , model(model)
  {
  }

  void Build(Node document)
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

private:
  void ReadBodyExtras(Node body, int index)
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

  /// 4.x frames: every PhysicalOffsetFrame of the model, by name and by absolute path.
  void CollectFrames(Node modelNode)
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

  /// The body and offset of a frame named by a socket (`/bodyset/femur_r`, `/ground`,
  /// `femur_r_offset`, `../femur_r_offset`, ...); frames local to `scope` (a joint) first.
  FrameOnBody ResolveFrame(Node where, const std::string& reference, Node scope, int depth = 0)
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

  int AddCoordinate(Node coordinateNode, const std::string& jointName)
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

  void ReadJoint(Node joint, int childFromBody)
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

  void ReadSpatialTransform(Node joint, Joint& j, const std::vector<int>& jointCoordinates)
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

  /// Parents before children, every body reached from ground.
  void OrderJoints(Node modelNode)
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

  /// OpenSim's `quadrant`: x, +x, -x (any case), y, z likewise, all, or none given (all).
  void ReadQuadrant(Node wrap, WrapObject& w)
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

  void ReadWrapObjects(Node modelNode)
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

  int CoordinateOf(Node where, const std::string& reference)
  {
    const std::string name = LastPathPart(reference);
    const int index = this->model.FindCoordinate(name);
    if (index < 0)
    {
      this->reader.Fail(where, "coordinate '" + reference + "' is not in the model");
    }
    return index;
  }

  void ReadCoupler(Node constraint)
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

  FrameOnBody PointFrame(Node point)
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

  void ReadPath(Node force, Node geometryPath)
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

  const Reader& reader;
  Model& model;
  bool v4 = false;
  std::map<std::string, Node> frameNodes;
};
}

Model ParseModel(const std::string& text, const std::string& fileName)
{
  pugi::xml_document document;
  const pugi::xml_parse_result parsed = document.load_buffer(text.data(), text.size());
  Reader reader(text, fileName);
  if (!parsed)
  {
    const size_t line = 1 +
      static_cast<size_t>(
        std::count(text.begin(), text.begin() + std::min<ptrdiff_t>(parsed.offset, text.size()), '\n'));
    throw InputError(
      "OpenSim model '" + fileName + "', line " + std::to_string(line) + ": malformed XML: " + parsed.description());
  }
  // The model is read by walks whose depth is the file's nesting: refuse a nesting no model has
  // before any of them (a deep one would overflow the stack). pugixml's traversal is a loop.
  DepthLimit limit;
  document.traverse(limit);
  if (limit.tooDeep)
  {
    reader.Fail(limit.tooDeep,
      "elements nested more than " + std::to_string(kMaxElementDepth) + " deep; no OpenSim model nests so deep");
  }
  Node root = document.child("OpenSimDocument");
  Model model;
  model.file = fileName;
  if (!root)
  {
    if (document.child("Model"))
    {
      root = document; // a bare <Model>: read as the current format
      model.version = 40000;
    }
    else
    {
      throw InputError("OpenSim model '" + fileName + "': no <OpenSimDocument> element (is it an .osim file?)");
    }
  }
  else
  {
    model.version = root.attribute("Version").as_int(0);
    if (model.version < 20000)
    {
      reader.Fail(root,
        "format version " + std::to_string(model.version) +
          " is not supported (OpenSim 3.x is 20000-30516, 4.x 40000 and later)");
    }
  }
  ModelBuilder(reader, model).Build(root);
  return model;
}

Model ReadModel(const std::string& fileName)
{
  std::ifstream stream(fileName, std::ios::binary);
  if (!stream)
  {
    throw InputError("OpenSim model '" + fileName + "' cannot be opened");
  }
  std::ostringstream content;
  content << stream.rdbuf();
  return ParseModel(content.str(), fileName);
}
}
