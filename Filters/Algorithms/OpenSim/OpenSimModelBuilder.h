// SPDX-License-Identifier: BSD-3-Clause
// Reading an OpenSim model document (docs/DESIGN.md, "OpenSim models"): the document and where
// its elements are for messages (Reader), and the model built from it (ModelBuilder: bodies,
// frames and joints in OpenSimModelBuilder.cxx; wrap objects, couplers and paths in
// OpenSimModelPaths.cxx). The OpenSim stage's own; OpenSimModel.cxx builds on it.
#pragma once

#include "OpenSim/OpenSimModel.h"

#include <pugixml.hpp>

#include <map>
#include <set>
#include <string>
#include <vector>

namespace md::osim::xml
{
using Node = pugi::xml_node;

inline const std::set<std::string> kFunctionTypes = { "Constant", "LinearFunction", "SimmSpline", "NaturalCubicSpline",
  "PiecewiseLinearFunction", "PolynomialFunction", "MultiplierFunction" };
inline const std::set<std::string> kJointTypes = { "CustomJoint", "PinJoint", "WeldJoint", "BallJoint",
  "UniversalJoint", "SliderJoint", "PlanarJoint", "FreeJoint", "GimbalJoint" };
/// The deepest nesting of elements read: OpenSim's own models nest about 12 deep.
constexpr size_t kMaxElementDepth = 256;
inline const std::set<std::string> kPointTypes = { "PathPoint", "ConditionalPathPoint", "MovingPathPoint" };

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
Eigen::Matrix3d BodyFixedXYZ(const Eigen::Vector3d& angles);

RigidTransform Offset(const Eigen::Vector3d& translation, const Eigen::Vector3d& orientation);

std::string LastPathPart(std::string path);

/// The first word of `text`, or "" when it has none.
std::string FirstWord(const char* text);

std::vector<std::string> Words(const char* text);

Node FirstElement(Node parent, const std::set<std::string>& types);

/// A frame fixed on a body (4.x PhysicalOffsetFrame, or a body itself).
struct FrameOnBody
{
  int body = -1;
  RigidTransform offset;
};

class ModelBuilder
{
public:
  ModelBuilder(const Reader& reader, Model& model);

  void Build(Node document);

private:
  void ReadBodyExtras(Node body, int index);

  /// 4.x frames: every PhysicalOffsetFrame of the model, by name and by absolute path.
  void CollectFrames(Node modelNode);

  /// The body and offset of a frame named by a socket (`/bodyset/femur_r`, `/ground`,
  /// `femur_r_offset`, `../femur_r_offset`, ...); frames local to `scope` (a joint) first.
  FrameOnBody ResolveFrame(Node where, const std::string& reference, Node scope, int depth = 0);

  int AddCoordinate(Node coordinateNode, const std::string& jointName);

  void ReadJoint(Node joint, int childFromBody);

  void ReadSpatialTransform(Node joint, Joint& j, const std::vector<int>& jointCoordinates);

  /// Parents before children, every body reached from ground.
  void OrderJoints(Node modelNode);

  /// OpenSim's `quadrant`: x, +x, -x (any case), y, z likewise, all, or none given (all).
  void ReadQuadrant(Node wrap, WrapObject& w);

  void ReadWrapObjects(Node modelNode);

  int CoordinateOf(Node where, const std::string& reference);

  void ReadCoupler(Node constraint);

  FrameOnBody PointFrame(Node point);

  void ReadPath(Node force, Node geometryPath);

  const Reader& reader;
  Model& model;
  bool v4 = false;
  std::map<std::string, Node> frameNodes;
};
}
