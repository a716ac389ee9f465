// SPDX-License-Identifier: BSD-3-Clause
#include "vtkOpenSimModelReader.h"

#include "MDBlocks.h"
#include "MDConvert.h"
#include "MDReport.h"
#include "MDTime.h"
#include "OpenSim/MeshFileCheck.h"
#include "OpenSim/MomentArms.h"
#include "OpenSim/OpenSimKinematics.h"
#include "OpenSim/OpenSimMotion.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCompositeDataSet.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkOBJReader.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataReader.h>
#include <vtkSTLReader.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkStringArray.h>
#include <vtkTable.h>
#include <vtkXMLPolyDataReader.h>
#include <vtksys/SystemTools.hxx>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

vtkStandardNewMacro(vtkOpenSimModelReader);

namespace
{
using md::Compose;
using md::Inverse;
using md::RigidTransform;
namespace osim = md::osim;

/// The motion from pose `from` to pose `to` of a body: exactly the identity where they are the
/// same (a body that does not move does not move by rounding).
RigidTransform Motion(const RigidTransform& to, const RigidTransform& from)
{
  if (to.rotation == from.rotation && to.translation == from.translation)
  {
    return RigidTransform();
  }
  return md::Compose(to, md::Inverse(from));
}

std::string Text(const char* s)
{
  return s ? std::string(s) : std::string();
}

/// A body's meshes in the body's frame, in model units.
struct BodyMesh
{
  md::Points points;
  vtkSmartPointer<vtkCellArray> polys;
};

template<typename Reader>
vtkSmartPointer<vtkPolyData> ReadWith(const std::string& path)
{
  vtkNew<Reader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  return reader->GetOutput();
}

/// A mesh file (.vtp, .stl, .obj, .vtk) of body `body`, its header checked before VTK allocates
/// what it claims, its cells and coordinates after. Null for another extension; throws
/// md::InputError naming the file for one that is damaged or holds no points.
vtkSmartPointer<vtkPolyData> ReadMeshFile(const std::string& path, const std::string& body)
{
  const std::string extension = vtksys::SystemTools::LowerCase(vtksys::SystemTools::GetFilenameLastExtension(path));
  if (extension != ".vtp" && extension != ".stl" && extension != ".obj" && extension != ".vtk")
  {
    return nullptr;
  }
  md::osim::CheckMeshFileHeader(path);
  vtkSmartPointer<vtkPolyData> mesh = extension == ".vtp" ? ReadWith<vtkXMLPolyDataReader>(path)
    : extension == ".stl"                                 ? ReadWith<vtkSTLReader>(path)
    : extension == ".obj"                                 ? ReadWith<vtkOBJReader>(path)
                                                          : ReadWith<vtkPolyDataReader>(path);
  const std::string label = "mesh file '" + path + "' (body '" + body + "')";
  if (!mesh || !mesh->GetPoints() || mesh->GetNumberOfPoints() == 0)
  {
    throw md::InputError(label + " holds no points: it is empty, damaged or not a " + extension + " file");
  }
  std::string error;
  if (!mdvtk::CheckPolyData(mesh, label, error))
  {
    throw md::InputError(error);
  }
  return mesh;
}

/// Whether `path` lies inside `folder` (both as the file system resolves them).
bool IsInside(const std::string& path, const std::string& folder)
{
  const std::string real = vtksys::SystemTools::GetRealPath(path);
  const std::string base = vtksys::SystemTools::GetRealPath(folder.empty() ? "." : folder);
  return real.size() > base.size() && real.compare(0, base.size(), base) == 0 && real[base.size()] == '/';
}

/// A body's meshes (the files of its geometry, found in `folders`) as one mesh in the body's
/// frame; the files not found are added to `missing`, those found outside every folder (a name
/// with '../' or an absolute one) to `outside`.
BodyMesh ReadBodyMesh(
  const osim::Body& body, const std::vector<std::string>& folders, std::string& missing, std::string& outside)
{
  std::vector<md::Points> parts;
  vtkNew<vtkCellArray> polys;
  vtkIdType offset = 0;
  for (const osim::Geometry& g : body.geometry)
  {
    // Models made on Windows name files with backslashes (".\\geometry\\x.vtp"): try the
    // name as given and its last part, in every folder.
    std::string relative = g.file;
    std::replace(relative.begin(), relative.end(), '\\', '/');
    const std::string bare = vtksys::SystemTools::GetFilenameName(relative);
    vtkSmartPointer<vtkPolyData> mesh;
    std::string found;
    for (const std::string& f : folders)
    {
      for (const std::string& name : { relative, bare })
      {
        const std::string path = vtksys::SystemTools::FileIsFullPath(name) ? name : f + "/" + name;
        if (!mesh && vtksys::SystemTools::FileExists(path, true))
        {
          mesh = ReadMeshFile(path, body.name);
          found = path;
        }
      }
    }
    if (!mesh)
    {
      missing += (missing.empty() ? "" : ", ") + g.file + " (" + body.name + ")";
      continue;
    }
    if (std::none_of(folders.begin(), folders.end(), [&](const std::string& f) { return IsInside(found, f); }))
    {
      outside += (outside.empty() ? "" : ", ") + g.file + " (" + body.name + ") at '" +
        vtksys::SystemTools::GetRealPath(found) + "'";
    }
    md::Points local = mdvtk::ToPoints(mesh->GetPoints());
    local = local * g.scale.asDiagonal();
    parts.push_back(g.placement.Apply(local));
    vtkCellArray* cells = mesh->GetPolys();
    const vtkIdType* ids = nullptr;
    vtkIdType count = 0;
    std::vector<vtkIdType> shifted;
    for (cells->InitTraversal(); cells->GetNextCell(count, ids);)
    {
      shifted.assign(ids, ids + count);
      for (vtkIdType& id : shifted)
      {
        id += offset;
      }
      polys->InsertNextCell(count, shifted.data());
    }
    offset += local.rows();
  }
  BodyMesh target;
  target.points.resize(offset, 3);
  vtkIdType row = 0;
  for (const md::Points& p : parts)
  {
    target.points.middleRows(row, p.rows()) = p;
    row += p.rows();
  }
  target.polys = polys;
  return target;
}

/// Throws md::InputError naming `what` when `points` or `motion` hold a value that is not finite
/// or is beyond what the filters downstream take (1e100): a model or motion whose values are
/// finite but huge, built on one another.
void CheckPlaced(const md::Points& points, const RigidTransform& motion, const std::string& what)
{
  constexpr double kLargest = 1e100;
  const bool finite = points.allFinite() && (points.size() == 0 || points.cwiseAbs().maxCoeff() <= kLargest) &&
    motion.rotation.allFinite() && motion.translation.allFinite() &&
    motion.translation.cwiseAbs().maxCoeff() <= kLargest;
  if (!finite)
  {
    throw md::InputError(what +
      " comes out at non-finite or huge coordinates: the model's offsets, scale factors or functions, or the "
      "motion's values, are too large");
  }
}

/// How the reader's motions are read (AngleUnit, IgnoreUnknownColumns).
osim::MotionOptions OptionsOf(int angleUnit, bool ignoreUnknownColumns)
{
  osim::MotionOptions options;
  options.angles = angleUnit == vtkOpenSimModelReader::ANGLES_IN_DEGREES ? osim::AngleUnit::Degrees
    : angleUnit == vtkOpenSimModelReader::ANGLES_IN_RADIANS              ? osim::AngleUnit::Radians
                                                                         : osim::AngleUnit::FromFile;
  options.ignoreUnknownColumns = ignoreUnknownColumns;
  return options;
}

/// The paths of `model` with a conditional point that comes or goes over `trajectory`, each with
/// the first time it does ("psoas_r (at 0.26 s), ..."); empty when none does.
std::string JumpingPaths(const osim::Model& model, const osim::CoordinateTrajectory& trajectory)
{
  std::ostringstream said;
  for (const osim::Path& path : model.paths)
  {
    for (const osim::PathPoint& point : path.points)
    {
      if (point.kind != osim::PathPointKind::Conditional || trajectory.frames.empty())
      {
        continue;
      }
      const bool first = osim::BeyondRange(point, trajectory.frames.front()[point.coordinate]) > 0.0;
      const auto change = std::find_if(trajectory.frames.begin(), trajectory.frames.end(),
        [&](const std::vector<double>& q) { return (osim::BeyondRange(point, q[point.coordinate]) > 0.0) != first; });
      if (change != trajectory.frames.end())
      {
        said << (said.tellp() > 0 ? ", " : "") << path.name << " (at "
             << trajectory.times[static_cast<size_t>(change - trajectory.frames.begin())] << " s)";
        break;
      }
    }
  }
  return said.str();
}

vtkSmartPointer<vtkStringArray> Strings(const char* name)
{
  auto array = vtkSmartPointer<vtkStringArray>::New();
  array->SetName(name);
  return array;
}
}

