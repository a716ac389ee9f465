// SPDX-License-Identifier: BSD-3-Clause
// Bone interpolation of the real LHDL femur through a 60 degree hip flexion.
// Reads ../shared/data/lhdl_hip_r (MUSCLEDEFORMATION_DATA_DIR); skipped, and
// reported as skipped by ctest, when the data is absent.
#include "FilterTestUtilities.h"
#include "RealData.h"

#include "Motion/BoneInterpolation.h"
#include "vtkBoneInterpolation.h"

#include <vtkFieldData.h>
#include <vtkPolyDataReader.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace
{
md::Points PointsOf(vtkPolyData* polyData)
{
  md::Points p(polyData->GetNumberOfPoints(), 3);
  for (vtkIdType i = 0; i < polyData->GetNumberOfPoints(); ++i)
  {
    polyData->GetPoint(i, p.row(i).data());
  }
  return p;
}

class RealFemur : public ::testing::Test
{
protected:
  void SetUp() override
  {
    const std::string femurFile = RealDataFile("lhdl_hip_r/femur_r.vtk");
    const std::string transforms = RealDataFile("lhdl_hip_r/femur_transforms.csv");
    if (femurFile.empty() || transforms.empty())
    {
      GTEST_SKIP() << "real data not found: set MUSCLEDEFORMATION_DATA_DIR to the folder holding "
                      "lhdl_hip_r (default ../shared/data)";
    }
    vtkNew<vtkPolyDataReader> reader;
    reader->SetFileName(femurFile.c_str());
    reader->Update();
    this->Rest = reader->GetOutput();
    ASSERT_EQ(this->Rest->GetNumberOfPoints(), 42502);
    // hip_flexion frame 35: 60 degrees of hip flexion.
    FemurFrame frame;
    ASSERT_TRUE(ReadFemurFrame(transforms, "hip_flexion", 35, frame));
    const Eigen::Matrix3d rotation = frame.rotation;
    const Eigen::Vector3d translation = frame.translation;
    this->Current = vtkSmartPointer<vtkPolyData>::New();
    this->Current->DeepCopy(this->Rest);
    vtkNew<vtkPoints> moved;
    moved->SetDataTypeToDouble();
    moved->SetNumberOfPoints(this->Rest->GetNumberOfPoints());
    for (vtkIdType i = 0; i < this->Rest->GetNumberOfPoints(); ++i)
    {
      Eigen::Vector3d x;
      this->Rest->GetPoint(i, x.data());
      const Eigen::Vector3d y = rotation * x + translation;
      moved->SetPoint(i, y.data());
    }
    this->Current->SetPoints(moved);
    this->Angle = Eigen::AngleAxisd(rotation).angle();
    this->Axis = Eigen::AngleAxisd(rotation).axis();
  }

  /// Output of vtkBoneInterpolation at one step.
  md::Points Step(int mode, int step, vtkFieldData* fieldData = nullptr)
  {
    vtkNew<vtkBoneInterpolation> interpolation;
    interpolation->SetInputData(0, this->Rest);
    interpolation->SetInputData(1, this->Current);
    interpolation->SetNumberOfSteps(Steps);
    interpolation->SetInterpolationMode(mode);
    interpolation->UpdateTimeStep(step);
    auto* output = vtkPolyData::SafeDownCast(interpolation->GetOutputDataObject(0));
    if (fieldData)
    {
      fieldData->DeepCopy(output->GetFieldData());
    }
    return PointsOf(output);
  }

  /// Every tenth point of the 42502: all 9 million pairs among them are checked.
  static std::vector<Eigen::Index> Sample(Eigen::Index n)
  {
    std::vector<Eigen::Index> sample;
    for (Eigen::Index i = 0; i < n; i += 10)
    {
      sample.push_back(i);
    }
    return sample;
  }

  static constexpr int Steps = 4;
  vtkSmartPointer<vtkPolyData> Rest;
  vtkSmartPointer<vtkPolyData> Current;
  double Angle = 0;
  Eigen::Vector3d Axis;
};
}

