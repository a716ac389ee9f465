// SPDX-License-Identifier: BSD-3-Clause
#include "Anatomy/MuscleFibres.h"

#include "Geometry/MeanValueCoordinates.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/Polyline.h"
#include "Geometry/TriangleTree.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/IterativeLinearSolvers>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>

namespace md
{
namespace
{
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// A streamline has arrived where phi is this close to its end's value (0 or 1), or (where the
/// field ends or is flat) where its last sample was beyond kNearEnd of the way.
constexpr double kArrived = 0.995;
constexpr double kNearEnd = 0.9;
/// A carried fibre point outside its muscle (or inside a bone) is found when it is out by less
/// than this many grid spacings (the search's radius: a point deeper inside costs little).
constexpr double kEscapeReach = 1.5;
/// A bone can poke into a muscle deeper than a fibre point strays out of it in a frame: an
/// obstacle without a distance grid (a bone refitted to a frame) is searched this many times farther.
constexpr double kObstacleReach = 3.0;
/// Share of the muscle's extent along its lines that makes an end's cap where it has no area.
constexpr double kCapShare = 0.05;
/// Residual of the field's solve (conjugate gradients), relative to its right-hand side: phi,
/// in [0, 1], then lies within 1e-11 of a direct solve's (measured on the LHDL muscles and
/// gait10dof18musc's), far below what moves a streamline, in a small share of its time.
constexpr double kFieldTolerance = 1e-12;

Eigen::Vector3d Centroid(const Points& points, const std::vector<Eigen::Index>& indices)
{
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (Eigen::Index i : indices)
  {
    sum += points.row(i).transpose();
  }
  return sum / static_cast<double>(std::max<size_t>(indices.size(), 1));
}

/// A regular grid over a box; nodes numbered x fastest.
struct Grid
{
  Eigen::Vector3d origin;
  double h = 1;
  std::array<int, 3> n{};

  Eigen::Index Size() const { return Eigen::Index(n[0]) * n[1] * n[2]; }
  Eigen::Index Index(int i, int j, int k) const { return (Eigen::Index(k) * n[1] + j) * n[0] + i; }
  Eigen::Vector3d Node(Eigen::Index index) const
  {
    const auto i = static_cast<int>(index % n[0]);
    const auto j = static_cast<int>((index / n[0]) % n[1]);
    const auto k = static_cast<int>(index / (Eigen::Index(n[0]) * n[1]));
    return this->origin + this->h * Eigen::Vector3d(i, j, k);
  }
  /// The node's 6 neighbours inside the grid (-1 beyond it).
  std::array<Eigen::Index, 6> Neighbours(Eigen::Index index) const
  {
    const auto i = static_cast<int>(index % n[0]);
    const auto j = static_cast<int>((index / n[0]) % n[1]);
    const auto k = static_cast<int>(index / (Eigen::Index(n[0]) * n[1]));
    const Eigen::Index sj = n[0], sk = Eigen::Index(n[0]) * n[1];
    return { i > 0 ? index - 1 : -1, i + 1 < n[0] ? index + 1 : -1, j > 0 ? index - sj : -1,
      j + 1 < n[1] ? index + sj : -1, k > 0 ? index - sk : -1, k + 1 < n[2] ? index + sk : -1 };
  }
};

/// Which grid nodes are inside the closed surface: rays along +x through every row of nodes,
/// the parity of the crossings before each node.
std::vector<char> InsideNodes(const TriangleMesh& mesh, const Grid& grid)
{
  std::vector<std::vector<double>> crossings(size_t(grid.n[1]) * grid.n[2]);
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
  {
    const Eigen::Vector3d a = mesh.points.row(mesh.triangles(t, 0)).transpose();
    const Eigen::Vector3d b = mesh.points.row(mesh.triangles(t, 1)).transpose();
    const Eigen::Vector3d c = mesh.points.row(mesh.triangles(t, 2)).transpose();
    const double area = (b.y() - a.y()) * (c.z() - a.z()) - (b.z() - a.z()) * (c.y() - a.y());
    if (area == 0)
    {
      continue; // parallel to the rays: no crossing
    }
    const auto range = [&](int axis, int count) {
      const double low = std::min({ a[axis], b[axis], c[axis] }), high = std::max({ a[axis], b[axis], c[axis] });
      return std::make_pair(std::max(0, static_cast<int>(std::ceil((low - grid.origin[axis]) / grid.h))),
        std::min(count - 1, static_cast<int>(std::floor((high - grid.origin[axis]) / grid.h))));
    };
    const auto [j0, j1] = range(1, grid.n[1]);
    const auto [k0, k1] = range(2, grid.n[2]);
    for (int k = k0; k <= k1; ++k)
    {
      for (int j = j0; j <= j1; ++j)
      {
        const double y = grid.origin.y() + j * grid.h, z = grid.origin.z() + k * grid.h;
        // Barycentric coordinates of (y, z) in the triangle's projection.
        const double u = ((b.y() - y) * (c.z() - z) - (b.z() - z) * (c.y() - y)) / area;
        const double v = ((c.y() - y) * (a.z() - z) - (c.z() - z) * (a.y() - y)) / area;
        const double w = 1 - u - v;
        if (u > 0 && v > 0 && w > 0)
        {
          crossings[size_t(k) * grid.n[1] + j].push_back(u * a.x() + v * b.x() + w * c.x());
        }
      }
    }
  }
  std::vector<char> inside(size_t(grid.Size()), 0);
  for (int k = 0; k < grid.n[2]; ++k)
  {
    for (int j = 0; j < grid.n[1]; ++j)
    {
      auto& row = crossings[size_t(k) * grid.n[1] + j];
      std::sort(row.begin(), row.end());
      size_t before = 0;
      for (int i = 0; i < grid.n[0]; ++i)
      {
        const double x = grid.origin.x() + i * grid.h;
        while (before < row.size() && row[before] < x)
        {
          ++before;
        }
        inside[size_t(grid.Index(i, j, k))] = static_cast<char>(before % 2);
      }
    }
  }
  return inside;
}

/// The harmonic field on the grid: NaN where it is not defined.
struct Field
{
  Grid grid;
  std::vector<double> phi;
  std::vector<signed char> fixed;        ///< -1 free (or unused), 0 next to the origin, 1 next to the insertion
  std::vector<char> used;                ///< inside the muscle, connected to both ends
  std::vector<Eigen::Vector3d> gradient; ///< per node: differences of phi over its used neighbours