struct vtkOpenSimModelReader::Internals
{
  std::string modelKey, motionKey, poseKey;
  osim::Model model;
  bool haveModel = false;
  osim::CoordinateTrajectory trajectory; ///< empty without a motion
  std::vector<BodyMesh> meshes;          ///< per body
  std::vector<md::TriangleMesh> wraps;   ///< per wrap object, in its body's frame
  std::vector<double> rest;
  std::vector<RigidTransform> restPoses;
  RigidTransform toOutput;     ///< ground -> the reference body's rest frame, lengths not yet scaled
  int referenceBody = -1;      ///< the reference body's index; -1: ground
  vtkNew<vtkTable> momentArms; ///< output MOMENT_ARMS as last computed
  std::string momentArmsKey;   ///< what it was computed from
};

struct vtkOpenSimModelReader::SteppedPose
{
  std::string name; ///< "<coordinate>+" or "<coordinate>-"
  std::vector<double> coordinates;
  std::vector<RigidTransform> bodyPoses;
};

std::vector<vtkOpenSimModelReader::SteppedPose> vtkOpenSimModelReader::SteppedPoses(const std::vector<double>& q) const
{
  const Internals& in = *this->Internal;
  std::vector<SteppedPose> stepped;
  if (this->MomentArmStep <= 0.0 || !this->PlayMotion || in.trajectory.times.empty())
  {
    return stepped;
  }
  for (int c : osim::MovingCoordinates(in.trajectory))
  {
    const osim::Coordinate& coordinate = in.model.coordinates[c];
    if (coordinate.motionType != osim::MotionType::Rotational)
    {
      continue;
    }
    for (const double sign : { 1.0, -1.0 })
    {
      SteppedPose pose;
      pose.name = coordinate.name + (sign > 0 ? "+" : "-");
      pose.coordinates = osim::MovedCoordinate(in.model, q, c, sign * this->MomentArmStep * M_PI / 180.0);
      pose.bodyPoses = osim::BodyPoses(in.model, pose.coordinates);
      stepped.push_back(std::move(pose));
    }
  }
  return stepped;
}