TEST_F(RealFemur, RigidKeepsEveryPairwiseDistanceAndEndsExactly)
{
  const md::Points rest = PointsOf(this->Rest);
  const md::Points current = PointsOf(this->Current);
  EXPECT_NEAR(this->Angle * 180 / M_PI, 60, 6) << "frame 35 should be about 60 degrees of rotation";
  const std::vector<Eigen::Index> sample = Sample(rest.rows());
  for (int step = 0; step <= Steps; ++step)
  {
    vtkNew<vtkFieldData> fieldData;
    const md::Points x = this->Step(vtkBoneInterpolation::RIGID, step, fieldData);
    if (step == 0)
    {
      EXPECT_TRUE((x.array() == rest.array()).all()) << "step 0 must be the rest pose exactly";
    }
    if (step == Steps)
    {
      EXPECT_TRUE((x.array() == current.array()).all()) << "step N must be the current pose exactly";
    }
    double worst = 0;
    for (size_t a = 0; a < sample.size(); ++a)
    {
      for (size_t b = a + 1; b < sample.size(); ++b)
      {
        const double d0 = (rest.row(sample[a]) - rest.row(sample[b])).norm();
        const double d = (x.row(sample[a]) - x.row(sample[b])).norm();
        worst = std::max(worst, std::abs(d - d0) / d0);
      }
    }
    // And every one of the 42502 points: the best rigid fit to the rest pose
    // leaves no residual, so no pairwise distance changed anywhere.
    const md::RigidFit fit = md::FitRigidTransform(rest, x);
    std::cout << "[ measured ] Rigid step " << step << "/" << Steps << ": largest relative change of "
              << sample.size() * (sample.size() - 1) / 2 << " pairwise distances " << worst
              << ", largest residual of a rigid fit to the rest pose " << fit.maxResidual << " mm\n";
    EXPECT_LT(worst, 1e-5) << "step " << step;
    EXPECT_LT(fit.maxResidual, 1e-6) << "step " << step;
    // The CSV's rotation is rounded to 9 decimals (not exactly orthonormal), so
    // the fitted angle agrees with its angle to about 1e-8 degrees.
    EXPECT_NEAR(fieldData->GetArray("RotationAngleDegrees")->GetTuple1(0), this->Angle * 180 / M_PI, 1e-6);
    EXPECT_LT(fieldData->GetArray("RigidFitMaxResidual")->GetTuple1(0), 1e-3);
  }
}

TEST_F(RealFemur, LinearShrinksTheBoneAsPredicted)
{
  const md::Points rest = PointsOf(this->Rest);
  const std::vector<Eigen::Index> sample = Sample(rest.rows());
  for (int step = 1; step < Steps; ++step)
  {
    const double s = static_cast<double>(step) / Steps;
    // A difference vector keeps its part along the rotation axis; its normal
    // part is scaled by f(s) = |(1 - s) + s e^{i angle}|.
    const double f = std::sqrt((1 - s) * (1 - s) + s * s + 2 * s * (1 - s) * std::cos(this->Angle));
    const md::Points x = this->Step(vtkBoneInterpolation::LINEAR, step);
    double smallestRatio = 1, worstPrediction = 0, restLength = 0, length = 0;
    for (size_t a = 0; a < sample.size(); ++a)
    {
      for (size_t b = a + 1; b < sample.size(); ++b)
      {
        const Eigen::Vector3d d0 = (rest.row(sample[a]) - rest.row(sample[b])).transpose();
        const double axial = d0.dot(this->Axis);
        const double predicted = std::sqrt(axial * axial + f * f * (d0.squaredNorm() - axial * axial));
        const double d = (x.row(sample[a]) - x.row(sample[b])).norm();
        worstPrediction = std::max(worstPrediction, std::abs(d - predicted) / predicted);
        smallestRatio = std::min(smallestRatio, d / d0.norm());
        if (d0.norm() > restLength)
        {
          restLength = d0.norm();
          length = d;
        }
      }
    }
    std::cout << "[ measured ] Linear step " << step << "/" << Steps << ": predicted shrink factor " << f << " ("
              << 100 * (1 - f) << " %), smallest measured distance ratio " << smallestRatio << ", femur length "
              << restLength << " -> " << length << " mm, largest deviation from the prediction " << worstPrediction
              << "\n";
    EXPECT_LT(worstPrediction, 1e-5);
    EXPECT_NEAR(smallestRatio, f, 0.01);
    EXPECT_LT(length, restLength * (1 - 0.5 * (1 - f)));
  }
  // The middle step of a 60 degree rotation: 1 - cos(30 deg), about 13 %.
  EXPECT_NEAR(1 - std::cos(this->Angle / 2), 0.134, 0.02);
}