  double At(Eigen::Index index) const { return this->phi[size_t(index)]; }
  /// The node nearest x; -1 beyond the grid.
  Eigen::Index Nearest(const Eigen::Vector3d& x) const
  {
    const Eigen::Vector3d local = (x - grid.origin) / grid.h;
    std::array<int, 3> at{};
    for (int d = 0; d < 3; ++d)
    {
      at[size_t(d)] = static_cast<int>(std::lround(local[d]));
      if (at[size_t(d)] < 0 || at[size_t(d)] >= grid.n[size_t(d)])
      {
        return -1;
      }
    }
    return grid.Index(at[0], at[1], at[2]);
  }
  /// Of `node` and the 26 around it, the used node nearest x; -1 for none.
  Eigen::Index NearestUsed(const Eigen::Vector3d& x, Eigen::Index node) const
  {
    const auto i = static_cast<int>(node % grid.n[0]);
    const auto j = static_cast<int>((node / grid.n[0]) % grid.n[1]);
    const auto k = static_cast<int>(node / (Eigen::Index(grid.n[0]) * grid.n[1]));
    Eigen::Index best = -1;
    double nearest = std::numeric_limits<double>::max();
    for (int dk = -1; dk <= 1; ++dk)
    {
      for (int dj = -1; dj <= 1; ++dj)
      {
        for (int di = -1; di <= 1; ++di)
        {
          const int a = i + di, b = j + dj, c = k + dk;
          if (a < 0 || b < 0 || c < 0 || a >= grid.n[0] || b >= grid.n[1] || c >= grid.n[2])
          {
            continue;
          }
          const Eigen::Index other = grid.Index(a, b, c);
          const double d = (grid.Node(other) - x).squaredNorm();
          if (this->used[size_t(other)] && d < nearest)
          {
            nearest = d;
            best = other;
          }
        }
      }
    }
    return best;
  }
  /// phi and its gradient at x (both trilinear in the cell, the gradient from the nodes'
  /// differences: along the surface where no flux crosses it); false outside the field.
  bool Sample(const Eigen::Vector3d& x, double& value, Eigen::Vector3d& direction) const
  {
    const Eigen::Vector3d local = (x - grid.origin) / grid.h;
    std::array<int, 3> cell{};
    Eigen::Vector3d f;
    for (int d = 0; d < 3; ++d)
    {
      const double floor = std::floor(local[d]);
      if (floor < 0 || floor + 1 >= grid.n[d])
      {
        return false;
      }
      cell[d] = static_cast<int>(floor);
      f[d] = local[d] - floor;
    }
    value = 0;
    direction.setZero();
    for (int dk = 0; dk < 2; ++dk)
    {
      for (int dj = 0; dj < 2; ++dj)
      {
        for (int di = 0; di < 2; ++di)
        {
          const Eigen::Index node = grid.Index(cell[0] + di, cell[1] + dj, cell[2] + dk);
          if (std::isnan(this->phi[size_t(node)]))
          {
            return false;
          }
          const double w = (di ? f[0] : 1 - f[0]) * (dj ? f[1] : 1 - f[1]) * (dk ? f[2] : 1 - f[2]);
          value += w * this->phi[size_t(node)];
          direction += w * this->gradient[size_t(node)];
        }
      }
    }
    return true;
  }
};

/// An end of the fibres as triangles: those of the surface with every corner in the end, or
/// where the end has none, its points (as triangles of one point); each with its corners' indices.
struct EndSurface
{
  std::vector<std::array<Eigen::Vector3d, 3>> corners;
  std::vector<std::array<Eigen::Index, 3>> ids;
};

EndSurface EndTriangles(const TriangleMesh& mesh, const std::vector<Eigen::Index>& end)
{
  std::vector<char> in(size_t(mesh.points.rows()), 0);
  for (Eigen::Index p : end)
  {
    in[size_t(p)] = 1;
  }
  EndSurface surface;
  std::vector<char> covered(size_t(mesh.points.rows()), 0);
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
  {
    const std::array<Eigen::Index, 3> ids{ mesh.triangles(t, 0), mesh.triangles(t, 1), mesh.triangles(t, 2) };
    if (in[size_t(ids[0])] && in[size_t(ids[1])] && in[size_t(ids[2])])
    {
      surface.corners.push_back({ mesh.points.row(ids[0]).transpose(), mesh.points.row(ids[1]).transpose(),
        mesh.points.row(ids[2]).transpose() });
      surface.ids.push_back(ids);
      covered[size_t(ids[0])] = covered[size_t(ids[1])] = covered[size_t(ids[2])] = 1;
    }
  }
  for (Eigen::Index p : end)
  {
    if (!covered[size_t(p)])
    {
      const Eigen::Vector3d x = mesh.points.row(p).transpose();
      surface.corners.push_back({ x, x, x });
      surface.ids.push_back({ p, p, p });
    }
  }
  return surface;
}

/// A point of an end's surface: its triangle's corners and its barycentric coordinates there.
struct Anchor
{
  std::array<Eigen::Index, 3> ids{};
  Eigen::Vector3d weights;
  Eigen::Vector3d point;
};

/// How a fibre's end is carried: `share` of the way from its area's point to the next fibre point.
struct FibreEnd
{
  Anchor anchor;
  double share = 0.5;
};

/// The point of `end` nearest x.
Anchor NearestAnchor(const EndSurface& end, const Eigen::Vector3d& x)
{
  Anchor best;
  double nearest = std::numeric_limits<double>::max();
  for (size_t t = 0; t < end.corners.size(); ++t)
  {
    const auto& [a, b, c] = end.corners[t];
    const Eigen::Vector3d q = ClosestPointOnTriangle(x, a, b, c);
    if ((q - x).squaredNorm() < nearest)
    {
      nearest = (q - x).squaredNorm();
      best.ids = end.ids[t];
      best.point = q;
      const Eigen::Vector3d n = (b - a).cross(c - a);
      const double area = n.squaredNorm();
      if (area > 0)
      {
        best.weights[0] = (c - b).cross(q - b).dot(n) / area;
        best.weights[1] = (a - c).cross(q - c).dot(n) / area;
        best.weights[2] = 1 - best.weights[0] - best.weights[1];
      }
      else
      {
        best.weights = Eigen::Vector3d(1, 0, 0);
      }
    }
  }
  return best;
}

/// Marks the inside nodes within `radius` of the end's triangles with `label` (the nearer end wins).
void MarkEnd(const std::vector<std::array<Eigen::Vector3d, 3>>& end, signed char label, double radius, const Grid& grid,
  const std::vector<char>& inside, Field& field, std::vector<double>& distance)
{
  for (const auto& [a, b, c] : end)
  {
    const Eigen::Vector3d low = (a.cwiseMin(b).cwiseMin(c).array() - radius - grid.origin.array()) / grid.h;
    const Eigen::Vector3d high = (a.cwiseMax(b).cwiseMax(c).array() + radius - grid.origin.array()) / grid.h;
    std::array<int, 3> from{}, to{};
    for (int d = 0; d < 3; ++d)
    {
      from[d] = std::max(0, static_cast<int>(std::ceil(low[d])));
      to[d] = std::min(grid.n[d] - 1, static_cast<int>(std::floor(high[d])));
    }
    for (int k = from[2]; k <= to[2]; ++k)
    {
      for (int j = from[1]; j <= to[1]; ++j)
      {
        for (int i = from[0]; i <= to[0]; ++i)
        {
          const Eigen::Index node = grid.Index(i, j, k);
          if (!inside[size_t(node)])
          {
            continue;
          }
          const double d = PointTriangleDistance(grid.Node(node), a, b, c);
          if (d <= radius && d < distance[size_t(node)])
          {
            distance[size_t(node)] = d;
            field.fixed[size_t(node)] = label;
          }
        }
      }
    }
  }
}

/// The harmonic field between the ends on the muscle's inside.
Field SolveField(
  const TriangleMesh& rest, const FibreEnds& ends, int gridNodes, const std::vector<const TriangleMesh*>& obstacles)
{
  const double volume = std::abs(SignedVolume(rest.points, rest.triangles));
  if (!(volume > 0))
  {
    throw InputError("the surface encloses no volume");
  }
  Field field;
  Grid& grid = field.grid;
  // The spacing rounded to two significant digits and the nodes on multiples of it: the same grid
  // for an input moved by rounding (the fibres then move by as little).
  const double spacing = std::cbrt(volume / std::max(gridNodes, 100));
  const double decade = std::pow(10.0, std::floor(std::log10(spacing)) - 1);
  grid.h = std::round(spacing / decade) * decade;
  const Eigen::Vector3d low = rest.points.colwise().minCoeff().transpose();
  const Eigen::Vector3d high = rest.points.colwise().maxCoeff().transpose();
  // Offset by fractions of the spacing no data lies on (round numbers do): no ray of the inside
  // test runs along an edge of the surface.
  grid.origin = ((low / grid.h).array().floor() - 2 + Eigen::Array3d(0.3183, 0.2718, 0.1414)).matrix() * grid.h;
  for (int d = 0; d < 3; ++d)
  {
    grid.n[d] = static_cast<int>(std::ceil((high[d] - grid.origin[d]) / grid.h)) + 3;
  }
  std::vector<char> inside = InsideNodes(rest, grid);
  for (const TriangleMesh* obstacle : obstacles)
  {
    const std::vector<char> in = InsideNodes(*obstacle, grid);
    for (size_t node = 0; node < inside.size(); ++node)
    {
      inside[node] = static_cast<char>(inside[node] && !in[node]);
    }
  }
  field.fixed.assign(size_t(grid.Size()), -1);
  field.phi.assign(size_t(grid.Size()), kNaN);
  // The ends: the inside nodes next to each end's points, the reach grown until both have some.
  for (double reach : { 1.5, 2.5, 4.0 })
  {
    std::fill(field.fixed.begin(), field.fixed.end(), -1);
    std::vector<double> distance(size_t(grid.Size()), std::numeric_limits<double>::max());
    MarkEnd(EndTriangles(rest, ends.origin).corners, 0, reach * grid.h, grid, inside, field, distance);
    MarkEnd(EndTriangles(rest, ends.insertion).corners, 1, reach * grid.h, grid, inside, field, distance);
    if (std::count(field.fixed.begin(), field.fixed.end(), 0) && std::count(field.fixed.begin(), field.fixed.end(), 1))
    {
      break;
    }
  }
  for (signed char label : { 0, 1 })
  {
    if (!std::count(field.fixed.begin(), field.fixed.end(), label))
    {
      throw InputError(std::string("no inside of the muscle next to its ") + (label ? "insertion" : "origin"));
    }
  }
  // The inside nodes connected to both ends.
  std::vector<int> component(size_t(grid.Size()), -1);
  std::vector<char>& used = field.used;
  used.assign(size_t(grid.Size()), 0);
  int components = 0;
  for (Eigen::Index start = 0; start < grid.Size(); ++start)
  {
    if (!inside[size_t(start)] || component[size_t(start)] >= 0)
    {
      continue;
    }
    std::vector<Eigen::Index> members{ start };
    component[size_t(start)] = components;
    std::array<bool, 2> touches{ false, false };
    for (size_t next = 0; next < members.size(); ++next)
    {
      const Eigen::Index node = members[next];
      if (field.fixed[size_t(node)] >= 0)
      {
        touches[size_t(field.fixed[size_t(node)])] = true;
      }
      for (Eigen::Index neighbour : grid.Neighbours(node))
      {
        if (neighbour >= 0 && inside[size_t(neighbour)] && component[size_t(neighbour)] < 0)
        {
          component[size_t(neighbour)] = components;
          members.push_back(neighbour);
        }
      }
    }
    if (touches[0] && touches[1])
    {
      for (Eigen::Index node : members)
      {
        used[size_t(node)] = 1;
      }
    }
    ++components;
  }
  if (!std::count(used.begin(), used.end(), 1))
  {
    throw InputError("its origin and insertion are not connected inside the muscle");
  }
  // Laplace's equation on the free used nodes (the graph Laplacian: no flux to unused nodes).
  std::vector<Eigen::Index> unknown(size_t(grid.Size()), -1);
  Eigen::Index unknowns = 0;
  for (Eigen::Index node = 0; node < grid.Size(); ++node)
  {
    if (used[size_t(node)] && field.fixed[size_t(node)] < 0)
    {
      unknown[size_t(node)] = unknowns++;
    }
  }
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(unknowns);
  for (Eigen::Index node = 0; node < grid.Size(); ++node)
  {
    const Eigen::Index row = unknown[size_t(node)];
    if (row < 0)
    {
      continue;
    }
    double degree = 0;
    for (Eigen::Index neighbour : grid.Neighbours(node))
    {
      if (neighbour < 0 || !used[size_t(neighbour)])
      {
        continue;
      }
      degree += 1;
      if (unknown[size_t(neighbour)] >= 0)
      {
        entries.emplace_back(row, unknown[size_t(neighbour)], -1.0);
      }
      else
      {
        rhs[row] += field.fixed[size_t(neighbour)];
      }
    }
    entries.emplace_back(row, row, degree);
  }
  Eigen::SparseMatrix<double> laplacian(unknowns, unknowns);
  laplacian.setFromTriplets(entries.begin(), entries.end());
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper, Eigen::IncompleteCholesky<double>>
    solver;
  solver.setTolerance(kFieldTolerance);
  solver.setMaxIterations(static_cast<Eigen::Index>(unknowns));
  solver.compute(laplacian);
  const Eigen::VectorXd solution = solver.solve(rhs);
  if (solver.info() != Eigen::Success)
  {
    throw Error("the fibres' field could not be solved");
  }
  for (Eigen::Index node = 0; node < grid.Size(); ++node)
  {
    if (used[size_t(node)])
    {
      field.phi[size_t(node)] =
        unknown[size_t(node)] >= 0 ? solution[unknown[size_t(node)]] : field.fixed[size_t(node)];
    }
    else
    {
      field.fixed[size_t(node)] = -1;
    }
  }
  // Two layers beyond the used nodes (their neighbours' mean) so that every cell a streamline
  // crosses near the surface has all its corners.
  for (int layer = 0; layer < 2; ++layer)
  {
    std::vector<double> extended = field.phi;
    for (Eigen::Index node = 0; node < grid.Size(); ++node)
    {
      if (!std::isnan(field.phi[size_t(node)]))
      {
        continue;
      }
      double sum = 0;
      int count = 0;
      for (Eigen::Index neighbour : grid.Neighbours(node))
      {
        if (neighbour >= 0 && !std::isnan(field.phi[size_t(neighbour)]))
        {
          sum += field.phi[size_t(neighbour)];
          ++count;
        }
      }
      if (count)
      {
        extended[size_t(node)] = sum / count;
      }
    }
    field.phi.swap(extended);
  }
  field.gradient.assign(size_t(grid.Size()), Eigen::Vector3d::Zero());
  for (Eigen::Index node = 0; node < grid.Size(); ++node)
  {
    if (std::isnan(field.phi[size_t(node)]))
    {
      continue;
    }
    const std::array<Eigen::Index, 6> around = grid.Neighbours(node);
    for (int d = 0; d < 3; ++d)
    {
      const Eigen::Index below = around[2 * size_t(d)], above = around[2 * size_t(d) + 1];
      const bool hasBelow = below >= 0 && !std::isnan(field.phi[size_t(below)]);
      const bool hasAbove = above >= 0 && !std::isnan(field.phi[size_t(above)]);
      const double here = field.phi[size_t(node)];
      if (hasBelow && hasAbove)
      {
        field.gradient[size_t(node)][d] = (field.phi[size_t(above)] - field.phi[size_t(below)]) / (2 * grid.h);
      }
      else if (hasBelow || hasAbove)
      {
        field.gradient[size_t(node)][d] =
          hasAbove ? (field.phi[size_t(above)] - here) / grid.h : (here - field.phi[size_t(below)]) / grid.h;
      }
    }
  }
  return field;
}

/// Where the level set phi = `level` crosses the grid's edges between used nodes.
std::vector<Eigen::Vector3d> LevelCrossings(const Field& field, double level)
{
  const Grid& grid = field.grid;
  std::vector<Eigen::Vector3d> crossings;
  for (Eigen::Index node = 0; node < grid.Size(); ++node)
  {
    const double here = field.At(node);
    if (!field.used[size_t(node)] || !(here < level))
    {
      continue;
    }
    for (Eigen::Index neighbour : grid.Neighbours(node))
    {
      if (neighbour >= 0 && field.used[size_t(neighbour)] && field.At(neighbour) >= level)
      {
        const double t = (level - here) / (field.At(neighbour) - here);
        crossings.push_back(grid.Node(node) + t * (grid.Node(neighbour) - grid.Node(node)));
      }
    }
  }
  return crossings;
}

/// Seeds on the level set of the field's median over the inside (the muscle's belly: next to a
/// small tendon end the field is steep and its level sets small; every streamline from the
/// origin to the insertion crosses it once), spread by farthest point sampling (at most `count`).
std::vector<Eigen::Vector3d> Seeds(const Field& field, size_t count)
{
  std::vector<double> values;
  for (Eigen::Index node = 0; node < field.grid.Size(); ++node)
  {
    if (field.used[size_t(node)] && field.fixed[size_t(node)] < 0)
    {
      values.push_back(field.At(node));
    }
  }
  std::vector<Eigen::Vector3d> seeds;
  if (values.empty())
  {
    return seeds;
  }
  std::nth_element(values.begin(), values.begin() + long(values.size() / 2), values.end());
  const std::vector<Eigen::Vector3d> candidates = LevelCrossings(field, values[values.size() / 2]);
  if (candidates.empty())
  {
    return seeds;
  }
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& c : candidates)
  {
    centre += c;
  }
  centre /= static_cast<double>(candidates.size());
  std::vector<double> distance(candidates.size());
  for (size_t i = 0; i < candidates.size(); ++i)
  {
    distance[i] = (candidates[i] - centre).squaredNorm();
  }
  // The first seed nearest the centre; each next the candidate farthest from those chosen.
  size_t next = size_t(std::min_element(distance.begin(), distance.end()) - distance.begin());
  std::fill(distance.begin(), distance.end(), std::numeric_limits<double>::max());
  while (seeds.size() < std::min(count, candidates.size()))
  {
    seeds.push_back(candidates[next]);
    for (size_t i = 0; i < candidates.size(); ++i)
    {
      distance[i] = std::min(distance[i], (candidates[i] - seeds.back()).squaredNorm());
    }
    next = size_t(std::max_element(distance.begin(), distance.end()) - distance.begin());
    if (distance[next] == 0)
    {
      break;
    }
  }
  return seeds;
}

/// The streamline of grad phi from `seed` up to the insertion (`towards` 1) or down to the
/// origin (`towards` 0), in midpoint steps of h / 2; empty when it leaves the field or stalls
/// away from its end.
std::vector<Eigen::Vector3d> Streamline(const Field& field, const Eigen::Vector3d& seed, double longest, int towards)
{
  const double step = field.grid.h / 2;
  const double sign = towards == 1 ? 1.0 : -1.0;
  // Progress towards the end: phi going up to 1, or down to 0.
  const auto progress = [&](double value) {
    return towards == 1 ? value : 1 - value;
  };
  const int most = static_cast<int>(std::ceil(4 * longest / step));
  std::vector<Eigen::Vector3d> line{ seed };
  Eigen::Vector3d x = seed;
  double last = 0; // progress at the last point sampled
  for (int s = 0; s < most; ++s)
  {
    double value = 0;
    Eigen::Vector3d gradient, middle;
    const bool sampled = field.Sample(x, value, gradient);
    if (sampled && progress(value) >= kArrived)
    {
      // Ends where it crossed kArrived (between its last two points): not a step on.
      if (line.size() >= 2 && progress(value) > last && last < kArrived)
      {
        const double t = (kArrived - last) / (progress(value) - last);
        line.back() = line[line.size() - 2] + t * (line.back() - line[line.size() - 2]);
      }
      return line;
    }
    if (!sampled || !(gradient.norm() > 0))
    {
      // Off the field or where it is flat: next to its end (within its marked nodes' reach), it
      // has arrived; anywhere else, it is lost.
      return last >= kNearEnd ? line : std::vector<Eigen::Vector3d>{};
    }
    last = progress(value);
    const Eigen::Vector3d half = x + 0.5 * step * sign * gradient.normalized();
    if (!field.Sample(half, value, middle) || !(middle.norm() > 0))
    {
      return last >= kNearEnd ? line : std::vector<Eigen::Vector3d>{};
    }
    x += step * sign * middle.normalized();
    const Eigen::Index node = field.Nearest(x);
    if (node < 0)
    {
      return {};
    }
    if (!field.used[size_t(node)])
    {
      // Drifted beyond the inside (the discrete field's flux through the surface is not quite
      // nil): back halfway towards the nearest inside node.
      const Eigen::Index back = field.NearestUsed(x, node);
      if (back < 0)
      {
        return {};
      }
      x = 0.5 * (x + field.grid.Node(back));
    }
    line.push_back(x);
  }
  return {};
}

/// The outward angle-weighted pseudo-normal (Baerentzen & Aanaes 2005) at `closest`, the point of
/// the tree's surface nearest some x, of the feature it lies on (the triangle, an edge or a
/// corner): x - closest is along it outside and against it inside, for a closed surface.
/// `around` lists each point's triangles; without it (an obstacle), none on an edge or a corner.
std::optional<Eigen::Vector3d> OuterNormal(
  const TriangleTree& tree, const TriangleTree::Closest& closest, const std::vector<std::vector<Eigen::Index>>* around)
{
  const Triangles& triangles = tree.Mesh().triangles;
  const Points& points = tree.Mesh().points;
  const auto corner = [&](Eigen::Index t, int c) -> Eigen::Vector3d {
    return points.row(triangles(t, c)).transpose();
  };
  const auto normal = [&](Eigen::Index t) -> Eigen::Vector3d {
    return (corner(t, 1) - corner(t, 0)).cross(corner(t, 2) - corner(t, 0));
  };
  const Eigen::Index t = closest.triangle;
  const Eigen::Vector3d n = normal(t);
  const double area = n.squaredNorm();
  const Eigen::Vector3d& q = closest.point;
  std::array<double, 3> bary{};
  if (area > 0)
  {
    bary[0] = (corner(t, 2) - corner(t, 1)).cross(q - corner(t, 1)).dot(n) / area;
    bary[1] = (corner(t, 0) - corner(t, 2)).cross(q - corner(t, 2)).dot(n) / area;
    bary[2] = 1 - bary[0] - bary[1];
  }
  constexpr double kOnFeature = 1e-9;
  const int onEdges =
    static_cast<int>(std::count_if(bary.begin(), bary.end(), [](double b) { return b <= kOnFeature; }));
  if (area > 0 && onEdges == 0)
  {
    return n;
  }
  if (!around || !(area > 0))
  {
    return std::nullopt;
  }
  Eigen::Vector3d pseudo = Eigen::Vector3d::Zero();
  if (onEdges == 1)
  {
    // On the edge opposite the corner whose coordinate is 0: its two triangles' normals.
    const int opposite = static_cast<int>(std::min_element(bary.begin(), bary.end()) - bary.begin());
    const Eigen::Index a = triangles(t, (opposite + 1) % 3), b = triangles(t, (opposite + 2) % 3);
    for (Eigen::Index other : (*around)[size_t(a)])
    {
      if ((triangles.row(other).array() == b).any())
      {
        pseudo += normal(other).normalized();
      }
    }
  }
  else
  {
    // On a corner: its triangles' normals weighted by their angles there.
    const int at = static_cast<int>(std::max_element(bary.begin(), bary.end()) - bary.begin());
    const Eigen::Index p = triangles(t, at);
    for (Eigen::Index other : (*around)[size_t(p)])
    {
      int c = 0;
      while (triangles(other, c) != p)
      {
        ++c;
      }
      const Eigen::Vector3d e1 = corner(other, (c + 1) % 3) - corner(other, c);
      const Eigen::Vector3d e2 = corner(other, (c + 2) % 3) - corner(other, c);
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      pseudo += angle * normal(other).normalized();
    }
  }
  return pseudo;
}

bool OnOuterSide(const TriangleTree& tree, const TriangleTree::Closest& closest, const Eigen::Vector3d& x,
  const std::vector<std::vector<Eigen::Index>>* around = nullptr)
{
  const std::optional<Eigen::Vector3d> normal = OuterNormal(tree, closest, around);
  return normal ? (x - closest.point).dot(*normal) > 0 : !tree.Inside(x);
}

/// Where x breaks the rules, if anywhere: the muscle's wall it is outside of, or the obstacle
/// it is inside of (the surface's point nearest it), searched within `reach`.
struct Breach
{
  bool outsideMuscle = false, insideObstacle = false;
  Eigen::Vector3d wall, obstacle;
};

/// An obstacle as a query needs it: the tree, and the motions to its pose and back.
struct PlacedObstacle
{
  const TriangleTree* tree;
  RigidTransform toNow, toTree;
};

Breach Check(const Eigen::Vector3d& x, double reach, const TriangleTree& muscle, Eigen::Index hint,
  const std::vector<std::vector<Eigen::Index>>& around, const std::vector<PlacedObstacle>& obstacles)
{
  Breach breach;
  const TriangleTree::Closest wall = muscle.ClosestPoint(x, reach, hint);
  // The nearest wall's side decides locally, and cheaply; where the surface folds through itself
  // it flips between two sheets under the slightest change of x, so an outside is confirmed by the
  // winding number, which changes only where x crosses the surface.
  if (wall.triangle >= 0 && OnOuterSide(muscle, wall, x, &around) && muscle.Winding(x) == 0)
  {
    breach.outsideMuscle = true;
    breach.wall = wall.point;
  }
  for (const PlacedObstacle& obstacle : obstacles)
  {
    const Eigen::Vector3d there = obstacle.toTree.Apply(x);
    if (!obstacle.tree->InBounds(there))
    {
      continue;
    }
    // Searched as far as the point may be inside: by the obstacle's distance grid (none needed
    // where it is surely outside), else a few reaches.
    double radius = kObstacleReach * reach;
    if (const auto bounds = obstacle.tree->SignedDistanceBounds(there))
    {
      if (bounds->first > 0)
      {
        continue;
      }
      radius = std::max(-bounds->first, bounds->second);
    }
    const TriangleTree::Closest bone = obstacle.tree->ClosestPoint(there, radius);
    if (bone.triangle >= 0 && !OnOuterSide(*obstacle.tree, bone, there))
    {
      breach.insideObstacle = true;
      breach.obstacle = obstacle.toNow.Apply(bone.point);
      break;
    }
  }
  return breach;
}

/// Keeps x inside `muscle` and out of `obstacles`: 0 where it was, 1 moved, 2 could not be kept
/// in (then where it was). Outside the muscle, x goes `depth` below the wall it left; inside an
/// obstacle, half that out of it (the muscle may lie on it); where the muscle's wall lies closer
/// to the obstacle than that, halfway between the two.
int KeepInside(Eigen::Vector3d& x, double depth, double reach, const TriangleTree& muscle, Eigen::Index hint,
  const std::vector<std::vector<Eigen::Index>>& around, const std::vector<PlacedObstacle>& obstacles)
{
  const Eigen::Vector3d carried = x;
  Breach breach = Check(x, reach, muscle, hint, around, obstacles);
  if (!breach.outsideMuscle && !breach.insideObstacle)
  {
    return 0;
  }
  std::optional<Eigen::Vector3d> wall, obstacle;
  for (int round = 0; round < 4; ++round)
  {
    if (breach.outsideMuscle)
    {
      wall = breach.wall;
      x = breach.wall - depth * (x - breach.wall).normalized();
    }
    else if (breach.insideObstacle)
    {
      obstacle = breach.obstacle;
      x = breach.obstacle + 0.5 * depth * (breach.obstacle - x).normalized();
    }
    if (wall && obstacle && round > 0)
    {
      x = 0.5 * (*wall + *obstacle);
    }
    breach = Check(x, reach, muscle, hint, around, obstacles);
    if (!breach.outsideMuscle && !breach.insideObstacle)
    {
      return 1;
    }
  }
  x = carried;
  return 2;
}

/// Mean value weights of `x` with the smallest left out, continuously (a weight that crosses the
/// threshold enters from nothing, so that the carried point does not jump under a small change of
/// the input): the threshold tau is where the weights, largest first, reach `share` of their
/// absolute sum (interpolated between two weights); a weight of at least 2 tau is kept whole, one
/// between tau and 2 tau fades in smoothly, the rest is dropped. The kept points are as many more
/// as make them span space (next to a flat part of the surface the largest weights are all on
/// it). Last, the kept weights are corrected to sum to 1 and reproduce x from the rest surface.
void KeepLargest(const Points& surface, const Eigen::Vector3d& x, const Eigen::RowVectorXd& weights, double share,
  std::vector<Eigen::Triplet<float, int>>& entries, Eigen::Index row)
{
  std::vector<Eigen::Index> order(size_t(weights.size()));
  std::iota(order.begin(), order.end(), Eigen::Index(0));
  std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) {
    return std::abs(weights[a]) > std::abs(weights[b]) || (std::abs(weights[a]) == std::abs(weights[b]) && a < b);
  });
  const double total = weights.cwiseAbs().sum();
  double tau = 0, cumulative = 0;
  for (size_t i = 0; i < order.size(); ++i)
  {
    const double here = std::abs(weights[order[i]]);
    if (cumulative + here >= share * total)
    {
      const double next = i + 1 < order.size() ? std::abs(weights[order[i + 1]]) : 0.0;
      const double f = here > 0 ? (share * total - cumulative) / here : 0.0;
      tau = here + f * (next - here);
      break;
    }
    cumulative += here;
  }
  const auto fade = [&](double size) {
    if (size >= 2 * tau)
    {
      return 1.0;
    }
    const double t = tau > 0 ? std::clamp(size / tau - 1, 0.0, 1.0) : 1.0;
    return t * t * (3 - 2 * t);
  };
  size_t count = 0;
  while (count < order.size() && (std::abs(weights[order[count]]) > tau || count < 4))
  {
    ++count;
  }
  // Constraints sum w (v - x) / size = 0 and sum w = 1 on the kept points.
  const double size = (surface.rowwise() - x.transpose()).rowwise().norm().maxCoeff();
  const auto constraintOf = [&](size_t n) {
    Eigen::Matrix<double, 4, Eigen::Dynamic> constraint(4, static_cast<Eigen::Index>(n));
    for (size_t i = 0; i < n; ++i)
    {
      constraint.col(Eigen::Index(i)) << (surface.row(order[i]).transpose() - x) / size, 1.0;
    }
    return constraint;
  };
  constexpr double kSpanning = 1e-10; // smallest over largest eigenvalue of the constraints' Gram matrix
  Eigen::Matrix<double, 4, Eigen::Dynamic> constraint = constraintOf(count);
  for (;;)
  {
    const Eigen::Vector4d eigen =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(constraint * constraint.transpose(), Eigen::EigenvaluesOnly)
        .eigenvalues();
    if (eigen[0] > kSpanning * eigen[3] || count == order.size())
    {
      break;
    }
    count = std::min(order.size(), 2 * count);
    constraint = constraintOf(count);
  }
  Eigen::VectorXd w(static_cast<Eigen::Index>(count));
  for (size_t i = 0; i < count; ++i)
  {
    w[Eigen::Index(i)] = weights[order[i]] * fade(std::abs(weights[order[i]]));
  }
  const Eigen::Vector4d residual = Eigen::Vector4d(0, 0, 0, 1) - constraint * w;
  w += constraint.transpose() * (constraint * constraint.transpose()).ldlt().solve(residual);
  for (size_t i = 0; i < count; ++i)
  {
    entries.emplace_back(static_cast<int>(row), static_cast<int>(order[i]), static_cast<float>(w[Eigen::Index(i)]));
  }
}

