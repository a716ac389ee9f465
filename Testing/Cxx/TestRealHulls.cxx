// Hulls and mean value coordinates of every real muscle: ../shared/data
// (MUSCLEDEFORMATION_DATA_DIR), lhdl_hip_r and vhf_right. Skipped, and
// reported as skipped by ctest, when the data is absent.
#include "MeanValueCoordinates.h"
#include "MeshChecks.h"
#include "ProgressiveHull.h"
#include "SurfaceRepair.h"

#include <vtkCellArray.h>
#include <vtkIdTypeArray.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkPolyDataReader.h>
#include <vtkSTLReader.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

namespace
{
std::string DataFile(const std::string& relative)
{
  const char* dir = std::getenv("MUSCLEDEFORMATION_DATA_DIR");
  const std::string path = std::string(dir ? dir : "") + "/" + relative;
  return std::ifstream(path).good() ? path : std::string();
}

md::TriangleMesh Read(const std::string& path)
{
  vtkSmartPointer<vtkPolyData> data;
  if (path.substr(path.size() - 4) == ".stl")
  {
    vtkNew<vtkSTLReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    data = reader->GetOutput();
  }
  else
  {
    vtkNew<vtkPolyDataReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    data = reader->GetOutput();
  }
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

md::Points UsedPoints(const md::TriangleMesh& mesh)
{
  std::vector<char> used(static_cast<size_t>(mesh.points.rows()), 0);
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      used[mesh.triangles(t, k)] = 1;
    }
  }
  md::Points out(std::count(used.begin(), used.end(), 1), 3);
  for (Eigen::Index i = 0, next = 0; i < mesh.points.rows(); ++i)
  {
    if (used[i])
    {
      out.row(next++) = mesh.points.row(i);
    }
  }
  return out;
}

class RealMuscleHull : public ::testing::TestWithParam<std::string>
{
};
}

TEST_P(RealMuscleHull, EnclosesEveryPointIsClosedManifoldAndReproducesPoints)
{
  const std::string path = DataFile(GetParam());
  if (path.empty())
  {
    GTEST_SKIP() << GetParam() << " not found: set MUSCLEDEFORMATION_DATA_DIR (default ../shared/data)";
  }
  const md::TriangleMesh muscle = Read(path);
  const md::Points points = UsedPoints(muscle);
  const double size = (points.colwise().maxCoeff() - points.colwise().minCoeff()).norm();
  md::RepairReport report;
  const md::TriangleMesh clean = md::RepairClosedSurface(muscle, report);
  const md::HullResult result = md::BuildProgressiveHull(clean, md::HullParameters{}, &report.pointsToEnclose);
  const md::TriangleMesh& hull = result.hull;
  std::cout << "[ measured ] " << GetParam() << ": " << hull.points.rows() << " hull points, volume ratio "
            << md::SignedVolume(hull.points, hull.triangles) / md::SignedVolume(clean.points, clean.triangles)
            << (report.Changed() ? ", repaired: " + report.Describe() : "") << "\n";
  EXPECT_TRUE(result.reachedTarget);
  EXPECT_TRUE(md::CheckEdges(hull.triangles).IsClosedOrientedManifold());
  EXPECT_EQ(md::CountSelfIntersections(hull), 0);
  EXPECT_EQ(md::CountOutside(hull, points, 1e-9 * size), 0) << "every muscle point tested";
  const md::WeightMatrix weights = md::MeanValueCoordinates(hull, points);
  EXPECT_LT((weights * hull.points - points).rowwise().norm().maxCoeff(), 1e-9 * size);
  EXPECT_LT((weights.rowwise().sum().array() - 1.0).abs().maxCoeff(), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(LhdlAndVhf, RealMuscleHull,
  ::testing::Values("lhdl_hip_r/gluteus_maximus_r.vtk", "lhdl_hip_r/gluteus_medius_r.vtk", "lhdl_hip_r/iliacus_r.vtk",
    "lhdl_hip_r/psoas_r.vtk", "vhf_right/VHF_Right_Muscle_GluteusMaximus_smooth.stl",
    "vhf_right/VHF_Right_Muscle_GluteusMedius_smooth.stl", "vhf_right/VHF_Right_Muscle_Illiacus_smooth.stl",
    "vhf_right/VHF_Right_Muscle_PsoasMajor_smooth.stl", "vhf_right/VHF_Right_Muscle_RectusFemoris_smooth.stl"),
  [](const ::testing::TestParamInfo<std::string>& info) {
    std::string name = info.param.substr(info.param.rfind('/') + 1);
    name = name.substr(0, name.find('.'));
    for (char& c : name)
    {
      c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    }
    return name;
  });
