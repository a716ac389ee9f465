// SPDX-License-Identifier: BSD-3-Clause
// OpenSim motion and storage files (.mot, .sto): a table of coordinate values over time, and
// its mapping onto a model's coordinates.
#pragma once

#include "OpenSim/OpenSimModel.h"

#include <string>
#include <vector>

namespace md::osim
{
struct MotionTable
{
  std::string file;
  std::vector<std::string> labels; ///< the columns after time
  std::vector<double> times;
  std::vector<std::vector<double>> rows; ///< rows[frame][column]
  /// The file's own statement: inDegrees=yes/no, "Angles are in degrees.", or (OpenSim's rule)
  /// degrees for a .mot file without a version line (SIMM motion files), otherwise radians.
  bool inDegrees = false;
};

/// Reads a .mot/.sto file. Throws InputError naming the file, the line and the problem (no
/// header end, no time column, a row of the wrong length, a value that is not a finite number,
/// times that do not increase).
MotionTable ReadMotion(const std::string& fileName);

enum class AngleUnit
{
  FromFile,
  Degrees,
  Radians
};

struct MotionOptions
{
  AngleUnit angles = AngleUnit::FromFile;
  /// Skip columns that name no coordinate of the model (a full-body motion for a lower-body
  /// model) instead of failing, as OpenSim does; each is reported in the warnings.
  bool ignoreUnknownColumns = true;
};

/// The model's coordinates at every frame of a motion.
struct CoordinateTrajectory
{
  std::vector<double> times;
  std::vector<std::vector<double>> frames; ///< frames[k][coordinate], couplers applied
  std::vector<std::string> warnings;       ///< coordinates the motion lacks, columns skipped
};

/// Columns are matched to coordinates by name or by full path (/jointset/<joint>/<coordinate>/value);
/// other state columns (speeds, muscle states) are skipped. Coordinates the motion lacks keep their
/// default values. Angles in degrees are converted for rotational coordinates only (OpenSim's
/// rule). Couplers then set their dependent coordinates. Throws InputError for a column naming no
/// coordinate of the model (unless ignoreUnknownColumns).
CoordinateTrajectory MapMotion(const Model& model, const MotionTable& motion, const MotionOptions& options = {});

/// Parses "name=value name=value ..." (separators: space, comma, semicolon) into the model's
/// coordinates, starting from `coordinates`; rotational values in degrees when `degrees`.
/// Throws InputError for an unknown name or a value that is not a number.
void SetCoordinates(const Model& model, const std::string& assignments, bool degrees, std::vector<double>& coordinates);
}