/// Fibres traced through the field on a grid of about `gridNodes` nodes inside the muscle (see
/// MuscleFibres::MuscleFibres), each with how its ends are carried; `free` says whether a point
/// is inside the muscle and out of the obstacles. Throws InputError where SolveField does.
struct TracedFibres
{
  int gridNodes = 0;
  double spacing = 0; ///< the grid's
  std::vector<Points> fibres;
  std::vector<std::array<FibreEnd, 2>> ends; ///< per fibre, how each end is carried
};

template<typename Free>
TracedFibres TraceFibres(const TriangleMesh& rest, const FibreEnds& given, const FibreParameters& parameters,
  int gridNodes, const std::vector<const TriangleMesh*>& obstacles, const Free& free)
{
  const Field field = SolveField(rest, given, gridNodes, obstacles);
  TracedFibres traced;
  traced.spacing = field.grid.h;
  traced.gridNodes = gridNodes;
  std::vector<Points>& fibres = traced.fibres;
  std::vector<std::array<FibreEnd, 2>>& ends = traced.ends;
  const double longest = BoxDiagonal(rest.points);
  const auto wanted = size_t(parameters.count);
  const EndSurface origin = EndTriangles(rest, given.origin), insertion = EndTriangles(rest, given.insertion);
  // Three times the seeds asked for: a streamline that stalls or leaves the muscle is replaced.
  for (const Eigen::Vector3d& seed : Seeds(field, 3 * wanted))
  {
    if (fibres.size() == wanted)
    {
      break;
    }
    std::vector<Eigen::Vector3d> up = Streamline(field, seed, longest, 1);
    std::vector<Eigen::Vector3d> line = Streamline(field, seed, longest, 0);
    if (up.empty() || line.empty() || up.size() + line.size() < 3)
    {
      continue;
    }
    std::reverse(line.begin(), line.end()); // from the origin to the seed, then on to the insertion
    line.insert(line.end(), up.begin() + 1, up.end());
    // The inner points at equal arc lengths; each end on the segment from its area's point
    // nearest the fibre's next point to that point, halfway (or farther in, to be inside).
    const Points innerPoints = ResampleByArcLength(line, parameters.pointsPerFibre - 2);
    Points fibre(parameters.pointsPerFibre, 3);
    fibre.middleRows(1, parameters.pointsPerFibre - 2) = innerPoints;
    std::array<FibreEnd, 2> closing;
    bool inside = true;
    for (int side = 0; side < 2 && inside; ++side)
    {
      const Eigen::Vector3d next = innerPoints.row(side == 0 ? 0 : innerPoints.rows() - 1).transpose();
      closing[size_t(side)].anchor = NearestAnchor(side == 0 ? origin : insertion, next);
      inside = false;
      for (double share : { 0.5, 0.7, 0.9 })
      {
        const Eigen::Vector3d end =
          closing[size_t(side)].anchor.point + share * (next - closing[size_t(side)].anchor.point);
        if (free(end))
        {
          closing[size_t(side)].share = share;
          fibre.row(side == 0 ? 0 : parameters.pointsPerFibre - 1) = end.transpose();
          inside = true;
          break;
        }
      }
    }
    for (Eigen::Index p = 1; p + 1 < fibre.rows() && inside; ++p)
    {
      inside = free(fibre.row(p).transpose());
    }
    if (inside)
    {
      fibres.push_back(std::move(fibre));
      ends.push_back(closing);
    }
  }
  return traced;
}

}

