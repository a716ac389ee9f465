// SPDX-License-Identifier: BSD-3-Clause
// Making a scanned closed surface usable: what is safe to repair is repaired
// and counted, what cannot be used is refused.
#pragma once

#include "Common/MeshTypes.h"

#include <string>
#include <vector>

namespace md
{
struct RepairReport
{
  std::int64_t unusedPointsRemoved = 0;
  std::int64_t duplicatePointsMerged = 0;      ///< points closer than mergeTolerance to another
  std::int64_t nearDuplicatePointsMerged = 0;  ///< of them, those not at the same coordinates
  double mergeTolerance = 0;                   ///< 1e-5 of the surface's size
  std::int64_t degenerateTrianglesRemoved = 0; ///< triangles repeating a point
  std::int64_t duplicateTrianglesRemoved = 0;
  std::int64_t finTrianglesRemoved = 0;        ///< back-to-back pairs on the same points
  std::int64_t trianglesReoriented = 0;        ///< flipped to agree with their neighbours
  std::int64_t nonManifoldEdgesSplit = 0;      ///< edges of more than two triangles, cut apart
  std::int64_t pointsDuplicatedAtPinches = 0;  ///< points copied so that every fan is its own
  std::int64_t selfIntersectionsUntangled = 0; ///< crossing triangle pairs undone by smoothing
  std::int64_t pointsSmoothed = 0;             ///< points moved to undo them
  double largestSmoothingShift = 0;            ///< farthest such move
  std::int64_t selfIntersectionsLeft = 0;      ///< crossing pairs smoothing could not undo
  std::int64_t enclosedPiecesRemoved = 0;      ///< separate pieces lying inside another piece
  /// Points of the input surface that the repaired one does not carry where
  /// they were (moved by smoothing or at pinches, or dropped with a fin): a
  /// hull of the repaired surface must enclose them too (BuildProgressiveHull).
  Points pointsToEnclose;

  bool Changed() const
  {
    return unusedPointsRemoved || duplicatePointsMerged || degenerateTrianglesRemoved || duplicateTrianglesRemoved ||
      finTrianglesRemoved || trianglesReoriented || nonManifoldEdgesSplit || pointsDuplicatedAtPinches ||
      selfIntersectionsUntangled || selfIntersectionsLeft || enclosedPiecesRemoved;
  }
  /// One line naming every repair made, e.g. "removed 10 unused points, ...".
  std::string Describe() const;
  /// Adds `rows` to pointsToEnclose.
  void AddPointsToEnclose(const std::vector<Eigen::RowVector3d>& rows);
};

/// A closed, manifold, outward-oriented copy of `surface`. Points closer than 1e-5 of the
/// surface's size (its bounding box's diagonal) are merged into one, the one of lowest index, so
/// that rounding noise cannot open a scan along its duplicate points. Non-manifold edges
/// (two sheets pinched along an edge) are cut apart: the triangles around the
/// edge are paired so that each pair bounds one lobe, and every point whose
/// triangles then form several fans gets a copy per fan, moved by a tiny
/// distance (1e-6 of the surface's size) into its own lobe so that the sheets
/// no longer touch. Small self-intersections of a scan (folded triangles) are
/// undone by smoothing the points around them, as little as it takes; pieces
/// lying entirely inside another piece are removed. Throws InputError for what cannot be repaired safely: an
/// open surface (boundary edges), fewer than 4 triangles, non-finite
/// coordinates, a surface of no volume.
TriangleMesh RepairClosedSurface(const TriangleMesh& surface, RepairReport& report);

/// The triangles of `surface` with its points closer than the repair's merge tolerance (1e-5 of
/// its size) welded into one (`representative`: each point's surviving twin, the lowest index of
/// its cluster) and the degenerate and duplicate triangles that leaves dropped: the surface on
/// its own points as RepairClosedSurface first sees it (back-to-back pairs, fins of no
/// thickness, are kept), so that a scan's exact and split duplicate points give the same
/// triangles.
Triangles WeldedTriangles(const TriangleMesh& surface, std::vector<std::int64_t>& representative);

/// RepairClosedSurface's last steps on a closed, consistently oriented `mesh` (in place), said in
/// `report`: triangles that cross each other are undone by smoothing the points around them, as
/// little as it takes (the region widened ring by ring where that is not enough; what smoothing
/// cannot undo is counted as left).
void UntangleSelfIntersections(TriangleMesh& mesh, RepairReport& report);
/// Removes the connected pieces of `mesh` whose every point lies inside another piece.
void RemoveEnclosedPieces(TriangleMesh& mesh, RepairReport& report);
}
