// SPDX-License-Identifier: BSD-3-Clause
// One muscle's failure leaves the others running: WithoutFailedMuscles and ForMusclesThatCan.
#include "Common/MuscleFailures.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

TEST(MuscleFailures, AMuscleThatFailsAloneIsLeftOutAndTheOthersRunAgain)
{
  // Muscle 1 of three fails on its own account: the run is repeated without it.
  const std::vector<std::string> muscles = { "a", "b", "c" };
  std::vector<std::string> failures;
  std::vector<std::vector<std::string>> runs;
  const std::vector<std::string> results = md::ForMusclesThatCan(
    muscles, failures, {}, [&](const std::vector<std::string>& subset, const std::function<void(double)>&) {
      runs.push_back(subset);
      for (size_t k = 0; k < subset.size(); ++k)
      {
        if (subset[k] == "b")
        {
          throw md::OfMuscle(md::InputError("b has no action line"), k);
        }
      }
      std::vector<std::string> out;
      for (const std::string& name : subset)
      {
        out.push_back(name + " done");
      }
      return out;
    });
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[1], (std::vector<std::string>{ "a", "c" }));
  EXPECT_EQ(results, (std::vector<std::string>{ "a done", "", "c done" }));
  EXPECT_EQ(failures, (std::vector<std::string>{ "", "b has no action line", "" }));
}

TEST(MuscleFailures, AFailureOfNoOneMuscleIsThrownOnAsItWas)
{
  std::vector<std::string> failures(2);
  int calls = 0;
  EXPECT_THROW(md::WithoutFailedMuscles(failures,
                 [&](const std::vector<size_t>&) -> int {
                   ++calls;
                   throw md::ComputationError("the solver diverged");
                 }),
    md::ComputationError);
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(failures, (std::vector<std::string>(2)));
}

TEST(MuscleFailures, WhenEveryMuscleFailsTheErrorNamesEachFailure)
{
  std::vector<std::string> failures(2);
  try
  {
    md::WithoutFailedMuscles(failures, [&](const std::vector<size_t>& active) -> int {
      throw md::OfMuscle(md::InputError("muscle " + std::to_string(active[0]) + " is open"), 0);
    });
    ADD_FAILURE() << "no InputError";
  }
  catch (const md::InputError& e)
  {
    EXPECT_NE(std::string(e.what()).find("muscle 0 is open"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("muscle 1 is open"), std::string::npos) << e.what();
  }
  EXPECT_EQ(failures, (std::vector<std::string>{ "muscle 0 is open", "muscle 1 is open" }));
}

TEST(MuscleFailures, ProgressNeverGoesBack)
{
  std::vector<double> reported;
  const auto progress = md::ForwardOnly([&](double fraction) { reported.push_back(fraction); });
  for (double fraction : { 0.2, 0.6, 0.1, 0.7 })
  {
    progress(fraction);
  }
  EXPECT_EQ(reported, (std::vector<double>{ 0.2, 0.6, 0.6, 0.7 }));
  EXPECT_FALSE(md::ForwardOnly({}));
}