FibreEnds FindFibreEnds(
  const TriangleMesh& rest, const std::vector<Attachment>& attachments, const std::vector<Points>& restLines)
{
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
  for (const Points& line : restLines)
  {
    if (line.rows() >= 2)
    {
      direction += (line.row(line.rows() - 1) - line.row(0)).transpose().normalized();
    }
  }
  if (!(direction.norm() > 0) || !direction.allFinite())
  {
    throw InputError("its action lines have no length, so the fibres have no direction");
  }
  direction.normalize();
  FibreEnds ends;
  for (const Attachment& area : attachments)
  {
    if (area.points.empty())
    {
      continue;
    }
    const Eigen::Vector3d centre = Centroid(rest.points, area.points);
    double toFirst = std::numeric_limits<double>::max(), toLast = toFirst;
    for (const Points& line : restLines)
    {
      toFirst = std::min(toFirst, (line.row(0).transpose() - centre).norm());
      toLast = std::min(toLast, (line.row(line.rows() - 1).transpose() - centre).norm());
    }
    auto& end = toFirst <= toLast ? ends.origin : ends.insertion;
    auto& source = toFirst <= toLast ? ends.originSource : ends.insertionSource;
    end.insert(end.end(), area.points.begin(), area.points.end());
    if (source.find(" " + area.bone) == std::string::npos || source.empty())
    {
      source += (source.empty() ? "its area on " : " and on ") + area.bone;
    }
  }
  const Eigen::VectorXd along = rest.points * direction;
  const std::vector<char> usedPoints = UsedMask(rest);
  double low = std::numeric_limits<double>::max(), high = -low;
  for (Eigen::Index p = 0; p < rest.points.rows(); ++p)
  {
    if (usedPoints[size_t(p)])
    {
      low = std::min(low, along[p]);
      high = std::max(high, along[p]);
    }
  }
  const double cap = kCapShare * (high - low);
  for (int side = 0; side < 2; ++side)
  {
    auto& end = side == 0 ? ends.origin : ends.insertion;
    if (!end.empty())
    {
      std::sort(end.begin(), end.end());
      end.erase(std::unique(end.begin(), end.end()), end.end());
      continue;
    }
    for (Eigen::Index p = 0; p < rest.points.rows(); ++p)
    {
      if (usedPoints[size_t(p)] && (side == 0 ? along[p] <= low + cap : along[p] >= high - cap))
      {
        end.push_back(p);
      }
    }
    (side == 0 ? ends.originSource : ends.insertionSource) = "its end along its action lines";
  }
  return ends;
}

