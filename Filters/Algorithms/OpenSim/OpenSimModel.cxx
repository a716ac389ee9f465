// SPDX-License-Identifier: BSD-3-Clause
#include "OpenSim/OpenSimModel.h"

#include "OpenSim/OpenSimModelBuilder.h"

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

Model ParseModel(const std::string& text, const std::string& fileName)
{
  using namespace xml;
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
