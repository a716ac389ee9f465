// SPDX-License-Identifier: BSD-3-Clause
// The interpolation method (Hajkova & Kohout sec. 4.3; docs/DESIGN.md section 6):
// the motion split into N steps, bones and matched action lines interpolated
// at every step, each step deformed from the previous result (all muscles
// together, obstacles for each other) and then statically resolved.
//
// Beyond the paper (StepDeformationDefaults): in each step's deformation the
// bones push the muscles (contact rows), instead of only stopping the points
// that move into them; the static resolution then has little left to do.
//
// Beyond the paper (HullMode::Refit): the rest-pose hull and its mean value
// coordinates are kept for the whole motion. After each step's static
// resolution the hull is refitted to the resolved mesh by least squares with a
// fixed matrix, and what the hull cannot carry (the bone prints) is kept as
// per-point detail; the paper rebuilt the hull before every step
// (HullMode::Rebuild, kept for comparison).
#pragma once

#include "Common/Attachment.h"
#include "Deformation/MuscleDeformer.h"
#include "Geometry/LocalFrame.h"
#include "Geometry/MeanValueCoordinates.h"
#include "Hull/ProgressiveHull.h"
#include "Intersections/StaticIntersections.h"
#include "Motion/BoneInterpolation.h"
#include "Settle/SurfaceSettle.h"

#include <functional>
#include <string>
#include <vector>

