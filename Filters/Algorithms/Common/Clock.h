// SPDX-License-Identifier: BSD-3-Clause
// The clock the stages time their work with (the seconds in their results and measures).
#pragma once

#include <chrono>

namespace md
{
using Clock = std::chrono::steady_clock;

/// Seconds from `start` to now.
inline double SecondsSince(Clock::time_point start)
{
  return std::chrono::duration<double>(Clock::now() - start).count();
}
}