MuscleFibres::MuscleFibres(const TriangleMesh& rest, const FibreEnds& given, const FibreParameters& parameters,
  const std::vector<const TriangleMesh*>& obstacles)
{
  if (given.origin.empty() || given.insertion.empty())
  {
    throw InputError("the fibres need an origin and an insertion");
  }
  if (parameters.count < 1 || parameters.pointsPerFibre < 3)
  {
    throw InputError("the fibres need a count of at least 1 and at least 3 points each");
  }
  const TriangleTree tree(rest);
  std::vector<TriangleTree> obstacleTrees;
  for (const TriangleMesh* obstacle : obstacles)
  {
    obstacleTrees.emplace_back(*obstacle);
  }
  // Inside the muscle and outside every obstacle.
  const auto free = [&](const Eigen::Vector3d& x) {
    return tree.Inside(x) && std::none_of(obstacleTrees.begin(), obstacleTrees.end(), [&](const TriangleTree& o) {
      return o.InBounds(x) && o.Inside(x);
    });
  };
  // A muscle too slender for its grid (no inside next to an end, the ends not joined, or few
  // streamlines that stay inside) is traced once more on a grid of four times the nodes; the
  // attempt with more fibres is kept.
  const auto wanted = size_t(parameters.count);
  TracedFibres traced;
  std::string firstError;
  int nodes = parameters.gridNodes;
  for (int attempt = 0; attempt < 2 && 2 * traced.fibres.size() < wanted; ++attempt, nodes *= 4)
  {
    try
    {
      TracedFibres more = TraceFibres(rest, given, parameters, nodes, obstacles, free);
      if (more.fibres.size() > traced.fibres.size())
      {
        traced = std::move(more);
      }
    }
    catch (const InputError& error)
    {
      firstError = firstError.empty() ? error.what() : firstError;
    }
  }
  std::vector<Points>& fibres = traced.fibres;
  std::vector<std::array<FibreEnd, 2>>& ends = traced.ends;
  if (fibres.empty())
  {
    throw InputError(firstError.empty() ? "no fibre could be traced from its origin to its insertion" : firstError);
  }
  if (traced.gridNodes != parameters.gridNodes)
  {
    this->Said.push_back("traced on a grid of " + std::to_string(traced.gridNodes) + " nodes, not " +
      std::to_string(parameters.gridNodes) + ": the muscle is too slender for that");
  }
  if (fibres.size() < wanted)
  {
    this->Said.push_back(
      std::to_string(fibres.size()) + " fibres, not " + std::to_string(wanted) + ": the others could not be traced");
  }
  this->Fibres = static_cast<int>(fibres.size());
  this->PerFibre = parameters.pointsPerFibre;
  this->RestPoints.resize(Eigen::Index(this->Fibres) * this->PerFibre, 3);
  for (size_t f = 0; f < fibres.size(); ++f)
  {
    this->RestPoints.middleRows(Eigen::Index(f) * this->PerFibre, this->PerFibre) = fibres[f];
  }
  // Inner points by their mean value weights (sparse); a fibre's ends, near the surface, as the
  // point of the segment between the area's point (carried by its triangle's corners, exactly
  // with the surface) and the next fibre point: the mean value weights of a point that near the
  // surface are all on the few points around it, and a sparse row there would depend on their
  // choice (on the input's rounding) many times over.
  std::vector<Eigen::Index> inner;
  for (Eigen::Index p = 0; p < this->RestPoints.rows(); ++p)
  {
    if (p % this->PerFibre != 0 && p % this->PerFibre != this->PerFibre - 1)
    {
      inner.push_back(p);
    }
  }
  Points innerPoints(static_cast<Eigen::Index>(inner.size()), 3);
  for (size_t i = 0; i < inner.size(); ++i)
  {
    innerPoints.row(Eigen::Index(i)) = this->RestPoints.row(inner[i]);
  }
  const WeightMatrix dense = MeanValueCoordinates(rest, innerPoints);
  std::vector<std::vector<Eigen::Triplet<float, int>>> rows(size_t(this->RestPoints.rows()));
  for (size_t i = 0; i < inner.size(); ++i)
  {
    KeepLargest(rest.points, innerPoints.row(Eigen::Index(i)).transpose(), dense.row(Eigen::Index(i)),
      parameters.keptWeightShare, rows[size_t(inner[i])], inner[i]);
  }
  for (int f = 0; f < this->Fibres; ++f)
  {
    for (int side = 0; side < 2; ++side)
    {
      // (1 - share) of the area's point (its triangle's corners) and share of the next point,
      // the next point added once it is carried (its weights not repeated: fewer to read).
      const FibreEnd& end = ends[size_t(f)][size_t(side)];
      const Eigen::Index p = Eigen::Index(f) * this->PerFibre + (side == 0 ? 0 : this->PerFibre - 1);
      const Eigen::Index next = side == 0 ? p + 1 : p - 1;
      for (int c = 0; c < 3; ++c)
      {
        rows[size_t(p)].emplace_back(static_cast<int>(p), static_cast<int>(end.anchor.ids[size_t(c)]),
          static_cast<float>((1 - end.share) * end.anchor.weights[c]));
      }
      this->EndBlends.push_back({ p, next, end.share });
    }
  }
  std::vector<Eigen::Triplet<float, int>> entries;
  for (const auto& row : rows)
  {
    entries.insert(entries.end(), row.begin(), row.end());
  }
  this->RestTriangles = rest.triangles;
  this->Around.assign(size_t(rest.points.rows()), {});
  for (Eigen::Index t = 0; t < rest.triangles.rows(); ++t)
  {
    for (int c = 0; c < 3; ++c)
    {
      this->Around[size_t(rest.triangles(t, c))].push_back(t);
    }
  }
  this->RestTree = std::make_shared<const TriangleTree>(tree);
  this->Depth.resize(this->RestPoints.rows());
  this->NearestWall.resize(size_t(this->RestPoints.rows()));
  this->Reach = kEscapeReach * traced.spacing;
  for (Eigen::Index p = 0; p < this->RestPoints.rows(); ++p)
  {
    const Eigen::Vector3d x = this->RestPoints.row(p).transpose();
    const TriangleTree::Closest wall = tree.ClosestPoint(x);
    this->NearestWall[size_t(p)] = wall.triangle;
    double depth = wall.distance;
    for (const TriangleTree& o : obstacleTrees)
    {
      const TriangleTree::Closest nearest = o.ClosestPoint(x, depth);
      depth = nearest.triangle >= 0 ? nearest.distance : depth;
    }
    this->Depth[p] = std::min(depth, kFibreClearance * traced.spacing);
  }
  this->Weights.resize(this->RestPoints.rows(), rest.points.rows());
  this->Weights.setFromTriplets(entries.begin(), entries.end());
}