vtkOpenSimModelReader::vtkOpenSimModelReader()
  : Internal(new Internals)
{
  this->SetNumberOfInputPorts(0);
  this->SetNumberOfOutputPorts(7);
}

vtkOpenSimModelReader::~vtkOpenSimModelReader()
{
  this->SetFileName(nullptr);
  this->SetMotionFileName(nullptr);
  this->SetGeometrySearchPath(nullptr);
  this->SetRestPoseCoordinates(nullptr);
  this->SetRestPoseFileName(nullptr);
  this->SetReferenceBody(nullptr);
}

int vtkOpenSimModelReader::FillOutputPortInformation(int port, vtkInformation* info)
{
  info->Set(vtkDataObject::DATA_TYPE_NAME(),
    port == BODY_TRANSFORMS || port == MOMENT_ARMS ? "vtkTable" : "vtkMultiBlockDataSet");
  return 1;
}

int vtkOpenSimModelReader::GetNumberOfTimeSteps()
{
  return static_cast<int>(this->Internal->trajectory.times.size());
}

double vtkOpenSimModelReader::GetTimeStep(int index)
{
  const std::vector<double>& times = this->Internal->trajectory.times;
  return index >= 0 && index < static_cast<int>(times.size()) ? times[index] : 0.0;
}

bool vtkOpenSimModelReader::Load()
{
  const std::string fileName = Text(this->FileName);
  if (fileName.empty())
  {
    vtkErrorMacro(<< "no FileName: give the OpenSim model (.osim) to read");
    return false;
  }
  std::vector<std::string> warnings;
  int result = 1;
  if (!mdvtk::CallCore(
        this, "",
        [&] {
          this->LoadModel(fileName, warnings);
          this->LoadMotion(warnings);
          this->LoadRestPose();
        },
        result))
  {
    return false;
  }
  for (const std::string& w : warnings)
  {
    vtkWarningMacro(<< "OpenSim model '" << fileName << "': " << w);
  }
  return true;
}

