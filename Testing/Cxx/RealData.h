// SPDX-License-Identifier: BSD-3-Clause
// Finding and reading the real data sets (../shared/data) for tests and benchmarks.
#pragma once

#include "Common/MeshTypes.h"
#include "MotionCases.h"

#include <vtkCellArray.h>
#include <vtkIdTypeArray.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkPolyDataReader.h>
#include <vtkSTLReader.h>
#include <vtkTriangleFilter.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

/// `folder`/`relative` (folder: the argument, else $MUSCLEDEFORMATION_DATA_DIR),
/// or "" when there is no such file.
inline std::string RealDataFile(const std::string& relative, const std::string& folder = "")
{
  const char* fromEnvironment = std::getenv("MUSCLEDEFORMATION_DATA_DIR");
  const std::string base = !folder.empty() ? folder : (fromEnvironment ? fromEnvironment : "");
  const std::string path = base + "/" + relative;
  return std::ifstream(path).good() ? path : std::string();
}

/// The triangles of a legacy .vtk or an .stl surface (polygons and strips triangulated).
inline md::TriangleMesh ReadSurface(const std::string& path)
{
  vtkNew<vtkTriangleFilter> triangles;
  if (path.size() > 4 && path.substr(path.size() - 4) == ".stl")
  {
    vtkNew<vtkSTLReader> reader;
    reader->SetFileName(path.c_str());
    triangles->SetInputConnection(reader->GetOutputPort());
  }
  else
  {
    vtkNew<vtkPolyDataReader> reader;
    reader->SetFileName(path.c_str());
    triangles->SetInputConnection(reader->GetOutputPort());
  }
  triangles->PassVertsOff();
  triangles->PassLinesOff();
  triangles->Update();
  vtkPolyData* data = triangles->GetOutput();
  md::TriangleMesh mesh;
  mesh.points.resize(data->GetNumberOfPoints(), 3);
  for (vtkIdType i = 0; i < data->GetNumberOfPoints(); ++i)
  {
    data->GetPoint(i, mesh.points.row(i).data());
  }
  vtkNew<vtkIdTypeArray> connectivity;
  connectivity->DeepCopy(data->GetPolys()->GetConnectivityArray());
  mesh.triangles.resize(data->GetNumberOfPolys(), 3);
  std::copy(connectivity->GetPointer(0), connectivity->GetPointer(0) + mesh.triangles.size(), mesh.triangles.data());
  return mesh;
}

/// The comma-separated fields of one line.
inline std::vector<std::string> SplitCsvLine(const std::string& line)
{
  std::vector<std::string> fields;
  std::stringstream ss(line);
  for (std::string field; std::getline(ss, field, ',');)
  {
    fields.push_back(field);
  }
  if (!line.empty() && line.back() == ',')
  {
    fields.emplace_back();
  }
  return fields;
}

/// One frame of lhdl_hip_r/femur_transforms.csv: x_CP = rotation x_RP + translation for the femur.
struct FemurFrame
{
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  double hipFlexion = 0;
  double hipAdduction = 0;
  md::Points Apply(const md::Points& p) const
  {
    md::Points out = p * this->rotation.transpose();
    out.rowwise() += this->translation.transpose();
    return out;
  }
};

/// Reads frame `frame` of `motion` from femur_transforms.csv; false when absent.
inline bool ReadFemurFrame(const std::string& csv, const std::string& motion, int frame, FemurFrame& out)
{
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line); // header
  while (std::getline(in, line))
  {
    const std::vector<std::string> fields = SplitCsvLine(line);
    if (fields.size() >= 18 && fields[0] == motion && std::stoi(fields[1]) == frame)
    {
      out.hipFlexion = std::stod(fields[3]);
      out.hipAdduction = std::stod(fields[4]);
      for (int k = 0; k < 9; ++k)
      {
        out.rotation(k / 3, k % 3) = std::stod(fields[6 + k]);
      }
      out.translation << std::stod(fields[15]), std::stod(fields[16]), std::stod(fields[17]);
      return true;
    }
  }
  return false;
}

/// The LHDL right hip (lhdl_hip_r) in the rest pose and one frame of a motion:
/// the pelvis bones stay, the femur and the path points fixed to it move by
/// the frame's transform; a conditional path point exists only while the hip
/// flexion is inside its range (as Examples/lhdl.py).
struct LhdlCase
{
  struct Muscle
  {
    std::string name;
    md::TriangleMesh surface;
    std::vector<md::Points> linesRest, linesCurrent; ///< raw action lines (not matched)
  };
  std::vector<Muscle> muscles;
  std::vector<std::string> boneNames;
  std::vector<md::TriangleMesh> bonesRest, bonesCurrent;
  FemurFrame frame;
};

