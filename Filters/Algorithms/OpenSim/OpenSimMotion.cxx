// SPDX-License-Identifier: BSD-3-Clause
#include "OpenSim/OpenSimMotion.h"

#include "Common/Names.h"
#include "OpenSim/OpenSimKinematics.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace md::osim
{
namespace
{
std::string Trim(const std::string& s)
{
  const size_t begin = s.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos)
  {
    return "";
  }
  const size_t end = s.find_last_not_of(" \t\r\n");
  return s.substr(begin, end - begin + 1);
}

bool EndsWith(const std::string& s, const std::string& tail)
{
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

std::vector<std::string> Split(const std::string& line, bool tabsOnly)
{
  std::vector<std::string> fields;
  if (tabsOnly)
  {
    std::string field;
    std::istringstream stream(line);
    while (std::getline(stream, field, '\t'))
    {
      field = Trim(field);
      if (!field.empty())
      {
        fields.push_back(field);
      }
    }
    return fields;
  }
  std::istringstream stream(line);
  std::string field;
  while (stream >> field)
  {
    fields.push_back(field);
  }
  return fields;
}
}

MotionTable ReadMotion(const std::string& fileName)
{
  std::ifstream stream(fileName);
  if (!stream)
  {
    throw InputError("motion file '" + fileName + "' cannot be opened");
  }
  MotionTable table;
  table.file = fileName;
  auto fail = [&](size_t line, const std::string& problem) {
    throw InputError("motion file '" + fileName + "', line " + std::to_string(line) + ": " + problem);
  };
  std::string line;
  size_t lineNumber = 0;
  int version = 0;
  int degreesStated = -1; // -1 unknown, 0 radians, 1 degrees
  bool headerEnded = false;
  while (std::getline(stream, line))
  {
    ++lineNumber;
    const std::string trimmed = Trim(line);
    if (trimmed == "endheader")
    {
      headerEnded = true;
      break;
    }
    const size_t equals = trimmed.find('=');
    if (equals != std::string::npos)
    {
      const std::string key = Trim(trimmed.substr(0, equals)), value = Lower(Trim(trimmed.substr(equals + 1)));
      if (key == "inDegrees")
      {
        degreesStated = (value == "yes" || value == "y") ? 1 : 0;
      }
      else if (key == "version")
      {
        version = std::atoi(value.c_str());
      }
    }
    else if (trimmed == "Angles are in degrees.")
    {
      degreesStated = 1;
    }
    else if (trimmed == "Angles are in radians.")
    {
      degreesStated = 0;
    }
  }
  if (!headerEnded)
  {
    fail(lineNumber, "no 'endheader' line ends the header");
  }
  table.inDegrees = degreesStated >= 0 ? degreesStated == 1 : (version < 1 && EndsWith(Lower(fileName), ".mot"));
  // The column labels: the first non-empty line after the header.
  std::vector<std::string> labels;
  while (labels.empty() && std::getline(stream, line))
  {
    ++lineNumber;
    // Labels may contain spaces only in files separated by tabs.
    labels = Split(line, line.find('\t') != std::string::npos);
  }
  if (labels.empty())
  {
    fail(lineNumber, "no column labels after the header");
  }
  if (Lower(labels[0]) != "time")
  {
    fail(lineNumber, "the first column is '" + labels[0] + "', not 'time' (a motion needs a time column)");
  }
  table.labels.assign(labels.begin() + 1, labels.end());
  while (std::getline(stream, line))
  {
    ++lineNumber;
    const std::vector<std::string> fields = Split(line, false);
    if (fields.empty())
    {
      continue;
    }
    if (fields.size() != labels.size())
    {
      fail(lineNumber,
        "a row of " + std::to_string(fields.size()) + " values under " + std::to_string(labels.size()) +
          " column labels");
    }
    std::vector<double> row(fields.size());
    for (size_t i = 0; i < fields.size(); ++i)
    {
      char* end = nullptr;
      row[i] = std::strtod(fields[i].c_str(), &end);
      if (end == fields[i].c_str() || *end != '\0' || !std::isfinite(row[i]))
      {
        fail(lineNumber, "column '" + labels[i] + "' holds '" + fields[i] + "', not a finite number");
      }
      if (std::abs(row[i]) > kLargestValue)
      {
        fail(lineNumber, "column '" + labels[i] + "' holds " + fields[i] + ", beyond the +-1e12 a pose can hold");
      }
    }
    if (!table.times.empty() && !(row[0] > table.times.back()))
    {
      fail(lineNumber, "time " + fields[0] + " does not come after the previous row's");
    }
    table.times.push_back(row[0]);
    table.rows.emplace_back(row.begin() + 1, row.end());
  }
  if (table.times.empty())
  {
    fail(lineNumber, "no rows of data");
  }
  return table;
}

CoordinateTrajectory MapMotion(const Model& model, const MotionTable& motion, const MotionOptions& options)
{
  CoordinateTrajectory trajectory;
  const bool degrees = options.angles == AngleUnit::FromFile ? motion.inDegrees : options.angles == AngleUnit::Degrees;
  std::vector<int> columnCoordinate(motion.labels.size(), -1);
  std::vector<bool> covered(model.coordinates.size(), false);
  std::string skipped;
  // The coordinate columns whose values change over the motion: those that move something.
  size_t movingColumns = 0, movingSkipped = 0, movingMatched = 0;
  auto changes = [&](size_t column) {
    return std::any_of(motion.rows.begin(), motion.rows.end(),
      [&](const std::vector<double>& row) { return row[column] != motion.rows.front()[column]; });
  };
  for (size_t i = 0; i < motion.labels.size(); ++i)
  {
    std::string label = motion.labels[i];
    if (label.find('/') != std::string::npos)
    {
      if (!EndsWith(label, "/value"))
      {
        continue; // a speed or another state, not a coordinate's value
      }
      label = label.substr(0, label.size() - 6);
      label = label.substr(label.rfind('/') + 1);
    }
    const int coordinate = model.FindCoordinate(label);
    const bool moving = changes(i);
    movingColumns += moving;
    if (coordinate < 0)
    {
      if (!options.ignoreUnknownColumns)
      {
        throw InputError("motion file '" + motion.file + "': column '" + motion.labels[i] +
          "' names no coordinate of model '" + model.name + "' (to skip such columns, set IgnoreUnknownColumns)");
      }
      skipped += (skipped.empty() ? "" : ", ") + motion.labels[i];
      movingSkipped += moving;
      continue;
    }
    movingMatched += moving;
    columnCoordinate[i] = coordinate;
    covered[coordinate] = true;
  }
  if (!skipped.empty())
  {
    trajectory.warnings.push_back(
      "motion file '" + motion.file + "': columns naming no coordinate of the model were skipped: " + skipped);
  }
  std::string missing;
  std::vector<bool> dependent(model.coordinates.size(), false);
  for (const CoordinateCoupler& c : model.couplers)
  {
    dependent[c.dependent] = true;
  }
  for (size_t c = 0; c < covered.size(); ++c)
  {
    if (!covered[c] && !dependent[c])
    {
      missing += (missing.empty() ? "" : ", ") + model.coordinates[c].name;
    }
  }
  // The motion of another model: most of what the file moves names no coordinate of this one,
  // or it moves none of them. (Constant columns do not count: the LHDL motions carry six
  // columns of zeros under other names.)
  if (2 * movingSkipped > movingColumns || (movingColumns > 0 && movingMatched == 0))
  {
    trajectory.warnings.push_back("motion file '" + motion.file + "' does not look like a motion of model '" +
      model.name + "': " + std::to_string(movingSkipped) + " of the " + std::to_string(movingColumns) +
      " columns whose values change name no coordinate of the model, and it moves " + std::to_string(movingMatched) +
      " of the model's coordinates");
  }
  if (!missing.empty())
  {
    trajectory.warnings.push_back("motion file '" + motion.file +
      "' has no column for these coordinates, which keep their default values: " + missing);
  }
  const std::vector<double> defaults = DefaultCoordinates(model);
  trajectory.times = motion.times;
  trajectory.frames.reserve(motion.rows.size());
  for (const std::vector<double>& row : motion.rows)
  {
    std::vector<double> q = defaults;
    for (size_t i = 0; i < row.size(); ++i)
    {
      const int c = columnCoordinate[i];
      if (c >= 0)
      {
        const bool rotational = model.coordinates[c].motionType == MotionType::Rotational;
        q[c] = degrees && rotational ? row[i] * M_PI / 180.0 : row[i];
      }
    }
    ApplyCouplers(model, q);
    trajectory.frames.push_back(std::move(q));
  }
  return trajectory;
}

void SetCoordinates(const Model& model, const std::string& assignments, bool degrees, std::vector<double>& coordinates)
{
  std::string text = assignments;
  for (char& c : text)
  {
    if (c == ',' || c == ';' || c == '\n' || c == '\t')
    {
      c = ' ';
    }
  }
  std::istringstream stream(text);
  std::string item;
  while (stream >> item)
  {
    const size_t equals = item.find('=');
    if (equals == std::string::npos)
    {
      throw InputError("'" + item + "' is not of the form coordinate=value");
    }
    const std::string name = item.substr(0, equals), value = item.substr(equals + 1);
    const int c = model.FindCoordinate(name);
    if (c < 0)
    {
      throw InputError("'" + name + "' is not a coordinate of model '" + model.name + "'");
    }
    char* end = nullptr;
    const double number = std::strtod(value.c_str(), &end);
    if (value.empty() || *end != '\0' || !std::isfinite(number))
    {
      throw InputError("the value of '" + name + "' ('" + value + "') is not a finite number");
    }
    const bool rotational = model.coordinates[c].motionType == MotionType::Rotational;
    coordinates[c] = degrees && rotational ? number * M_PI / 180.0 : number;
  }
  ApplyCouplers(model, coordinates);
}
}