std::optional<RigidTransform> RigidMotionOf(const Points& rest, const Points& now, double tolerance)
{
  if (rest.rows() != now.rows() || rest.rows() == 0)
  {
    return std::nullopt;
  }
  // Fitted to a few hundred points spread over the surface, then checked at every point.
  const Eigen::Index stride = std::max<Eigen::Index>(1, rest.rows() / 500);
  const Eigen::Index sampled = (rest.rows() + stride - 1) / stride;
  Points from(sampled, 3), to(sampled, 3);
  for (Eigen::Index i = 0; i < sampled; ++i)
  {
    from.row(i) = rest.row(i * stride);
    to.row(i) = now.row(i * stride);
  }
  const RigidTransform motion = FitRigidTransform(from, to).transform;
  const double squared = tolerance * tolerance;
  int beyond = 0; // points off the motion by more than the tolerance (or not finite)
#pragma omp parallel for schedule(static) reduction(+ : beyond)
  for (Eigen::Index p = 0; p < rest.rows(); ++p)
  {
    beyond +=
      !((motion.rotation * rest.row(p).transpose() + motion.translation - now.row(p).transpose()).squaredNorm() <=
        squared);
  }
  return beyond == 0 ? std::optional<RigidTransform>(motion) : std::nullopt;
}