void vtkOpenSimModelReader::LoadModel(const std::string& fileName, std::vector<std::string>& warnings)
{
  Internals& in = *this->Internal;
  const std::string modelKey =
    fileName + "|" + Text(this->GeometrySearchPath) + "|" + std::to_string(this->LoadGeometry);
  if (in.haveModel && modelKey == in.modelKey)
  {
    return;
  }
  in.haveModel = false;
  in.motionKey.clear();
  in.poseKey.clear();
  in.model = osim::ReadModel(fileName);
  ++this->ModelReadCount;
  warnings = in.model.warnings;
  // Meshes: beside the model, in its Geometry/ and geometry/ folders, then the search path.
  const std::string folder = vtksys::SystemTools::GetFilenamePath(fileName);
  std::vector<std::string> folders = { folder, folder + "/Geometry", folder + "/geometry" };
  std::stringstream search(Text(this->GeometrySearchPath));
  std::string entry;
  while (std::getline(search, entry, ';'))
  {
    if (!entry.empty())
    {
      folders.push_back(entry);
    }
  }
  in.meshes.assign(in.model.bodies.size(), BodyMesh());
  std::string missing, outside;
  for (size_t b = 0; b < in.model.bodies.size() && this->LoadGeometry; ++b)
  {
    in.meshes[b] = ReadBodyMesh(in.model.bodies[b], folders, missing, outside);
  }
  if (!missing.empty())
  {
    warnings.push_back("mesh files not found (the bodies still move): " + missing);
  }
  if (!outside.empty())
  {
    warnings.push_back("mesh files read from outside the model's folder, its Geometry folders and "
                       "GeometrySearchPath: " +
      outside);
  }
  in.wraps.clear();
  for (const osim::WrapObject& w : in.model.wrapObjects)
  {
    in.wraps.push_back(osim::WrapSurface(w));
  }
  in.modelKey = modelKey;
  in.haveModel = true;
}

void vtkOpenSimModelReader::LoadMotion(std::vector<std::string>& warnings)
{
  Internals& in = *this->Internal;
  const std::string motionKey = Text(this->MotionFileName) + "|" + std::to_string(this->AngleUnit) + "|" +
    std::to_string(this->IgnoreUnknownColumns);
  if (motionKey == in.motionKey)
  {
    return;
  }
  in.trajectory = osim::CoordinateTrajectory();
  in.motionKey.clear();
  if (!Text(this->MotionFileName).empty())
  {
    in.trajectory = osim::MapMotion(
      in.model, osim::ReadMotion(this->MotionFileName), OptionsOf(this->AngleUnit, this->IgnoreUnknownColumns));
    warnings.insert(warnings.end(), in.trajectory.warnings.begin(), in.trajectory.warnings.end());
    if (const std::string jumping = JumpingPaths(in.model, in.trajectory); !jumping.empty())
    {
      warnings.push_back("the motion makes these paths gain or lose a conditional path point, where they jump "
                         "(and muscles deformed along them with them): " +
        jumping + "; ConditionalPointFade (degrees) spreads each jump over that much of its coordinate");
    }
  }
  in.motionKey = motionKey;
}

void vtkOpenSimModelReader::LoadRestPose()
{
  Internals& in = *this->Internal;
  const std::string poseKey = Text(this->RestPoseFileName) + "|" + Text(this->RestPoseCoordinates) + "|" +
    Text(this->ReferenceBody) + "|" + in.motionKey;
  if (poseKey == in.poseKey)
  {
    return;
  }
  in.poseKey.clear();
  in.rest = osim::DefaultCoordinates(in.model);
  if (!Text(this->RestPoseFileName).empty())
  {
    // The first row of a motion file (a static trial in the scan pose), read as the motion is.
    const osim::CoordinateTrajectory pose = osim::MapMotion(
      in.model, osim::ReadMotion(this->RestPoseFileName), OptionsOf(this->AngleUnit, this->IgnoreUnknownColumns));
    in.rest = pose.frames.front();
  }
  osim::SetCoordinates(in.model, Text(this->RestPoseCoordinates), true, in.rest);
  in.restPoses = osim::BodyPoses(in.model, in.rest);
  in.toOutput = RigidTransform();
  in.referenceBody = -1;
  const std::string reference = Text(this->ReferenceBody);
  if (!reference.empty())
  {
    const int body = in.model.FindBody(reference);
    if (body < 0)
    {
      throw md::InputError("ReferenceBody '" + reference + "' is not a body of the model");
    }
    in.toOutput = Inverse(in.restPoses[body]);
    in.referenceBody = body;
  }
  in.poseKey = poseKey;
}

int vtkOpenSimModelReader::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  if (!this->Load())
  {
    return 0;
  }
  mdvtk::AdvertiseTimes(outputVector, this->PlayMotion ? this->Internal->trajectory.times : std::vector<double>{});
  return 1;
}

