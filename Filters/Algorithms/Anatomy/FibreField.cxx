// SPDX-License-Identifier: BSD-3-Clause
#include "Anatomy/FibreField.h"

#include "Geometry/MeshChecks.h"
#include "Geometry/Polyline.h"
#include "Geometry/TriangleTree.h"

#include <Eigen/IterativeLinearSolvers>

#include <algorithm>
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
/// Residual of the field's solve (conjugate gradients), relative to its right-hand side: phi,
/// in [0, 1], then lies within 1e-11 of a direct solve's (measured on the LHDL muscles and
/// gait10dof18musc's), far below what moves a streamline, in a small share of its time.
constexpr double kFieldTolerance = 1e-12;

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
}

TracedFibres TraceFibres(const TriangleMesh& rest, const FibreEnds& given, const FibreParameters& parameters,
  int gridNodes, const std::vector<const TriangleMesh*>& obstacles,
  const std::function<bool(const Eigen::Vector3d&)>& free)
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
