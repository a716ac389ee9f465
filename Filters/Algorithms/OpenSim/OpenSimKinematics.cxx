// SPDX-License-Identifier: BSD-3-Clause
#include "OpenSim/OpenSimKinematics.h"
#include "OpenSim/OpenSimWrapping.h"

#include "Geometry/Polyline.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace md::osim
{
std::vector<double> DefaultCoordinates(const Model& model)
{
  std::vector<double> q(model.coordinates.size());
  for (size_t i = 0; i < q.size(); ++i)
  {
    q[i] = model.coordinates[i].defaultValue;
  }
  ApplyCouplers(model, q);
  return q;
}

void ApplyCouplers(const Model& model, std::vector<double>& coordinates)
{
  for (const CoordinateCoupler& c : model.couplers)
  {
    coordinates[c.dependent] = c.scale * c.function(coordinates[c.independent]);
  }
}

std::vector<RigidTransform> BodyPoses(const Model& model, const std::vector<double>& coordinates)
{
  std::vector<RigidTransform> poses(model.bodies.size());
  for (const Joint& joint : model.joints)
  {
    double value[6];
    for (int i = 0; i < 6; ++i)
    {
      const TransformAxis& axis = joint.axes[i];
      value[i] = axis.function(axis.coordinate >= 0 ? coordinates[axis.coordinate] : 0.0);
    }
    RigidTransform mobiliser;
    mobiliser.rotation = (Eigen::AngleAxisd(value[0], joint.axes[0].axis) *
      Eigen::AngleAxisd(value[1], joint.axes[1].axis) * Eigen::AngleAxisd(value[2], joint.axes[2].axis))
                           .toRotationMatrix();
    mobiliser.translation =
      value[3] * joint.axes[3].axis + value[4] * joint.axes[4].axis + value[5] * joint.axes[5].axis;
    // child-in-ground = parent-in-ground * parentOffset * mobiliser * inverse(childOffset)
    poses[joint.childBody] =
      Compose(Compose(poses[joint.parentBody], Compose(joint.parentOffset, mobiliser)), Inverse(joint.childOffset));
  }
  return poses;
}

double BeyondRange(const PathPoint& point, double value)
{
  constexpr double kSlack = 1e-5; // OpenSim's
  if (!std::isfinite(value))
  {
    return std::numeric_limits<double>::infinity();
  }
  return std::max({ 0.0, point.rangeMin - kSlack - value, value - point.rangeMax - kSlack });
}

namespace
{
/// A conditional point's weight at `value`: 1 within its range, falling smoothly (C1) to 0 over
/// `fade` beyond it.
double FadeWeight(const PathPoint& point, double value, double fade)
{
  const double beyond = BeyondRange(point, value);
  if (beyond <= 0.0)
  {
    return 1.0;
  }
  if (beyond >= fade)
  {
    return 0.0;
  }
  const double t = beyond / fade;
  return 1.0 - t * t * (3.0 - 2.0 * t);
}
}

PathGeometry PathAt(const Model& model, const Path& path, const std::vector<double>& coordinates,
  const std::vector<RigidTransform>& bodyPoses, double conditionalFade, const std::vector<double>* conditionsAt)
{
  const std::vector<double>& conditions = conditionsAt ? *conditionsAt : coordinates;
  PathGeometry geometry;
  std::vector<Eigen::Vector3d> points;
  std::vector<double> weight; // per point kept: 1, or a fading conditional point's weight
  points.reserve(path.points.size());
  for (size_t k = 0; k < path.points.size(); ++k)
  {
    const PathPoint& p = path.points[k];
    Eigen::Vector3d local = p.location;
    double w = 1.0;
    if (p.kind == PathPointKind::Conditional)
    {
      const double value = conditions[p.coordinate];
      const bool fades = conditionalFade > 0.0 && model.coordinates[p.coordinate].motionType == MotionType::Rotational;
      w = fades ? FadeWeight(p, value, conditionalFade) : (BeyondRange(p, value) > 0.0 ? 0.0 : 1.0);
      if (w == 0.0 && !fades)
      {
        continue;
      }
    }
    else if (p.kind == PathPointKind::Moving)
    {
      for (int i = 0; i < 3; ++i)
      {
        double argument = 0.0;
        if (p.locationCoordinate[i] >= 0)
        {
          const Coordinate& c = model.coordinates[p.locationCoordinate[i]];
          argument = std::clamp(coordinates[p.locationCoordinate[i]], c.rangeMin, c.rangeMax);
        }
        local[i] = p.locationFunction[i](argument);
      }
    }
    const RigidTransform& body = bodyPoses[p.body];
    points.push_back(body.Apply(p.frame.Apply(local)));
    weight.push_back(w);
    geometry.pointIndex.push_back(static_cast<int>(k));
  }
  // Fading points move onto the segment between their nearest steady neighbours.
  for (size_t i = 0; i < points.size(); ++i)
  {
    if (weight[i] >= 1.0)
    {
      continue;
    }
    size_t before = i, after = i;
    while (before > 0 && path.points[geometry.pointIndex[before]].kind == PathPointKind::Conditional)
    {
      --before;
    }
    while (after + 1 < points.size() && path.points[geometry.pointIndex[after]].kind == PathPointKind::Conditional)
    {
      ++after;
    }
    if (before == i || after == i)
    {
      continue; // an end of the path stays where it is
    }
    const Eigen::Vector3d a = points[before], b = points[after];
    const double span = (b - a).squaredNorm();
    const double t = span > 0.0 ? std::clamp((points[i] - a).dot(b - a) / span, 0.0, 1.0) : 0.0;
    const Eigen::Vector3d onSegment = a + t * (b - a);
    points[i] = onSegment + weight[i] * (points[i] - onSegment);
  }
  // The polyline: the path points as they are, each wrap by its surface points.
  std::vector<Eigen::Vector3d> polyline;
  if (path.wraps.empty())
  {
    polyline = std::move(points);
  }
  else
  {
    const std::vector<WrappedPoint> wrapped =
      WrapPath(model, path, points, geometry.pointIndex, bodyPoses, kWrapPointSpacing, &geometry.length);
    geometry.pointIndex.clear();
    for (const WrappedPoint& p : wrapped)
    {
      if (p.wrap < 0)
      {
        polyline.push_back(p.position);
        geometry.pointIndex.push_back(p.pathPoint);
      }
      else if (p.leaves)
      {
        for (Eigen::Index k = 0; k < p.surface.rows(); ++k)
        {
          polyline.push_back(p.surface.row(k).transpose());
          geometry.pointIndex.push_back(-1 - p.wrap);
        }
      }
    }
  }
  geometry.points.resize(static_cast<Eigen::Index>(polyline.size()), 3);
  for (size_t i = 0; i < polyline.size(); ++i)
  {
    geometry.points.row(static_cast<Eigen::Index>(i)) = polyline[i].transpose();
  }
  if (path.wraps.empty())
  {
    geometry.length = md::PolylineLength(geometry.points);
  }
  return geometry;
}

Points PointsLike(const PathGeometry& path, const PathGeometry& like)
{
  if (path.points.rows() == like.points.rows() || path.points.rows() < 2 || like.points.rows() < 2)
  {
    return path.points.rows() == like.points.rows() ? path.points : Points(Points::Zero(like.points.rows(), 3));
  }
  // The share of each polyline's length before each of its points.
  const auto shares = [](const Points& points) {
    std::vector<double> s(static_cast<size_t>(points.rows()), 0.0);
    for (Eigen::Index i = 1; i < points.rows(); ++i)
    {
      s[static_cast<size_t>(i)] = s[static_cast<size_t>(i) - 1] + (points.row(i) - points.row(i - 1)).norm();
    }
    const double total = s.back();
    for (double& v : s)
    {
      v = total > 0 ? v / total : 0.0;
    }
    return s;
  };
  const std::vector<double> along = shares(path.points), wanted = shares(like.points);
  Points out(like.points.rows(), 3);
  size_t segment = 1;
  for (Eigen::Index k = 0; k < like.points.rows(); ++k)
  {
    const double share = wanted[static_cast<size_t>(k)];
    while (segment + 1 < along.size() && along[segment] < share)
    {
      ++segment;
    }
    const double span = along[segment] - along[segment - 1];
    const double t = span > 0 ? std::clamp((share - along[segment - 1]) / span, 0.0, 1.0) : 0.0;
    out.row(k) = (1.0 - t) * path.points.row(Eigen::Index(segment) - 1) + t * path.points.row(Eigen::Index(segment));
  }
  return out;
}

double PolylineLength(const Points& points)
{
  return md::PolylineLength(points);
}

namespace
{
/// A surface of revolution about z: rings of `resolution` points at the given (radius, z), closed
/// by a point at each end whose ring radius is zero.
TriangleMesh Revolve(const std::vector<std::pair<double, double>>& profile, int resolution)
{
  TriangleMesh mesh;
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Matrix<std::int64_t, 1, 3>> triangles;
  std::vector<std::int64_t> ringStart;
  for (const auto& [radius, z] : profile)
  {
    ringStart.push_back(static_cast<std::int64_t>(points.size()));
    if (radius == 0.0)
    {
      points.emplace_back(0.0, 0.0, z);
      continue;
    }
    for (int k = 0; k < resolution; ++k)
    {
      const double angle = 2.0 * M_PI * k / resolution;
      points.emplace_back(radius * std::cos(angle), radius * std::sin(angle), z);
    }
  }
  for (size_t r = 0; r + 1 < profile.size(); ++r)
  {
    const bool apexA = profile[r].first == 0.0, apexB = profile[r + 1].first == 0.0;
    for (int k = 0; k < resolution; ++k)
    {
      const int next = (k + 1) % resolution;
      const std::int64_t a0 = ringStart[r] + (apexA ? 0 : k), a1 = ringStart[r] + (apexA ? 0 : next);
      const std::int64_t b0 = ringStart[r + 1] + (apexB ? 0 : k), b1 = ringStart[r + 1] + (apexB ? 0 : next);
      if (!apexA)
      {
        triangles.push_back({ a0, b0, a1 });
      }
      if (!apexB)
      {
        triangles.push_back({ a1, b0, b1 });
      }
    }
  }
  mesh.points.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i)
  {
    mesh.points.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
  }
  mesh.triangles.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  for (size_t i = 0; i < triangles.size(); ++i)
  {
    mesh.triangles.row(static_cast<Eigen::Index>(i)) = triangles[i];
  }
  return mesh;
}
}

