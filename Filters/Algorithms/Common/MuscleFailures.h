// SPDX-License-Identifier: BSD-3-Clause
// One muscle's failure must not take the others down: a computation over several muscles runs
// again without a muscle whose failure is its own (Error::muscle), and says why in `failures`.
#pragma once

#include "Common/MeshTypes.h"

#include <algorithm>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace md
{
/// `progress` that never goes back: a run again without a failed muscle starts over.
inline std::function<void(double)> ForwardOnly(const std::function<void(double)>& progress)
{
  if (!progress)
  {
    return {};
  }
  auto reported = std::make_shared<double>(0.0);
  return [progress, reported](double fraction) {
    *reported = std::max(*reported, fraction);
    progress(*reported);
  };
}

/// Calls `run(active)` with the indices of the muscles still in (those whose `failures` entry is
/// empty on entry) until it returns. When it throws an Error marked as one muscle's (an index into
/// `active`), that muscle's entry of `failures` gets the message and `run` is called again without
/// it. Anything else is thrown on, and so is the failure when no muscle is left: as it was thrown
/// for a single muscle, else as an InputError naming every muscle's failure.
template<class Run>
auto WithoutFailedMuscles(std::vector<std::string>& failures, Run run)
{
  std::vector<size_t> active;
  for (size_t m = 0; m < failures.size(); ++m)
  {
    if (failures[m].empty())
    {
      active.push_back(m);
    }
  }
  for (;;)
  {
    if (failures.empty())
    {
      throw InputError("there is no muscle to deform");
    }
    if (active.empty())
    {
      if (failures.size() == 1)
      {
        throw InputError(failures[0]);
      }
      std::string all = "no muscle could be deformed:";
      for (const std::string& failure : failures)
      {
        all += " " + failure + ";";
      }
      all.pop_back();
      throw InputError(all);
    }
    try
    {
      return run(active);
    }
    catch (Error& e)
    {
      if (!e.muscle || *e.muscle >= active.size())
      {
        throw; // not one muscle's: nothing to go on with
      }
      failures[active[*e.muscle]] = e.what();
      active.erase(active.begin() + static_cast<std::ptrdiff_t>(*e.muscle));
      if (active.empty() && failures.size() == 1)
      {
        throw; // as it was thrown: an InputError or a ComputationError
      }
    }
  }
}

/// `run(subset, progress)` on the muscles of `muscles` whose `failures` entry is empty (resized to
/// the muscles), as WithoutFailedMuscles: a muscle that fails on its own account is left out and
/// the others run again. Returns one result per muscle of `muscles`, those of failed muscles empty.
template<class Muscle, class Run>
auto ForMusclesThatCan(const std::vector<Muscle>& muscles, std::vector<std::string>& failures,
  const std::function<void(double)>& progress, Run run)
{
  failures.resize(muscles.size());
  const std::function<void(double)> forward = ForwardOnly(progress);
  return WithoutFailedMuscles(failures, [&](const std::vector<size_t>& active) {
    std::vector<Muscle> subset;
    for (size_t m : active)
    {
      subset.push_back(muscles[m]);
    }
    auto some = run(subset, forward);
    decltype(some) all(muscles.size());
    for (size_t k = 0; k < active.size(); ++k)
    {
      all[active[k]] = std::move(some[k]);
    }
    return all;
  });
}
}