Points MuscleFibres::At(const Points& surface, const std::vector<FibreObstacle>& given, std::pair<int, int>* kept) const
{
  std::vector<PlacedObstacle> obstacles;
  for (const FibreObstacle& o : given)
  {
    obstacles.push_back({ o.tree, o.toNow, Inverse(o.toNow) });
  }
  // Four lanes a point (the fourth zero), read through raw pointers: a frame reads every weight.
  Eigen::Matrix<double, 4, Eigen::Dynamic> padded(4, surface.rows());
  padded.topRows<3>() = surface.transpose();
  padded.row(3).setZero();
  Points points(this->Weights.rows(), 3);
  const float* values = this->Weights.valuePtr();
  const int* columns = this->Weights.innerIndexPtr();
  const int* starts = this->Weights.outerIndexPtr();
#pragma omp parallel for schedule(static)
  for (Eigen::Index p = 0; p < points.rows(); ++p)
  {
    Eigen::Array4d x = Eigen::Array4d::Zero();
    for (int k = starts[p]; k < starts[p + 1]; ++k)
    {
      x += static_cast<double>(values[k]) * padded.col(columns[k]).array();
    }
    points.row(p) = x.head<3>().matrix().transpose();
  }
  for (const EndBlend& end : this->EndBlends)
  {
    points.row(end.point) += end.share * points.row(end.next);
  }
  TriangleTree tree = *this->RestTree;
  tree.Refit(surface);
  int moved = 0, stuck = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : moved, stuck)
  for (Eigen::Index p = 0; p < points.rows(); ++p)
  {
    Eigen::Vector3d x = points.row(p).transpose();
    const int result =
      KeepInside(x, this->Depth[p], this->Reach, tree, this->NearestWall[size_t(p)], this->Around, obstacles);
    moved += result > 0;
    stuck += result > 1;
    points.row(p) = x.transpose();
  }
  if (kept)
  {
    *kept = { moved, stuck };
  }
  return points;
}

std::vector<double> MuscleFibres::Lengths(const Points& points) const
{
  std::vector<double> lengths;
  for (int f = 0; f < this->Fibres; ++f)
  {
    lengths.push_back(PolylineLength(points.middleRows(Eigen::Index(f) * this->PerFibre, this->PerFibre)));
  }
  return lengths;
}

double MuscleFibres::MeanWeightsPerPoint() const
{
  return this->Weights.rows() ? static_cast<double>(this->Weights.nonZeros()) / this->Weights.rows() : 0.0;
}

Spread SpreadOf(std::vector<double> values)
{
  if (values.empty())
  {
    return { kNaN, kNaN, kNaN };
  }
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  const double median = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  return { median, values.front(), values.back() };
}
}