namespace md
{
enum class HullMode
{
  Refit = 0,   ///< keep the rest-pose hull and mapping, refit after each step
  Rebuild = 1, ///< the paper: a new hull and mapping before each step
};

/// The least-squares inverse of a mean value mapping: the hull points X that
/// best reproduce a full mesh V, argmin |W X - V|^2 + lambda |L (X - X0)|^2
/// + mu |X - X0|^2, with L the rest hull's cotangent Laplacian and X0 a guess
/// (the hull the deformation produced) that keeps the shape where W says little. W and the
/// normal matrix are fixed, so the factorisation is done once.
class HullRefitter
{
public:
  /// `regularisation` is relative to trace(W^T W): it weighs the Laplacian
  /// term (over trace(L^T L)) and an identity term (over the number of hull
  /// points) that holds the hull points the mesh hardly depends on.
  HullRefitter(const WeightMatrix& weights, const TriangleMesh& restHull, double regularisation = 1e-3);
  Points Fit(const Points& mesh, const Points& guess) const;

private:
  struct Factorisation;
  const WeightMatrix& Weights;
  Eigen::MatrixXd Regulariser; // lambda L^T L
  std::shared_ptr<const Factorisation> Solver;
};

/// One muscle to move: its rest-pose surface and its matched action lines
/// (rest -> current).
struct MuscleMotion
{
  std::string name;
  TriangleMesh muscle;
  std::vector<MatchedLine> lines;
  /// Where it is attached to the bones (their boneIndex: the bones' order); honoured on the
  /// surface (settleOnSurface), not by the hull-based pass.
  std::vector<Attachment> attachments;
};

/// One bone: the same points in the rest pose and the current pose.
struct BoneMotion
{
  std::string name;
  TriangleMesh rest;
  Points current;
};

/// The deformation step of the interpolation method: the paper's, except
/// that bones push the muscle (DeformationParameters::contactWeight 0.5;
/// 0 gives the paper's step). Measured on the LHDL hip at 60 degrees of
/// flexion, N = 4: the largest static shift falls from 16.7 to 5.4 mm.
inline DeformationParameters StepDeformationDefaults()
{
  DeformationParameters parameters;
  parameters.contactWeight = 0.5;
  return parameters;
}

struct InterpolationParameters
{
  int numberOfSteps = kDefaultNumberOfSteps; ///< N; 0: automatic
  /// Largest bone-point move per step when N is automatic.
  double maximumStepDisplacement = kDefaultMaximumStepDisplacement;
  InterpolationMode interpolationMode = kDefaultInterpolationMode; ///< bones and action lines
  HullMode hullMode = HullMode::Refit;
  double refitRegularisation = 1e-3; ///< HullRefitter's, relative (the filter's default too)
  /// Halfway smoothing steps of the per-point detail after each step (Refit):
  /// the rims of earlier bone prints fade (0: the detail is kept as it is).
  int detailRelaxation = 2;
  StaticResolveParameters staticResolve;
  DeformationParameters deformation = StepDeformationDefaults();
  /// Each step's answer settled on the full mesh (SurfaceSettle), each settle starting from the
  /// last one's answer (SettleMotion): independent of the hull (the default, the filter's too);
  /// false: the hull-based pass's answer (the paper's, hull-dependent).
  bool settleOnSurface = true;
  SettleParameters settle;
  HullParameters hull;
};

/// The measures of one muscle after step j (docs/DESIGN.md, "Measures").
struct MuscleStepMeasures
{
  double volumeChangePercent = 0;       ///< against the rest pose
  std::int64_t newPenetrationCount = 0; ///< inside a bone or another muscle, not so in the rest pose
  double maxNewPenetrationDepth = 0;
  std::int64_t newBonePenetrationCount = 0; ///< the same, bones only
  double maxNewBonePenetrationDepth = 0;
  double stepStaticShift = 0;             ///< largest move of this step's static resolution
  double maxStaticShift = 0;              ///< largest over steps 1..j
  std::int64_t staticallyMovedPoints = 0; ///< points this step's static resolution moved
  std::int64_t sharpEdgeCount = 0;        ///< dihedral angle > 60 degrees, not so in the rest pose
  std::int64_t flippedTriangleCount = 0;  ///< against the rest pose
  int stepIterations = 0;
  int iterations = 0;                       ///< steps 1..j
  bool converged = true;                    ///< every step so far
  std::int64_t pointsFrozenInObstacles = 0; ///< this step
  double hullSeconds = 0;                   ///< this step's hull work: refit, or rebuild and mapping
  double deformationSeconds = 0;            ///< this step's deformation and static resolution (its share)
  Points staticShift;                       ///< this step's static move, per point
};

struct InterpolationResult
{
  int numberOfSteps = 0;
  bool zeroMotion = false;                               ///< RP = CP: every step is the input
  std::vector<std::vector<Points>> points;               ///< [step][muscle], step 0 the rest pose
  std::vector<std::vector<MuscleStepMeasures>> measures; ///< [step][muscle]
  std::vector<double> restHullSeconds;                   ///< per muscle: rest hull and mapping
  std::vector<double> stepSeconds;                       ///< [step], 0 for step 0
  double totalSeconds = 0;
  std::vector<std::string> warnings;
  /// Per muscle: empty, or why it could not be deformed (its points are then empty at every
  /// step, its measures the defaults): the others were deformed without it.
  std::vector<std::string> failures;
};

/// The rest-pose hull of every muscle and the mean value coordinates of its points in it, and
/// with InterpolationParameters::settleOnSurface its full-mesh energy, kept between runs of
/// DeformByInterpolation by a caller that runs the method again (another number of steps, other
/// bones, weights or tolerances): they depend on the rest pose and their parameters alone, and
/// they are most of a first run's time. A muscle whose surface or parameters changed gets a new
/// hull or energy; the entries follow the order of the muscles.
struct RestMappingCache
{
  struct Entry
  {
    TriangleMesh surface; ///< the rest pose it was made from (in the method's local frame)
    HullParameters hull;  ///< and the hull parameters
    TriangleMesh restHull;
    WeightMatrix weights;
    /// The full-mesh energy, of the rest pose and its matched action lines (the local frame's).
    KeptSurfaceEnergy surfaceEnergy;
  };
  std::vector<Entry> muscles;
  int hullBuildCount = 0;   ///< rest-pose hulls built so far (not counting HullMode::Rebuild's)
  int energyBuildCount = 0; ///< full-mesh energies built so far
};

/// Runs `work` (called with a RestMappingCache) on the entries of `cache` for the muscles
/// `active` alone, moved into a cache of their own in that order with `cache`'s counts, and
/// gives them and the counts back afterwards, also when `work` throws: the method run on a
/// subset of the muscles (those that can go) keeps what it built by muscle.
template<class Work>
auto WithCacheSubset(RestMappingCache& cache, const std::vector<size_t>& active, Work&& work)
{
  RestMappingCache subset;
  subset.hullBuildCount = cache.hullBuildCount;
  subset.energyBuildCount = cache.energyBuildCount;
  for (size_t m : active)
  {
    subset.muscles.push_back(std::move(cache.muscles[m]));
  }
  auto giveBack = [&] {
    for (size_t k = 0; k < active.size(); ++k)
    {
      cache.muscles[active[k]] = std::move(subset.muscles[k]);
    }
    cache.hullBuildCount = subset.hullBuildCount;
    cache.energyBuildCount = subset.energyBuildCount;
  };
  try
  {
    auto result = work(subset);
    giveBack();
    return result;
  }
  catch (...)
  {
    giveBack();
    throw;
  }
}

/// One muscle's action lines as the method takes them: rest[l] matched with current[l]
/// (MatchActionLines with `tolerance`), with its own points `knots[l]` (none given: every point;
/// they must fit rest[l], KnotsFit), lines of too many points cut down
/// (LimitActionLinePoints, said in `notes`). Both lists must be as long (InputError otherwise).
std::vector<MatchedLine> MatchMuscleLines(const std::vector<Points>& rest, const std::vector<Points>& current,
  double tolerance, std::vector<std::string>& notes, const std::vector<Knots>& knots = {});

/// Number of steps: `parameters.numberOfSteps`, or when 0 enough steps that no
/// bone point moves more than `parameters.maximumStepDisplacement` in one.
int ResolveNumberOfSteps(const std::vector<BoneMotion>& bones, const InterpolationParameters& parameters);

/// Runs the whole method, in the muscles' LocalFrame (lengths in `parameters` and in the result
/// in the data's units). A muscle that cannot be deformed (no surface or action line, no hull, a
/// deformation that diverges) is left out and named in `failures`; the others are deformed as if it
/// had not been given. Throws InputError naming the bone for input it cannot use, and
/// InputError or ComputationError when no muscle can be deformed.
/// `progress` (optional) receives fractions in [0, 1]. `kept` (optional) holds the rest-pose hulls
/// and mappings of an earlier run, used where they still hold and updated.
InterpolationResult DeformByInterpolation(const std::vector<MuscleMotion>& muscles,
  const std::vector<BoneMotion>& bones, const InterpolationParameters& parameters,
  const std::function<void(double)>& progress = {}, RestMappingCache* kept = nullptr);

/// Points and lengths of a result computed in `frame` (for callers that bring their input into
/// the frame themselves, e.g. to match action lines there) back in world coordinates. Step 0 (and
/// every step of a zero motion) becomes `restPoints[m]`, the input itself, not its round trip.
void ResultToWorld(const LocalFrame& frame, const std::vector<const Points*>& restPoints, InterpolationResult& result);
}
