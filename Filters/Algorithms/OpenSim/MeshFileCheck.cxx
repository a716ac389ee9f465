// SPDX-License-Identifier: BSD-3-Clause
#include "OpenSim/MeshFileCheck.h"

#include "Common/MeshTypes.h"
#include "Common/Names.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <regex>
#include <sstream>

namespace md::osim
{
namespace
{
/// How many values an XML file's compressed data may expand to per byte of the file: zlib
/// gives at most about 1000 on runs of zeros; a mesh's coordinates compress 2-4 times.
constexpr double kXmlValuesPerByte = 64.0;

/// A count as a whole number ("6000000000").
std::string Count(double value)
{
  std::ostringstream text;
  text << std::fixed << std::setprecision(0) << value;
  return text.str();
}

[[noreturn]] void Lies(const std::string& path, const std::string& problem)
{
  throw InputError("mesh file '" + path + "': " + problem + "; the file is damaged or not what its name says");
}

/// VTK's rule (vtksys DetectFileType): text when at most 5 % of the first 256 bytes are
/// neither printable nor white space.
bool LooksLikeText(const std::string& bytes)
{
  const size_t n = std::min<size_t>(bytes.size(), 256);
  size_t binary = 0;
  for (size_t i = 0; i < n; ++i)
  {
    const unsigned char c = static_cast<unsigned char>(bytes[i]);
    if (!std::isprint(c) && !std::isspace(c))
    {
      ++binary;
    }
  }
  return n == 0 || binary <= n / 20;
}

void CheckStl(const std::string& path, const std::string& bytes)
{
  if (LooksLikeText(bytes))
  {
    return; // ASCII STL: read facet by facet
  }
  if (bytes.size() < 84)
  {
    Lies(path, "a binary STL of " + std::to_string(bytes.size()) + " bytes, shorter than its 84-byte header");
  }
  std::uint32_t triangles = 0;
  std::memcpy(&triangles, bytes.data() + 80, 4); // little endian, as every STL writer and reader
  const std::uint64_t needed = 84 + 50 * static_cast<std::uint64_t>(triangles);
  if (needed > bytes.size())
  {
    Lies(path,
      "its binary STL header claims " + std::to_string(triangles) + " triangles (" + std::to_string(needed) +
        " bytes) but the file has " + std::to_string(bytes.size()) + " bytes");
  }
}

/// Legacy VTK: every count on a keyword line (POINTS n, POLYGONS n size, POINT_DATA n, a field
/// array's components and tuples, ...) asks for at most one value per byte of the file.
void CheckLegacyVtk(const std::string& path, const std::string& bytes)
{
  std::istringstream lines(bytes);
  std::string line;
  int lineNumber = 0;
  while (std::getline(lines, line))
  {
    ++lineNumber;
    if (lineNumber <= 2)
    {
      continue; // the version line and the title
    }
    std::istringstream words(line);
    std::string keyword;
    if (!(words >> keyword) || !std::isalpha(static_cast<unsigned char>(keyword[0])))
    {
      continue; // ASCII data, or binary data
    }
    // Cells (POLYGONS n size): the larger count; POINTS n: 3n coordinates; a field array
    // (name components tuples type): the product.
    const bool cells = keyword == "VERTICES" || keyword == "LINES" || keyword == "POLYGONS" ||
      keyword == "TRIANGLE_STRIPS" || keyword == "CELLS";
    double values = 1.0, largest = 0.0;
    std::string word;
    bool counted = false;
    while (words >> word)
    {
      if (std::all_of(word.begin(), word.end(), [](unsigned char c) { return std::isdigit(c); }))
      {
        const double count = word.size() > 15 ? 1e300 : std::stod(word);
        values *= count;
        largest = std::max(largest, count);
        counted = true;
      }
    }
    values = cells ? largest : keyword == "POINTS" ? 3.0 * largest : values;
    if (counted && values > static_cast<double>(bytes.size()))
    {
      Lies(path,
        "line " + std::to_string(lineNumber) + " ('" + line.substr(0, 60) + "') asks for " + Count(values) +
          " values but the file has " + std::to_string(bytes.size()) + " bytes");
    }
  }
}

/// VTK XML: the NumberOf... attributes against the file's size.
void CheckXml(const std::string& path, const std::string& bytes)
{
  // The XML part ends where appended raw data begins.
  const size_t appended = bytes.find("<AppendedData");
  const std::string xml = bytes.substr(0, appended == std::string::npos ? bytes.size() : appended + 64);
  static const std::regex count(R"(NumberOf(\w+)\s*=\s*\"\s*(\d+)\s*\")");
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), count); it != std::sregex_iterator(); ++it)
  {
    const std::string digits = (*it)[2];
    const double value = digits.size() > 15 ? 1e300 : std::stod(digits);
    if (value > kXmlValuesPerByte * static_cast<double>(bytes.size()))
    {
      Lies(path,
        "NumberOf" + std::string((*it)[1]) + "=\"" + digits + "\" is more than a file of " +
          std::to_string(bytes.size()) + " bytes can hold");
    }
  }
}
}

void CheckMeshFileHeader(const std::string& path, const std::string& bytes)
{
  const size_t dot = path.find_last_of('.');
  const std::string extension = dot == std::string::npos ? "" : Lower(path.substr(dot));
  if (extension == ".stl")
  {
    CheckStl(path, bytes);
  }
  else if (extension == ".vtk")
  {
    CheckLegacyVtk(path, bytes);
  }
  else if (extension == ".vtp")
  {
    CheckXml(path, bytes);
  }
}

void CheckMeshFileHeader(const std::string& path)
{
  std::ifstream stream(path, std::ios::binary);
  if (!stream)
  {
    throw InputError("mesh file '" + path + "' cannot be opened");
  }
  std::ostringstream content;
  content << stream.rdbuf();
  CheckMeshFileHeader(path, content.str());
}
}