int vtkOpenSimModelReader::RequestData(
  vtkInformation* request, vtkInformationVector**, vtkInformationVector* outputVector)
{
  if (!this->Load())
  {
    return 0;
  }
  const Internals& in = *this->Internal;
  // The frame nearest the requested time.
  std::vector<double> q = in.rest;
  double time = 0.0;
  if (!in.trajectory.times.empty())
  {
    // The time asked for on the port whose request this is (the other ports keep older times).
    int port = request->Has(vtkDemandDrivenPipeline::FROM_OUTPUT_PORT())
      ? request->Get(vtkDemandDrivenPipeline::FROM_OUTPUT_PORT())
      : 0;
    port = port < 0 || port >= this->GetNumberOfOutputPorts() ? 0 : port;
    vtkInformation* info = outputVector->GetInformationObject(port);
    double requested = this->CurrentPoseTime;
    const bool asked = this->PlayMotion && info->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
    if (asked)
    {
      requested = info->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
    }
    const int k = mdvtk::NearestTime(in.trajectory.times, requested);
    q = in.trajectory.frames[k];
    time = in.trajectory.times[k];
    const double first = in.trajectory.times.front(), last = in.trajectory.times.back();
    const double slack = 1e-9 * (std::abs(first) + std::abs(last) + 1.0);
    // The default CurrentPoseTime, 0, stands for the first frame (a motion may start later).
    const bool given = asked || this->CurrentPoseTime != kDefaultCurrentPoseTime;
    if (given && (requested < first - slack || requested > last + slack))
    {
      vtkWarningMacro(<< (asked ? "the time asked for, " : "CurrentPoseTime ") << requested << (asked ? "," : "")
                      << " lies outside the motion's times (" << first << " to " << last
                      << "): the nearest frame, at time " << time << ", is shown");
    }
  }
  int result = 1;
  std::ostringstream when;
  if (in.trajectory.times.empty())
  {
    when << "at the rest pose";
  }
  else
  {
    when << "at time " << time;
  }
  if (!mdvtk::CallCore(
        this, "",
        [&] {
          const std::vector<RigidTransform> poses = osim::BodyPoses(in.model, q);
          const std::vector<SteppedPose> stepped = this->SteppedPoses(q);
          this->WriteBodies(poses, vtkMultiBlockDataSet::GetData(outputVector, BODIES), when.str());
          this->WriteBodies(in.restPoses, vtkMultiBlockDataSet::GetData(outputVector, BODIES_REST), "at the rest pose");
          this->WritePaths(q, poses, vtkMultiBlockDataSet::GetData(outputVector, MUSCLE_PATHS), when.str(), stepped);
          this->WritePaths(
            in.rest, in.restPoses, vtkMultiBlockDataSet::GetData(outputVector, MUSCLE_PATHS_REST), "at the rest pose");
          for (int port : { BODIES, BODIES_REST })
          {
            mdvtk::MarkRoles(vtkMultiBlockDataSet::GetData(outputVector, port), mdvtk::Role::Bone);
          }
          for (int port : { MUSCLE_PATHS, MUSCLE_PATHS_REST })
          {
            mdvtk::MarkRoles(vtkMultiBlockDataSet::GetData(outputVector, port), mdvtk::Role::ActionLine);
          }
          this->WriteWrapsAndTransforms(poses, q, time, stepped, outputVector);
          this->WriteMomentArms(vtkTable::GetData(outputVector, MOMENT_ARMS));
        },
        result))
  {
    mdvtk::ClearOutputs(outputVector);
    return result;
  }
  if (this->PlayMotion && !in.trajectory.times.empty())
  {
    mdvtk::SetDataTime(outputVector, time);
  }
  return 1;
}

void vtkOpenSimModelReader::WriteWrapsAndTransforms(const std::vector<md::RigidTransform>& poses,
  const std::vector<double>& q, double time, const std::vector<SteppedPose>& stepped,
  vtkInformationVector* outputVector) const
{
  const Internals& in = *this->Internal;
  vtkMultiBlockDataSet* wraps = vtkMultiBlockDataSet::GetData(outputVector, WRAP_OBJECTS);
  for (size_t w = 0; w < in.model.wrapObjects.size(); ++w)
  {
    md::TriangleMesh mesh = in.wraps[w];
    mesh.points = this->Scale * this->Placed(poses, in.model.wrapObjects[w].body).Apply(mesh.points);
    mdvtk::AddBlock(wraps, in.model.wrapObjects[w].name, mdvtk::ToPolyData(mesh));
  }
  this->WriteTransforms(poses, q, time, stepped, vtkTable::GetData(outputVector, BODY_TRANSFORMS));
}

