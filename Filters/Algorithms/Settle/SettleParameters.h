// SPDX-License-Identifier: BSD-3-Clause
// The settings of the settle on the muscles' own surfaces (docs/DESIGN.md section 7): its energy's
// rows and their weights, the contacts, the parts a motion's step is settled in, and when it stops.
#pragma once

namespace md
{
/// The settle's settings. Each default is the one measured best on the LHDL hip and the phantom;
/// docs/DESIGN.md section 7 says why, and decision records 0009 and 0010 what else was tried.
struct SettleParameters
{
  /// A point in contact is held this fraction of its muscle's size outside the obstacle, so
  /// that the surfaces do not touch.
  double contactOffset = 1e-3;
  /// A point nearer an obstacle than the offset plus this fraction of its muscle's size, its
  /// contact not yet broken, is watched: it joins an iteration's step if that step would break
  /// it (the step solved again), so that a point just beyond the offset takes the same path as
  /// one just within, and rounding does not choose between equilibria. 0 watches nothing, as
  /// the one pass from the rest pose does (SettleInOnePass).
  double contactLookahead = 1e-3;
  /// Rows pulling every point to where the motion of the action-line segments near it takes it
  /// (BlendedSegments), relative to the shape rows: they fix the near-null modes of the other
  /// rows (see DeformationParameters::followWeight) and hold a muscle pressed between obstacles
  /// along the contact, where the other rows hold it only weakly.
  double followWeight = 0.1;
  /// Each point is turned and carried by the action-line segments whose distance from it exceeds
  /// the nearest one's by less than this fraction of the muscle's size, blended
  /// (BlendedSegments), so that no point's target jumps where two segments are equally near.
  double blendWidth = 0.05;
  /// Samples of each action-line segment that pull the muscle (SampleMatchedLines).
  int samplesPerSegment = 10;
  /// The rows that hold an attachment area's points where its bone carries them (Attachment),
  /// relative to the shape rows' weight: stiff enough that the areas stay on their bones, soft
  /// enough that the rest of the muscle follows smoothly and the settles converge
  /// (docs/DESIGN.md section 9).
  double attachmentWeight = 10;
  /// The shape rows' cotangent weights are clamped to [0, largestCotangent] (CotangentLaplacian;
  /// at 3, angles under 18.4 degrees count as 18.4): a scan's slivers and obtuse triangles
  /// otherwise let points cross their neighbours.
  double largestCotangent = 3;
  /// The shape rows are scaled so that the balance with the action-line rows is that of a hull
  /// of this many points (the hull-based pass's at its default size): the energy is then
  /// comparable with the paper's, and it depends on the muscle's own mesh only.
  double balancePoints = 250;
  /// A step of a motion whose unconstrained minimum moves by more than this fraction of a
  /// muscle's size is settled in as many equal parts as keep each part's move within it
  /// (SettleParts): from farther, the linearised contacts lose their way. Measured on the
  /// minimum, not on whether a settle converged, so that the count changes with the input only
  /// where the move crosses a multiple of this, not under rounding noise.
  double largestStartMove = 0.125;
  /// A step of a motion that carries its contacts (SettleMotion::carryContacts) is settled in as
  /// many equal parts as keep each part's unconstrained minimum within this fraction of a
  /// muscle's size (SettleParts), each part starting with the contacts the last one ended with:
  /// the muscles go on from the equilibrium they are in, even where they jump (an OpenSim path
  /// point comes or goes, and its line with it).
  double largestCarriedMove = 0.0625;
  /// Linearisations of the volume and of the obstacles' surfaces. A settle that is nearly there
  /// when they run out (its contacts held, every move within 1e-5 of its muscle's size) goes on
  /// for as many again.
  int maximumIterations = 100;
  /// Converged when no point moves more than this fraction of the muscle's size in an
  /// iteration, the contacts are those of the iteration before, and the volume is within 1e-9
  /// of its target.
  double tolerance = 1e-7;

  /// True when `other` gives the same SurfaceEnergy (the settle's own settings aside).
  bool SameEnergyAs(const SettleParameters& other) const
  {
    return this->followWeight == other.followWeight && this->blendWidth == other.blendWidth &&
      this->samplesPerSegment == other.samplesPerSegment && this->balancePoints == other.balancePoints &&
      this->largestCotangent == other.largestCotangent && this->attachmentWeight == other.attachmentWeight;
  }
};
}
