// SPDX-License-Identifier: BSD-3-Clause
// Names as users give them: case and file extensions aside.
#pragma once

#include <algorithm>
#include <cctype>
#include <string>

namespace md
{
inline std::string Lower(std::string text)
{
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

/// The name without a trailing file extension ("femur_r.vtk" -> "femur_r"): one to four letters
/// after the last dot, which is not the first character.
inline std::string WithoutExtension(const std::string& name)
{
  const size_t dot = name.rfind('.');
  if (dot == std::string::npos || dot == 0)
  {
    return name;
  }
  const std::string extension = name.substr(dot + 1);
  const bool looksLikeExtension = !extension.empty() && extension.size() <= 4 &&
    std::all_of(extension.begin(), extension.end(), [](unsigned char c) { return std::isalpha(c); });
  return looksLikeExtension ? name.substr(0, dot) : name;
}
}