TriangleMesh WrapSurface(const WrapObject& wrap, int resolution)
{
  resolution = std::max(resolution, 6);
  TriangleMesh mesh;
  if (wrap.shape == WrapShape::Cylinder)
  {
    const double r = wrap.dimensions[0], half = 0.5 * wrap.dimensions[1];
    // From the top down so that the normals point outwards.
    mesh = Revolve({ { 0.0, half }, { r, half }, { r, -half }, { 0.0, -half } }, resolution);
  }
  else if (wrap.shape == WrapShape::Sphere || wrap.shape == WrapShape::Ellipsoid)
  {
    std::vector<std::pair<double, double>> profile;
    const int rings = resolution / 2;
    for (int i = 0; i <= rings; ++i)
    {
      const double polar = M_PI * i / rings;
      profile.emplace_back(i == 0 || i == rings ? 0.0 : std::sin(polar), std::cos(polar));
    }
    mesh = Revolve(profile, resolution);
    const Eigen::Vector3d radii = wrap.shape == WrapShape::Sphere
      ? Eigen::Vector3d::Constant(wrap.dimensions[0])
      : Eigen::Vector3d(wrap.dimensions[0], wrap.dimensions[1], wrap.dimensions[2]);
    mesh.points = mesh.points * radii.asDiagonal();
  }
  else
  {
    // Torus about z: centre circle of radius R, tube of radius r.
    const double R = wrap.dimensions[0], r = wrap.dimensions[1];
    const int tube = std::max(6, resolution / 2);
    mesh.points.resize(static_cast<Eigen::Index>(resolution) * tube, 3);
    mesh.triangles.resize(2 * static_cast<Eigen::Index>(resolution) * tube, 3);
    for (int i = 0; i < resolution; ++i)
    {
      const double u = 2.0 * M_PI * i / resolution;
      for (int j = 0; j < tube; ++j)
      {
        const double v = 2.0 * M_PI * j / tube;
        mesh.points.row(i * tube + j) << (R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u),
          r * std::sin(v);
        const std::int64_t a = i * tube + j, b = ((i + 1) % resolution) * tube + j,
                           c = ((i + 1) % resolution) * tube + (j + 1) % tube, d = i * tube + (j + 1) % tube;
        mesh.triangles.row(2 * (i * tube + j)) << a, b, c;
        mesh.triangles.row(2 * (i * tube + j) + 1) << a, c, d;
      }
    }
  }
  mesh.points = wrap.placement.Apply(mesh.points);
  return mesh;
}
}
