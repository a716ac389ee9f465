// SPDX-License-Identifier: BSD-3-Clause
// A model's mesh files checked before a reader allocates what their headers claim: a file whose
// header promises more than the file holds (a binary STL claiming 2^31 - 1 triangles, a legacy
// .vtk claiming 2e9 points) is an error naming it, not an allocation that aborts the process.
#pragma once

#include <cstdint>
#include <string>

namespace md::osim
{
/// Throws InputError naming `path` when the counts in its header (by its extension: .stl,
/// .vtk, .vtp) ask for more values than a file of its size can hold. Other extensions, and .obj
/// (read line by line, allocating as it goes), pass unchecked.
void CheckMeshFileHeader(const std::string& path);

/// The same for a file's whole contents, `bytes`, named `path` in messages.
void CheckMeshFileHeader(const std::string& path, const std::string& bytes);
}
