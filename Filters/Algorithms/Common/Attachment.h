// SPDX-License-Identifier: BSD-3-Clause
// Where a muscle is attached to a bone: the part of its surface that moves with the bone.
#pragma once

#include "Common/MeshTypes.h"

#include <string>
#include <vector>

namespace md
{
/// An attachment area (an origin or an insertion): points of a muscle's surface that move
/// rigidly with one bone. The bone's rigid motion near the area is fitted to its `anchors`, so
/// that a bone interpolated linearly (not quite rigid) carries the area as it moves there.
struct Attachment
{
  std::string bone;                  ///< the bone's name (messages)
  Eigen::Index boneIndex = -1;       ///< the bone's index among the deformation's bones
  std::vector<Eigen::Index> points;  ///< the muscle's points in the area
  std::vector<Eigen::Index> anchors; ///< points of the bone near the area
  Points anchorsRest;                ///< their rest positions, in the frame the muscle is in
  std::string source;                ///< how the area was found (messages)

  bool operator==(const Attachment& other) const
  {
    return this->boneIndex == other.boneIndex && this->points == other.points && this->anchors == other.anchors &&
      this->anchorsRest.rows() == other.anchorsRest.rows() && this->anchorsRest == other.anchorsRest;
  }
};
}