md::RigidTransform vtkOpenSimModelReader::OutputFrame(const std::vector<md::RigidTransform>& poses) const
{
  const Internals& in = *this->Internal;
  return this->FollowReferenceBody && in.referenceBody >= 0 ? Inverse(poses[static_cast<size_t>(in.referenceBody)])
                                                            : in.toOutput;
}

md::RigidTransform vtkOpenSimModelReader::Placed(const std::vector<md::RigidTransform>& poses, size_t body) const
{
  return Compose(this->OutputFrame(poses), poses[body]); // body frame -> output frame (scaled apart)
}

void vtkOpenSimModelReader::WriteBodies(
  const std::vector<md::RigidTransform>& poses, vtkMultiBlockDataSet* tree, const std::string& when) const
{
  const Internals& in = *this->Internal;
  const osim::Model& model = in.model;
  for (size_t b = 0; b < model.bodies.size(); ++b)
  {
    if (b == 0 && model.bodies[0].geometry.empty())
    {
      continue;
    }
    auto block = vtkSmartPointer<vtkPolyData>::New();
    const BodyMesh& mesh = in.meshes[b];
    // Rest to this pose, in the output frame and units.
    const RigidTransform motion = Motion(this->Placed(poses, b), this->Placed(in.restPoses, b));
    const md::Points placed = this->Scale * this->Placed(poses, b).Apply(mesh.points);
    CheckPlaced(placed, motion, "body '" + model.bodies[b].name + "' " + when);
    if (mesh.points.rows() > 0)
    {
      block->SetPoints(mdvtk::ToVtkPoints(placed));
      block->SetPolys(mesh.polys);
    }
    vtkNew<vtkDoubleArray> transform;
    transform->SetName("RestToCurrentTransform");
    transform->SetNumberOfComponents(12);
    double values[12];
    for (int i = 0; i < 9; ++i)
    {
      values[i] = motion.rotation(i / 3, i % 3);
    }
    for (int i = 0; i < 3; ++i)
    {
      values[9 + i] = this->Scale * motion.translation[i];
    }
    transform->InsertNextTuple(values);
    block->GetFieldData()->AddArray(transform);
    mdvtk::AddBlock(tree, model.bodies[b].name, block);
  }
}

void vtkOpenSimModelReader::WritePaths(const std::vector<double>& coordinates,
  const std::vector<md::RigidTransform>& poses, vtkMultiBlockDataSet* tree, const std::string& when,
  const std::vector<SteppedPose>& stepped) const
{
  const Internals& in = *this->Internal;
  const osim::Model& model = in.model;
  const double fade = this->ConditionalPointFade * M_PI / 180.0;
  // A path's points at `at` in the output frame and units.
  const auto placed = [&](md::Points points, const std::vector<RigidTransform>& at, const std::string& label) {
    const RigidTransform frame = this->OutputFrame(at);
    for (Eigen::Index i = 0; i < points.rows(); ++i)
    {
      points.row(i) = this->Scale * frame.Apply(Eigen::Vector3d(points.row(i).transpose())).transpose();
    }
    CheckPlaced(points, RigidTransform(), label);
    return points;
  };
  for (const osim::Path& path : model.paths)
  {
    const osim::PathGeometry g = osim::PathAt(model, path, coordinates, poses, fade);
    const md::Points points = placed(g.points, poses, "path '" + path.name + "' " + when);
    auto block = vtkSmartPointer<vtkPolyData>::New();
    block->SetPoints(mdvtk::ToVtkPoints(points));
    for (const SteppedPose& pose : stepped)
    {
      // The frame's conditional points and fades (conditionsAt): as many points as at the frame.
      const osim::PathGeometry at = osim::PathAt(model, path, pose.coordinates, pose.bodyPoses, fade, &coordinates);
      vtkSmartPointer<vtkDataArray> array = mdvtk::ToVtkPoints(
        placed(osim::PointsLike(at, g), pose.bodyPoses, "path '" + path.name + "' at pose " + pose.name + " " + when))
                                              ->GetData();
      array->SetName(mdvtk::PointsAt(pose.name).c_str());
      block->GetPointData()->AddArray(array);
    }
    vtkNew<vtkCellArray> line;
    line->InsertNextCell(static_cast<vtkIdType>(points.rows()));
    auto names = Strings("PathPointName"), onBody = Strings("PathPointBody"),
         lineName = Strings(mdvtk::array::ActionLineName);
    for (Eigen::Index i = 0; i < points.rows(); ++i)
    {
      line->InsertCellPoint(i);
      // A point over a wrap object takes the object's name and body.
      const int index = g.pointIndex[static_cast<size_t>(i)];
      if (index >= 0)
      {
        const osim::PathPoint& point = path.points[static_cast<size_t>(index)];
        names->InsertNextValue(point.name);
        onBody->InsertNextValue(model.bodies[point.body].name);
      }
      else
      {
        const osim::WrapObject& wrap = model.wrapObjects[path.wraps[static_cast<size_t>(-1 - index)].wrapObject];
        names->InsertNextValue(wrap.name);
        onBody->InsertNextValue(model.bodies[wrap.body].name);
      }
    }
    lineName->InsertNextValue(path.name);
    block->SetLines(line);
    block->GetPointData()->AddArray(names);
    block->GetPointData()->AddArray(onBody);
    block->GetCellData()->AddArray(lineName);
    mdvtk::AddFieldValue(block->GetFieldData(), "PathLength", this->Scale * g.length);
    this->WriteMuscleProperties(path, block->GetFieldData());
    mdvtk::AddBlock(tree, path.name, block);
  }
}

