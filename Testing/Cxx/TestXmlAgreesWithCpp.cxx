// SPDX-License-Identifier: BSD-3-Clause
// The defaults and ranges a user sees in ParaView (ServerManagerXML) and the ones a C++ or VTK
// user gets (the filters' constructors, which take the core's defaults, and their clamps) are
// written twice, the XML being ParaView's own format: this test holds them to each other, the
// defaults through each filter's PrintSelf, the ranges against the headers' vtkSetClampMacro.
// (HullTargetNumberOfPoints once had a minimum of 4 in one and 8 in the other.)
#include "vtkActionLineGrouping.h"
#include "vtkActionLineMatching.h"
#include "vtkBoneInterpolation.h"
#include "vtkHullDecimation.h"
#include "vtkInterpolatedMuscleDeformation.h"
#include "vtkIntersectionResolve.h"
#include "vtkMotionMuscleDeformation.h"
#include "vtkMoveWithBodies.h"
#include "vtkMuscleDeformation.h"
#include "vtkMuscleFromPath.h"
#include "vtkMusculoskeletalPhantom.h"
#include "vtkOpenSimModelReader.h"
#include "vtkPathsOverBones.h"

#include <vtkSmartPointer.h>
#include <vtkType.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace
{
template<typename T>
vtkSmartPointer<vtkObject> Make()
{
  return vtkSmartPointer<T>::New();
}

const std::map<std::string, std::function<vtkSmartPointer<vtkObject>()>> Classes = {
  { "vtkActionLineGrouping", Make<vtkActionLineGrouping> },
  { "vtkActionLineMatching", Make<vtkActionLineMatching> },
  { "vtkBoneInterpolation", Make<vtkBoneInterpolation> },
  { "vtkHullDecimation", Make<vtkHullDecimation> },
  { "vtkMuscleFromPath", Make<vtkMuscleFromPath> },
  { "vtkInterpolatedMuscleDeformation", Make<vtkInterpolatedMuscleDeformation> },
  { "vtkIntersectionResolve", Make<vtkIntersectionResolve> },
  { "vtkMotionMuscleDeformation", Make<vtkMotionMuscleDeformation> },
  { "vtkMoveWithBodies", Make<vtkMoveWithBodies> },
  { "vtkMuscleDeformation", Make<vtkMuscleDeformation> },
  { "vtkMusculoskeletalPhantom", Make<vtkMusculoskeletalPhantom> },
  { "vtkOpenSimModelReader", Make<vtkOpenSimModelReader> },
  { "vtkPathsOverBones", Make<vtkPathsOverBones> },
};

std::map<std::string, std::string> Attributes(const std::string& tag)
{
  std::map<std::string, std::string> attributes;
  static const std::regex attribute(R"re((\w+)="([^"]*)")re");
  for (std::sregex_iterator it(tag.begin(), tag.end(), attribute), end; it != end; ++it)
  {
    attributes[(*it)[1]] = (*it)[2];
  }
  return attributes;
}

/// The value PrintSelf gives for `name` ("  Name: value"), or "" when it prints none.
std::string Printed(vtkObject* object, const std::string& name)
{
  std::ostringstream out;
  object->Print(out);
  std::istringstream lines(out.str());
  std::string line;
  const std::string key = name + ": ";
  while (std::getline(lines, line))
  {
    const size_t start = line.find_first_not_of(' ');
    if (start != std::string::npos && line.compare(start, key.size(), key) == 0)
    {
      return line.substr(start + key.size());
    }
  }
  return "";
}

std::string ReadText(const std::string& path)
{
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// One numeric property of a proxy of ServerManagerXML.
struct XmlProperty
{
  std::string className;                         ///< the proxy's VTK class
  std::map<std::string, std::string> attributes; ///< the property's
  std::string elements;                          ///< its domains, documentation, hints
};

/// Every Int or Double vector property of every SourceProxy of every file of ServerManagerXML
/// (files in name order), and how many files there are.
std::vector<XmlProperty> NumericProperties(size_t& files)
{
  std::vector<std::string> paths;
  for (const auto& file :
    std::filesystem::directory_iterator(std::string(MUSCLEDEFORMATION_SOURCE_DIR) + "/ServerManagerXML"))
  {
    if (file.path().extension() == ".xml")
    {
      paths.push_back(file.path().string());
    }
  }
  std::sort(paths.begin(), paths.end());
  files = paths.size();
  static const std::regex proxy(R"re(<SourceProxy([^>]*)>([\s\S]*?)</SourceProxy>)re");
  static const std::regex property(R"re(<(Int|Double)VectorProperty([^>]*[^/])>([\s\S]*?)</\1VectorProperty>)re");
  std::vector<XmlProperty> properties;
  for (const std::string& path : paths)
  {
    const std::string text = ReadText(path);
    for (std::sregex_iterator p(text.begin(), text.end(), proxy), end; p != end; ++p)
    {
      const std::string className = Attributes((*p)[1])["class"];
      const std::string body = (*p)[2];
      for (std::sregex_iterator q(body.begin(), body.end(), property); q != end; ++q)
      {
        properties.push_back({ className, Attributes((*q)[2]), (*q)[3] });
      }
    }
  }
  return properties;
}
}

TEST(ServerManagerXml, EveryNumericDefaultIsTheConstructorsDefault)
{
  int compared = 0;
  size_t files = 0;
  static const std::regex entry(R"re(<Entry([^>]*)/>)re");
  for (XmlProperty& xml : NumericProperties(files))
  {
    std::map<std::string, std::string>& a = xml.attributes;
    const std::string& className = xml.className;
    ASSERT_EQ(Classes.count(className), 1u) << className << " is in the XML but not in this test";
    if (a["information_only"] == "1" || a["number_of_elements"] != "1" || a["default_values"].empty() ||
      a["command"] != "Set" + a["name"])
    {
      continue;
    }
    vtkSmartPointer<vtkObject> object = Classes.at(className)();
    const std::string printed = Printed(object, a["name"]);
    ASSERT_FALSE(printed.empty()) << className << "::PrintSelf does not print " << a["name"];
    char* rest = nullptr;
    double value = std::strtod(printed.c_str(), &rest);
    if (!rest || *rest != '\0')
    {
      // An enumeration may print its entry's text: the XML's Entry says its value.
      bool found = false;
      for (std::sregex_iterator e(xml.elements.begin(), xml.elements.end(), entry), end; e != end && !found; ++e)
      {
        std::map<std::string, std::string> item = Attributes((*e)[1]);
        if (item["text"] == printed)
        {
          value = std::stod(item["value"]);
          found = true;
        }
      }
      ASSERT_TRUE(found) << className << "." << a["name"] << " prints '" << printed << "', no number or entry";
    }
    EXPECT_DOUBLE_EQ(value, std::stod(a["default_values"]))
      << className << "." << a["name"] << ": XML default " << a["default_values"] << ", C++ " << printed;
    ++compared;
  }
  EXPECT_EQ(files, 12u) << "one file per proxy";
  EXPECT_GE(compared, 42); // every numeric property the XML had when this was written: the parsing works
}

namespace
{
/// A bound of vtkSetClampMacro as written in a header: a number, VTK_INT_MAX or VTK_DOUBLE_MAX;
/// NaN for anything else (an enumeration's names).
double Bound(const std::string& token)
{
  if (token == "VTK_INT_MAX")
  {
    return VTK_INT_MAX;
  }
  if (token == "VTK_DOUBLE_MAX")
  {
    return VTK_DOUBLE_MAX;
  }
  char* rest = nullptr;
  const double value = std::strtod(token.c_str(), &rest);
  return rest && *rest == '\0' ? value : std::nan("");
}
}

TEST(ServerManagerXml, EveryRangeTheGuiOffersTheFilterAccepts)
{
  // The XML's RangeDomain is what the GUI's sliders offer; the header's vtkSetClampMacro what the
  // filter accepts. The first must lie within the second (a value offered and then silently
  // clamped is another value than the one shown), and every clamped property offers a range or
  // an enumeration.
  int compared = 0;
  size_t files = 0;
  static const std::regex range(R"re(<(Int|Double)RangeDomain([^>]*)/>)re");
  for (XmlProperty& xml : NumericProperties(files))
  {
    const std::string header = ReadText(std::string(MUSCLEDEFORMATION_SOURCE_DIR) + "/Filters/" + xml.className + ".h");
    ASSERT_FALSE(header.empty()) << xml.className;
    const std::string name = xml.className + "." + xml.attributes["name"];
    const std::regex clamp(
      "vtkSetClampMacro\\(\\s*" + xml.attributes["name"] + "\\s*,\\s*\\w+\\s*,\\s*([^,]+?)\\s*,\\s*([^)]+?)\\s*\\)");
    std::smatch c;
    if (!std::regex_search(header, c, clamp))
    {
      continue;
    }
    std::smatch r;
    const bool hasRange = std::regex_search(xml.elements, r, range);
    EXPECT_TRUE(hasRange || xml.elements.find("EnumerationDomain") != std::string::npos)
      << name << " is clamped in C++ but offers no range in the XML";
    if (!hasRange)
    {
      continue;
    }
    std::map<std::string, std::string> domain = Attributes(r[2]);
    const double low = Bound(c[1]), high = Bound(c[2]);
    ASSERT_FALSE(std::isnan(low) || std::isnan(high)) << name;
    EXPECT_GE(std::stod(domain["min"]), low) << name << ": the GUI offers below the minimum";
    if (!domain["max"].empty())
    {
      EXPECT_LE(std::stod(domain["max"]), high) << name << ": the GUI offers above the maximum";
    }
    ++compared;
  }
  EXPECT_GE(compared, 30); // the ranges the XML had when this was written: the parsing works
}
