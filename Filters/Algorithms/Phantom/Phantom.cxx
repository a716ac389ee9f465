// SPDX-License-Identifier: BSD-3-Clause
#include "Phantom/Phantom.h"

#include "Geometry/Polyline.h"

#include <algorithm>
#include <cmath>

namespace md
{
namespace
{
using Vec3 = Eigen::Vector3d;

/// Points along `curve` at most `spacing` apart, at equal arc lengths.
Points Resample(const std::vector<Vec3>& curve, double spacing)
{
  double length = 0.0;
  for (size_t i = 1; i < curve.size(); ++i)
  {
    length += (curve[i] - curve[i - 1]).norm();
  }
  const auto segments = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::ceil(length / spacing)));
  return ResampleByArcLength(curve, segments + 1);
}

/// Smooth step from 0 (x <= a) to 1 (x >= b).
double SmoothStep(double a, double b, double x)
{
  const double t = std::clamp((x - a) / (b - a), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

/// Ellipsoidal closing of a radius profile: 1 in the middle, falling to 0 at
/// both ends over `capLength`.
double CapFactor(double x, double length, double capLength)
{
  const double fromEnd = std::min(x, length - x);
  if (fromEnd >= capLength)
  {
    return 1.0;
  }
  const double u = (capLength - std::max(fromEnd, 0.0)) / capLength;
  return std::sqrt(std::max(0.0, 1 - u * u));
}

/// Spindle profile of a muscle belly: 0 at the ends, 1 in the middle.
double Spindle(double x, double length)
{
  return std::pow(std::sin(M_PI * std::clamp(x / length, 0.0, 1.0)), 0.6);
}

Points Rows(std::initializer_list<Vec3> points)
{
  Points out(static_cast<Eigen::Index>(points.size()), 3);
  Eigen::Index i = 0;
  for (const Vec3& p : points)
  {
    out.row(i++) = p.transpose();
  }
  return out;
}

/// The part of a dense polyline between fractions a and b of its length.
Points Trim(const Points& line, double a, double b, double spacing)
{
  std::vector<double> s(static_cast<size_t>(line.rows()), 0.0);
  for (Eigen::Index i = 1; i < line.rows(); ++i)
  {
    s[i] = s[i - 1] + (line.row(i) - line.row(i - 1)).norm();
  }
  const double length = s.back();
  std::vector<Vec3> curve;
  auto at = [&](double target) {
    size_t k = 1;
    while (k + 1 < s.size() && s[k] < target)
    {
      ++k;
    }
    const double span = s[k] - s[k - 1];
    const double f = span > 0 ? std::clamp((target - s[k - 1]) / span, 0.0, 1.0) : 0.0;
    return Vec3((1 - f) * line.row(k - 1) + f * line.row(k));
  };
  curve.push_back(at(a * length));
  for (Eigen::Index i = 0; i < line.rows(); ++i)
  {
    if (s[i] > a * length && s[i] < b * length)
    {
      curve.push_back(line.row(i).transpose());
    }
  }
  curve.push_back(at(b * length));
  return Resample(curve, spacing);
}
}

Points RoundedPolyline(const Points& controlPoints, double cornerRadius, double spacing)
{
  const Eigen::Index n = controlPoints.rows();
  std::vector<Vec3> curve;
  curve.push_back(controlPoints.row(0).transpose());
  for (Eigen::Index i = 1; i + 1 < n; ++i)
  {
    const Vec3 previous = controlPoints.row(i - 1).transpose();
    const Vec3 corner = controlPoints.row(i).transpose();
    const Vec3 next = controlPoints.row(i + 1).transpose();
    const double r = std::min({ cornerRadius, 0.45 * (corner - previous).norm(), 0.45 * (next - corner).norm() });
    const Vec3 a = corner - r * (corner - previous).normalized();
    const Vec3 b = corner + r * (next - corner).normalized();
    constexpr int filletSamples = 16;
    for (int k = 0; k <= filletSamples; ++k)
    {
      const double t = static_cast<double>(k) / filletSamples;
      curve.push_back((1 - t) * (1 - t) * a + 2 * (1 - t) * t * corner + t * t * b);
    }
  }
  curve.push_back(controlPoints.row(n - 1).transpose());
  return Resample(curve, spacing);
}

TriangleMesh BuildTube(const TubeSpecification& spec)
{
  const Points& c = spec.centreline;
  const Eigen::Index segments = c.rows() - 1;
  std::vector<double> s(static_cast<size_t>(c.rows()), 0.0);
  for (Eigen::Index i = 1; i < c.rows(); ++i)
  {
    s[i] = s[i - 1] + (c.row(i) - c.row(i - 1)).norm();
  }
  const double length = s.back();

  // Rotation-minimising frames, one per centreline segment (parallel transport).
  std::vector<Vec3> tangents(static_cast<size_t>(segments)), normals(static_cast<size_t>(segments));
  for (Eigen::Index k = 0; k < segments; ++k)
  {
    tangents[k] = (c.row(k + 1) - c.row(k)).transpose().normalized();
    if (k == 0)
    {
      Vec3 n = spec.normalHint - spec.normalHint.dot(tangents[0]) * tangents[0];
      normals[0] = n.normalized();
    }
    else
    {
      const Eigen::Quaterniond turn = Eigen::Quaterniond::FromTwoVectors(tangents[k - 1], tangents[k]);
      Vec3 n = turn * normals[k - 1];
      normals[k] = (n - n.dot(tangents[k]) * tangents[k]).normalized();
    }
  }

  // Rings at equal steps of the length of the radius profile, so that the
  // closing caps get as fine a sampling as the sides.
  constexpr int profileSamples = 4000;
  std::vector<double> profileX(profileSamples + 1), profileS(profileSamples + 1, 0.0);
  double largestRadius = 0;
  double previousRadius = 0;
  for (int i = 0; i <= profileSamples; ++i)
  {
    profileX[i] = length * i / profileSamples;
    const Eigen::Vector2d r = spec.radii(profileX[i], length);
    const double mean = 0.5 * (r[0] + r[1]);
    largestRadius = std::max(largestRadius, std::max(r[0], r[1]));
    if (i > 0)
    {
      profileS[i] = profileS[i - 1] + std::hypot(profileX[i] - profileX[i - 1], mean - previousRadius);
    }
    previousRadius = mean;
  }
  const int m = spec.resolution;
  const double spacing = 2 * M_PI * largestRadius / m;
  const int rings = std::max(3, static_cast<int>(std::lround(profileS.back() / spacing)));

  TriangleMesh mesh;
  mesh.points.resize(2 + static_cast<Eigen::Index>(rings - 1) * m, 3);
  mesh.points.row(0) = c.row(0);
  size_t profileIndex = 1;
  size_t segment = 0;
  for (int k = 1; k < rings; ++k)
  {
    const double target = profileS.back() * k / rings;
    while (profileIndex + 1 < profileS.size() && profileS[profileIndex] < target)
    {
      ++profileIndex;
    }
    const double f = (target - profileS[profileIndex - 1]) / (profileS[profileIndex] - profileS[profileIndex - 1]);
    const double x = (1 - f) * profileX[profileIndex - 1] + f * profileX[profileIndex];
    while (segment + 1 < static_cast<size_t>(segments) && s[segment + 1] < x)
    {
      ++segment;
    }
    const double g = std::clamp((x - s[segment]) / (s[segment + 1] - s[segment]), 0.0, 1.0);
    const Vec3 centre = ((1 - g) * c.row(segment) + g * c.row(segment + 1)).transpose();
    const Vec3 n = normals[segment];
    const Vec3 b = tangents[segment].cross(n);
    const Eigen::Vector2d r = spec.radii(x, length);
    for (int j = 0; j < m; ++j)
    {
      const double phi = 2 * M_PI * j / m;
      mesh.points.row(1 + static_cast<Eigen::Index>(k - 1) * m + j) =
        (centre + r[0] * std::cos(phi) * n + r[1] * std::sin(phi) * b).transpose();
    }
  }
  const Eigen::Index lastPole = mesh.points.rows() - 1;
  mesh.points.row(lastPole) = c.row(c.rows() - 1);

  auto ringPoint = [m](int ring, int j) {
    return static_cast<std::int64_t>(1 + static_cast<std::int64_t>(ring - 1) * m + (j % m));
  };
  std::vector<Eigen::Matrix<std::int64_t, 1, 3>> triangles;
  for (int j = 0; j < m; ++j)
  {
    triangles.push_back({ 0, ringPoint(1, j + 1), ringPoint(1, j) });
  }
  for (int k = 1; k + 1 < rings; ++k)
  {
    for (int j = 0; j < m; ++j)
    {
      const auto a = ringPoint(k, j), b = ringPoint(k, j + 1);
      const auto cc = ringPoint(k + 1, j + 1), d = ringPoint(k + 1, j);
      triangles.push_back({ a, b, cc });
      triangles.push_back({ a, cc, d });
    }
  }
  for (int j = 0; j < m; ++j)
  {
    triangles.push_back({ lastPole, ringPoint(rings - 1, j), ringPoint(rings - 1, j + 1) });
  }
  mesh.triangles.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  for (size_t t = 0; t < triangles.size(); ++t)
  {
    mesh.triangles.row(static_cast<Eigen::Index>(t)) = triangles[t];
  }
  return mesh;
}

namespace
{
/// The pelvis: a flat curved plate from the ischium over the hip to the iliac crest (`k` the
/// scale; tubes of `resolution` points round, sampled every `spacing` along).
PhantomBone Pelvis(double k, int resolution, double spacing)
{
  TubeSpecification pelvis;
  pelvis.centreline =
    RoundedPolyline(k * Rows({ { -20, -18, -85 }, { -42, 0, 5 }, { -46, -6, 100 }, { -36, 0, 175 } }), 40 * k, spacing);
  pelvis.radii = [k](double x, double length) {
    const double cap = CapFactor(x, length, 12 * k);
    const double width = 20 * k + 14 * k * SmoothStep(0.3 * length, 0.7 * length, x);
    return Eigen::Vector2d(11 * k * cap, width * cap);
  };
  pelvis.normalHint = Vec3::UnitX();
  pelvis.resolution = resolution;
  PhantomBone bone{ "Pelvis", BuildTube(pelvis), {} };
  bone.currentPoints = bone.rest.points;
  return bone;
}

/// The femur: head (a sphere about `hipCentre`), neck, shaft, condyles; in the current pose
/// moved by `motion`.
PhantomBone Femur(double k, int resolution, double spacing, const Vec3& hipCentre, const RigidTransform& motion)
{
  const double headRadius = 22 * k;
  const Vec3 neckCorner = k * Vec3(50, 0, -45);
  const Vec3 headPole = hipCentre - headRadius * (neckCorner - hipCentre).normalized();
  TubeSpecification femur;
  femur.centreline = RoundedPolyline(Rows({ headPole, neckCorner, k * Vec3(58, 0, -400) }), 30 * k, spacing);
  femur.radii = [k, headRadius](double x, double length) {
    const double neck = 13 * k, shaft = 14 * k, condyle = 26 * k;
    const double fromHeadCentre = x - headRadius;
    double r;
    if (fromHeadCentre < 0)
    {
      r = std::sqrt(std::max(0.0, headRadius * headRadius - fromHeadCentre * fromHeadCentre));
    }
    else
    {
      const double sphere = std::sqrt(std::max(0.0, headRadius * headRadius - fromHeadCentre * fromHeadCentre));
      const double body = neck + (shaft - neck) * SmoothStep(60 * k, 120 * k, x) +
        (condyle - shaft) * SmoothStep(length - 90 * k, length - condyle, x);
      r = std::max(sphere, body * CapFactor(x, length, condyle));
      if (x > length - condyle)
      {
        r = condyle * CapFactor(x, length, condyle);
      }
    }
    return Eigen::Vector2d(r, r);
  };
  femur.normalHint = Vec3::UnitY();
  femur.resolution = resolution;
  PhantomBone bone{ "Femur", BuildTube(femur), {} };
  bone.currentPoints = motion.Apply(bone.rest.points);
  return bone;
}

/// The three muscles with their action lines in both poses: the iliopsoas, the gluteus maximus
/// (two bundles) and the rectus femoris; the points of a line fixed to the femur moved by
/// `phantom`'s femur motion.
void AddMuscles(Phantom& phantom, double k, int resolution, double spacing, double flexionDegrees)
{
  const RigidTransform& femurMotion = phantom.femurMotion;
  auto muscleTube = [&](const Points& path, double width, double thickness, const Vec3& widthDirection) {
    TubeSpecification tube;
    tube.centreline = Trim(RoundedPolyline(path, 25 * k, spacing), 0.08, 0.92, spacing);
    tube.radii = [width, thickness](double x, double length) {
      const double f = Spindle(x, length);
      return Eigen::Vector2d(width * f, thickness * f);
    };
    tube.normalHint = widthDirection;
    tube.resolution = resolution;
    return BuildTube(tube);
  };
  // Moves the points of a path that are fixed to the femur (flag true).
  auto currentPath = [&](const Points& path, const std::vector<bool>& onFemur) {
    Points current = path;
    for (Eigen::Index i = 0; i < path.rows(); ++i)
    {
      if (onFemur[i])
      {
        current.row(i) = femurMotion.Apply(Vec3(path.row(i).transpose())).transpose();
      }
    }
    return current;
  };
  // Iliopsoas: iliac fossa, over the anterior rim of the hip (a conditional via
  // point, active below 40 degrees of flexion), to the lesser trochanter.
  {
    PhantomMuscle muscle;
    muscle.name = "Iliopsoas";
    const Points path = k * Rows({ { -28, 30, 130 }, { -5, 38, 0 }, { 35, 6, -70 } });
    muscle.rest = muscleTube(path, 15 * k, 12 * k, Vec3::UnitX());
    muscle.actionLineNames = { "iliopsoas" };
    muscle.actionLinesRest = { path };
    Points current = currentPath(path, { false, false, true });
    if (flexionDegrees >= 40)
    {
      current = Rows({ Vec3(current.row(0).transpose()), Vec3(current.row(2).transpose()) });
    }
    muscle.actionLinesCurrent = { current };
    phantom.muscles.push_back(std::move(muscle));
  }
  // Gluteus maximus: broad and flat behind the hip, two bundles, wrapping the
  // greater trochanter through a via point fixed to the femur.
  {
    PhantomMuscle muscle;
    muscle.name = "GluteusMaximus";
    const Points path = k * Rows({ { -35, -40, 125 }, { 10, -48, 5 }, { 62, -30, -45 }, { 55, -16, -95 } });
    const std::vector<bool> onFemur = { false, false, true, true };
    muscle.rest = muscleTube(path, 28 * k, 11 * k, Vec3::UnitX());
    const Vec3 spread = 9 * k * Vec3::UnitX();
    const Vec3 lift = 4 * k * Vec3::UnitZ();
    for (int bundle = 0; bundle < 2; ++bundle)
    {
      const double side = bundle == 0 ? 1.0 : -1.0;
      Points line = path;
      for (Eigen::Index i = 0; i < line.rows(); ++i)
      {
        line.row(i) += (side * (spread + lift)).transpose();
      }
      muscle.actionLineNames.push_back("gluteus_maximus_" + std::to_string(bundle + 1));
      muscle.actionLinesRest.push_back(line);
      muscle.actionLinesCurrent.push_back(currentPath(line, onFemur));
    }
    phantom.muscles.push_back(std::move(muscle));
  }
  // Rectus femoris: from the anterior inferior iliac spine down the front of
  // the thigh to the knee; the femur sweeps into it at large flexion.
  {
    PhantomMuscle muscle;
    muscle.name = "RectusFemoris";
    const Points path = k * Rows({ { 32, 40, 45 }, { 48, 38, -60 }, { 60, 32, -380 } });
    muscle.rest = muscleTube(path, 16 * k, 12 * k, Vec3::UnitX());
    muscle.actionLineNames = { "rectus_femoris" };
    muscle.actionLinesRest = { path };
    muscle.actionLinesCurrent = { currentPath(path, { false, false, true }) };
    phantom.muscles.push_back(std::move(muscle));
  }
}
}

Phantom BuildPhantom(const PhantomParameters& parameters)
{
  if (!(parameters.scale > 0) || parameters.resolution < 6 || !std::isfinite(parameters.flexionDegrees))
  {
    throw InputError("the phantom needs a positive scale, a finite flexion angle and a resolution of "
                     "at least 6");
  }
  const double k = parameters.scale;
  const int resolution = parameters.resolution;
  const double spacing = 1.0 * k; // centreline sampling, mm
  Phantom phantom;
  phantom.hipCentre = Vec3::Zero();
  const double flexion = parameters.flexionDegrees * M_PI / 180.0;
  phantom.femurMotion = RigidTransform::AboutPoint(Vec3::UnitX(), flexion, phantom.hipCentre);
  phantom.bones.push_back(Pelvis(k, resolution, spacing));
  phantom.bones.push_back(Femur(k, resolution, spacing, phantom.hipCentre, phantom.femurMotion));
  AddMuscles(phantom, k, resolution, spacing, parameters.flexionDegrees);
  return phantom;
}
}
