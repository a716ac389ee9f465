// SPDX-License-Identifier: BSD-3-Clause
// Mesh files whose headers claim more than the file holds are refused before a reader
// allocates what they claim.
#include "OpenSim/MeshFileCheck.h"
#include "OpenSimTestModels.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>

using md::osim::CheckMeshFileHeader;
using md::osim::test::ExpectInputError;

namespace
{
std::string BinaryStl(std::uint32_t claimed, size_t triangles)
{
  std::string bytes(80, '\0');
  char count[4];
  std::memcpy(count, &claimed, 4);
  bytes.append(count, 4);
  for (size_t t = 0; t < triangles; ++t)
  {
    for (int b = 0; b < 50; ++b)
    {
      bytes.push_back(static_cast<char>(0x80 + (b * 7 + static_cast<int>(t)) % 100)); // binary-looking data
    }
  }
  return bytes;
}

const char* const kTetrahedron = "# vtk DataFile Version 3.0\ntetrahedron\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n"
                                 "0 0 0 1 0 0 0 1 0 0 0 1\nPOLYGONS 4 16\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
}

TEST(MeshFileCheck, AFileThatHoldsWhatItsHeaderClaimsPasses)
{
  EXPECT_NO_THROW(CheckMeshFileHeader("ok.stl", BinaryStl(10, 10)));
  EXPECT_NO_THROW(CheckMeshFileHeader("ok.stl", "solid x\nfacet normal 0 0 1\nendsolid x\n")); // ASCII
  EXPECT_NO_THROW(CheckMeshFileHeader("ok.vtk", kTetrahedron));
  EXPECT_NO_THROW(CheckMeshFileHeader("ok.vtp",
    "<VTKFile type=\"PolyData\"><PolyData><Piece NumberOfPoints=\"4\" "
    "NumberOfPolys=\"4\"></Piece></PolyData></VTKFile>"));
  EXPECT_NO_THROW(CheckMeshFileHeader("any.obj", std::string(10, '\xff')));
}

TEST(MeshFileCheck, AHeaderThatLiesAboutItsSizeIsNamed)
{
  // 584 bytes claiming 2^31 - 1 triangles (VTK's STL reader aborted allocating them).
  std::string e = ExpectInputError([] { CheckMeshFileHeader("liar.stl", BinaryStl(2147483647u, 10)); });
  EXPECT_NE(e.find("mesh file 'liar.stl'"), std::string::npos) << e;
  EXPECT_NE(e.find("claims 2147483647 triangles (107374182434 bytes) but the file has 584 bytes"), std::string::npos)
    << e;
  e = ExpectInputError([] { CheckMeshFileHeader("short.stl", std::string(40, '\x90')); });
  EXPECT_NE(e.find("shorter than its 84-byte header"), std::string::npos) << e;
  std::string vtk = kTetrahedron;
  vtk.replace(vtk.find("POINTS 4"), 8, "POINTS 2000000000");
  e = ExpectInputError([&] { CheckMeshFileHeader("liar.vtk", vtk); });
  EXPECT_NE(e.find("line 5 ('POINTS 2000000000 float') asks for 6000000000 values"), std::string::npos) << e;
  vtk = kTetrahedron;
  vtk.replace(vtk.find("POLYGONS 4 16"), 13, "POLYGONS 4 99999999999999999999");
  e = ExpectInputError([&] { CheckMeshFileHeader("cells.vtk", vtk); });
  EXPECT_NE(e.find("cells.vtk"), std::string::npos) << e;
  e = ExpectInputError([] {
    CheckMeshFileHeader(
      "liar.vtp", "<VTKFile><PolyData><Piece NumberOfPoints=\"2000000000\"></Piece></PolyData></VTKFile>");
  });
  EXPECT_NE(e.find("NumberOfPoints=\"2000000000\" is more than a file of"), std::string::npos) << e;
  e = ExpectInputError([] { CheckMeshFileHeader("/nonexistent/x.stl"); });
  EXPECT_NE(e.find("cannot be opened"), std::string::npos) << e;
}