/// Loads the case, or returns false when the data is absent.
inline bool LoadLhdlCase(const std::string& motion, int frameIndex, LhdlCase& out, const std::string& folder = "")
{
  const std::string transforms = RealDataFile("lhdl_hip_r/femur_transforms.csv", folder);
  const std::string lines = RealDataFile("lhdl_hip_r/action_lines_rp_mm.csv", folder);
  FemurFrame rest;
  if (transforms.empty() || lines.empty() || !ReadFemurFrame(transforms, motion, frameIndex, out.frame) ||
    !ReadFemurFrame(transforms, "scan_pose_RP", 0, rest))
  {
    return false;
  }
  for (const char* bone : { "iliac_r", "sacrum", "femur_r" })
  {
    const std::string path = RealDataFile(std::string("lhdl_hip_r/") + bone + ".vtk", folder);
    if (path.empty())
    {
      return false;
    }
    out.boneNames.emplace_back(bone);
    out.bonesRest.push_back(ReadSurface(path));
    md::TriangleMesh current = out.bonesRest.back();
    if (std::string(bone) == "femur_r")
    {
      current.points = out.frame.Apply(current.points);
    }
    out.bonesCurrent.push_back(current);
  }
  // Path points by path name, in order, in both poses.
  std::map<std::string, std::map<int, std::pair<Eigen::RowVector3d, Eigen::RowVector3d>>> paths;
  std::map<std::string, std::map<int, bool>> activeRest, activeCurrent;
  {
    std::ifstream in(lines);
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line))
    {
      const std::vector<std::string> f = SplitCsvLine(line);
      if (f.size() < 8)
      {
        continue;
      }
      const Eigen::RowVector3d p(std::stod(f[5]), std::stod(f[6]), std::stod(f[7]));
      const bool onFemur = f[4] == "femur_r";
      md::Points single(1, 3);
      single.row(0) = p;
      const Eigen::RowVector3d moved = onFemur ? Eigen::RowVector3d(out.frame.Apply(single).row(0)) : p;
      const int order = std::stoi(f[1]);
      paths[f[0]][order] = { p, moved };
      bool inRest = true, inCurrent = true;
      if (f[3] == "ConditionalPathPoint" && f.size() >= 11)
      {
        const double low = std::stod(f[9]), high = std::stod(f[10]);
        inRest = low <= rest.hipFlexion && rest.hipFlexion <= high;
        inCurrent = low <= out.frame.hipFlexion && out.frame.hipFlexion <= high;
      }
      activeRest[f[0]][order] = inRest;
      activeCurrent[f[0]][order] = inCurrent;
    }
  }
  const std::map<std::string, std::vector<std::string>> actionLines = {
    { "gluteus_maximus_r", { "glut_max1_r", "glut_max2_r", "glut_max3_r" } },
    { "gluteus_medius_r", { "glut_med1_r", "glut_med2_r", "glut_med3_r" } },
    { "iliacus_r", { "iliacus_r" } },
    { "psoas_r", { "psoas_r" } },
  };
  for (const char* name : { "gluteus_maximus_r", "gluteus_medius_r", "iliacus_r", "psoas_r" })
  {
    const std::string path = RealDataFile(std::string("lhdl_hip_r/") + name + ".vtk", folder);
    if (path.empty())
    {
      return false;
    }
    LhdlCase::Muscle muscle;
    muscle.name = name;
    muscle.surface = ReadSurface(path);
    for (const std::string& pathName : actionLines.at(name))
    {
      std::vector<Eigen::RowVector3d> restPoints, currentPoints;
      for (const auto& [order, pair] : paths[pathName])
      {
        if (activeRest[pathName][order])
        {
          restPoints.push_back(pair.first);
        }
        if (activeCurrent[pathName][order])
        {
          currentPoints.push_back(pair.second);
        }
      }
      md::Points r(static_cast<Eigen::Index>(restPoints.size()), 3),
        c(static_cast<Eigen::Index>(currentPoints.size()), 3);
      for (size_t k = 0; k < restPoints.size(); ++k)
      {
        r.row(static_cast<Eigen::Index>(k)) = restPoints[k];
      }
      for (size_t k = 0; k < currentPoints.size(); ++k)
      {
        c.row(static_cast<Eigen::Index>(k)) = currentPoints[k];
      }
      muscle.linesRest.push_back(r);
      muscle.linesCurrent.push_back(c);
    }
    out.muscles.push_back(std::move(muscle));
  }
  return true;
}

/// The LHDL case as inputs of the interpolation method. False when the data is absent.
inline bool LhdlMotion(const std::string& motion, int frame, MotionCase& c, const std::string& folder = "")
{
  LhdlCase lhdl;
  if (!LoadLhdlCase(motion, frame, lhdl, folder))
  {
    return false;
  }
  c.name = "LHDL " + motion + " frame " + std::to_string(frame);
  for (const LhdlCase::Muscle& muscle : lhdl.muscles)
  {
    c.muscles.push_back({ muscle.name, muscle.surface, MatchLines(muscle.linesRest, muscle.linesCurrent) });
  }
  for (size_t b = 0; b < lhdl.boneNames.size(); ++b)
  {
    c.bones.push_back({ lhdl.boneNames[b], lhdl.bonesRest[b], lhdl.bonesCurrent[b].points });
  }
  return true;
}