void vtkOpenSimModelReader::WriteMuscleProperties(const md::osim::Path& path, vtkFieldData* fieldData) const
{
  namespace array = mdvtk::array;
  auto type = Strings(array::MuscleType);
  type->InsertNextValue(path.type);
  fieldData->AddArray(type);
  mdvtk::AddFieldValue(fieldData, array::MetresPerLengthUnit, 1.0 / this->Scale);
  // As OpenSim names them; the lengths in the output's unit, as every other length here.
  const md::MuscleProperties& muscle = path.muscle;
  const std::pair<const char*, double> values[] = { { array::MaxIsometricForce, muscle.maxIsometricForce },
    { array::OptimalFiberLength, this->Scale * muscle.optimalFiberLength },
    { array::TendonSlackLength, this->Scale * muscle.tendonSlackLength },
    { array::PennationAngleAtOptimal, muscle.pennationAngle } };
  for (const auto& [name, value] : values)
  {
    if (std::isfinite(value))
    {
      mdvtk::AddFieldValue(fieldData, name, value);
    }
  }
}

void vtkOpenSimModelReader::WriteMomentArms(vtkTable* table)
{
  Internals& in = *this->Internal;
  std::ostringstream key;
  key << in.modelKey << "|" << in.motionKey << "|" << in.poseKey << "|" << this->Scale;
  if (key.str() != in.momentArmsKey)
  {
    in.momentArms->Initialize();
    in.momentArmsKey.clear();
    const osim::Model& model = in.model;
    const bool playing = !in.trajectory.times.empty();
    std::vector<int> coordinates = osim::MovingCoordinates(in.trajectory);
    if (!playing)
    {
      coordinates.resize(model.coordinates.size());
      std::iota(coordinates.begin(), coordinates.end(), 0);
    }
    const std::vector<std::vector<double>> frames =
      playing ? in.trajectory.frames : std::vector<std::vector<double>>{ in.rest };
    const auto column = [&](const std::string& name) {
      auto array = vtkSmartPointer<vtkDoubleArray>::New();
      array->SetName(name.c_str());
      array->SetNumberOfTuples(static_cast<vtkIdType>(frames.size()));
      in.momentArms->AddColumn(array);
      return array;
    };
    auto times = column(mdvtk::array::Time);
    std::vector<vtkSmartPointer<vtkDoubleArray>> values, lengths;
    std::vector<std::vector<vtkSmartPointer<vtkDoubleArray>>> arms(model.paths.size());
    for (int c : coordinates)
    {
      values.push_back(column(model.coordinates[c].name));
    }
    for (size_t p = 0; p < model.paths.size(); ++p)
    {
      lengths.push_back(column("Length(" + model.paths[p].name + ")"));
      for (int c : coordinates)
      {
        arms[p].push_back(column("MomentArm(" + model.paths[p].name + ", " + model.coordinates[c].name + ")"));
      }
    }
    const std::vector<osim::PathMoments> framesMoments = osim::MomentsAt(model, frames, coordinates);
    for (size_t k = 0; k < frames.size(); ++k)
    {
      const auto row = static_cast<vtkIdType>(k);
      times->SetValue(row, playing ? in.trajectory.times[k] : 0.0);
      for (size_t i = 0; i < coordinates.size(); ++i)
      {
        const bool rotational = model.coordinates[coordinates[i]].motionType == osim::MotionType::Rotational;
        values[i]->SetValue(row, frames[k][coordinates[i]] * (rotational ? 180.0 / M_PI : 1.0));
      }
      const osim::PathMoments& moments = framesMoments[k];
      for (size_t p = 0; p < model.paths.size(); ++p)
      {
        lengths[p]->SetValue(row, this->Scale * moments.length[p]);
        for (size_t i = 0; i < coordinates.size(); ++i)
        {
          arms[p][i]->SetValue(row, this->Scale * moments.momentArm[p][i]);
        }
      }
    }
    in.momentArmsKey = key.str();
  }
  table->ShallowCopy(in.momentArms);
}

void vtkOpenSimModelReader::WriteTransforms(const std::vector<md::RigidTransform>& poses,
  const std::vector<double>& coordinates, double time, const std::vector<SteppedPose>& stepped, vtkTable* table) const
{
  const Internals& in = *this->Internal;
  const osim::Model& model = in.model;
  auto bodyNames = Strings(mdvtk::array::Body);
  table->AddColumn(bodyNames);
  std::vector<vtkSmartPointer<vtkDoubleArray>> columns;
  for (const char* name : mdvtk::array::TransformColumns)
  {
    auto column = vtkSmartPointer<vtkDoubleArray>::New();
    column->SetName(name);
    table->AddColumn(column);
    columns.push_back(column);
  }
  // The frame's rows, then those of each stepped pose, named in column Pose.
  auto poseNames = Strings(mdvtk::array::Pose);
  for (size_t s = 0; s <= stepped.size(); ++s)
  {
    const std::vector<RigidTransform>& at = s == 0 ? poses : stepped[s - 1].bodyPoses;
    for (size_t b = 0; b < model.bodies.size(); ++b)
    {
      const RigidTransform motion = Motion(this->Placed(at, b), this->Placed(in.restPoses, b));
      bodyNames->InsertNextValue(model.bodies[b].name);
      poseNames->InsertNextValue(s == 0 ? std::string() : stepped[s - 1].name);
      for (int i = 0; i < 9; ++i)
      {
        columns[i]->InsertNextValue(motion.rotation(i / 3, i % 3));
      }
      for (int i = 0; i < 3; ++i)
      {
        columns[9 + i]->InsertNextValue(this->Scale * motion.translation[i]);
      }
    }
  }
  if (!stepped.empty())
  {
    table->AddColumn(poseNames);
    mdvtk::AddFieldValue(table->GetFieldData(), mdvtk::array::MomentArmStep, this->MomentArmStep);
  }
  mdvtk::AddFieldValue(table->GetFieldData(), mdvtk::array::Time, time);
  auto rotationalNames = Strings(mdvtk::array::RotationalCoordinates);
  for (size_t c = 0; c < model.coordinates.size(); ++c)
  {
    const bool rotational = model.coordinates[c].motionType == osim::MotionType::Rotational;
    mdvtk::AddFieldValue(table->GetFieldData(), model.coordinates[c].name.c_str(),
      rotational ? coordinates[c] * 180.0 / M_PI : coordinates[c]);
    if (rotational)
    {
      rotationalNames->InsertNextValue(model.coordinates[c].name);
    }
  }
  table->GetFieldData()->AddArray(rotationalNames);
}

void vtkOpenSimModelReader::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << Text(this->FileName) << "\n";
  os << indent << "MotionFileName: " << Text(this->MotionFileName) << "\n";
  os << indent << "GeometrySearchPath: " << Text(this->GeometrySearchPath) << "\n";
  os << indent << "RestPoseCoordinates: " << Text(this->RestPoseCoordinates) << "\n";
  os << indent << "RestPoseFileName: " << Text(this->RestPoseFileName) << "\n";
  os << indent << "ReferenceBody: " << Text(this->ReferenceBody) << "\n";
  os << indent << "FollowReferenceBody: " << this->FollowReferenceBody << "\n";
  os << indent << "Scale: " << this->Scale << "\n";
  os << indent << "CurrentPoseTime: " << this->CurrentPoseTime << "\n";
  os << indent << "PlayMotion: " << this->PlayMotion << "\n";
  os << indent << "AngleUnit: " << this->AngleUnit << "\n";
  os << indent << "IgnoreUnknownColumns: " << this->IgnoreUnknownColumns << "\n";
  os << indent << "LoadGeometry: " << this->LoadGeometry << "\n";
  os << indent << "ConditionalPointFade: " << this->ConditionalPointFade << "\n";
  os << indent << "MomentArmStep: " << this->MomentArmStep << "\n";
}
