// SPDX-License-Identifier: BSD-3-Clause
// The settle's dual system solved (ActiveSet.h): the blocks no entry links are found, each block
// meets the active set's conditions and is solved as it is alone, a singular system takes the
// smallest multipliers and one with a zero on its diagonal is still solved.
#include "Settle/ActiveSet.h"

#include <gtest/gtest.h>

#include <random>
#include <tuple>
#include <vector>

namespace
{
/// A system of `contacts` inequality rows then `equalities` rows over `blocks` interleaved
/// blocks (row k in block k % blocks), each block B B^T for a random B with more columns than
/// rows (positive definite), and a right-hand side that makes some contacts let go.
struct Problem
{
  Eigen::MatrixXd system;
  Eigen::VectorXd rhs;
  std::vector<double> slack;
};

Problem RandomProblem(int contacts, int equalities, int blocks, unsigned seed)
{
  std::mt19937 random(seed);
  std::normal_distribution<double> normal;
  const int size = contacts + equalities;
  Eigen::MatrixXd rows(size, size + 50);
  for (int r = 0; r < size; ++r)
  {
    for (int c = 0; c < size + 50; ++c)
    {
      rows(r, c) = normal(random);
    }
  }
  Problem p;
  p.system = Eigen::MatrixXd::Zero(size, size);
  for (int j = 0; j < size; ++j)
  {
    for (int l = 0; l < size; ++l)
    {
      if (j % blocks == l % blocks)
      {
        p.system(j, l) = rows.row(j).dot(rows.row(l));
      }
    }
  }
  p.rhs.resize(size);
  for (int j = 0; j < size; ++j)
  {
    p.rhs(j) = normal(random);
  }
  p.slack.assign(static_cast<size_t>(contacts), 1e-12);
  return p;
}

/// The rows of `rows` of `p`'s system as a problem of its own.
Problem Part(const Problem& p, const std::vector<Eigen::Index>& rows)
{
  Problem part{ p.system(rows, rows), p.rhs(rows), {} };
  for (const Eigen::Index row : rows)
  {
    if (row < static_cast<Eigen::Index>(p.slack.size()))
    {
      part.slack.push_back(p.slack[row]);
    }
  }
  return part;
}
}

TEST(ActiveSet, TheBlocksNoEntryLinksAreFoundLargestFirst)
{
  Eigen::MatrixXd system = Eigen::MatrixXd::Identity(6, 6);
  for (const auto& [j, l] : { std::pair{ 0, 3 }, std::pair{ 3, 5 }, std::pair{ 1, 4 } })
  {
    system(j, l) = system(l, j) = 0.5;
  }
  const std::vector<std::vector<Eigen::Index>> expected = { { 0, 3, 5 }, { 1, 4 }, { 2 } };
  EXPECT_EQ(md::UnlinkedBlocks(system), expected);
  EXPECT_EQ(md::UnlinkedBlocks(Eigen::MatrixXd::Ones(3, 3)).size(), 1U);
}

/// Each block of a system with small blocks (factorised dense) and one with blocks of 300 rows
/// (factorised sparse) meets the active set's conditions and is solved as it is alone.
class ActiveSetBlocks : public testing::TestWithParam<std::tuple<int, int, int>>
{
};

TEST_P(ActiveSetBlocks, EachBlockMeetsTheConditionsAndIsSolvedAsAlone)
{
  const auto [contacts, equalities, blocks] = GetParam();
  const Problem p = RandomProblem(contacts, equalities, blocks, 7);
  std::vector<char> active(static_cast<size_t>(contacts + equalities), 1);
  const Eigen::VectorXd y = md::SolveActiveSet(p.system, p.rhs, p.slack, active);
  const Eigen::VectorXd residual = p.system * y - p.rhs;
  int lettingGo = 0;
  for (int j = 0; j < contacts + equalities; ++j)
  {
    if (j >= contacts || active[j])
    {
      EXPECT_NEAR(residual(j), 0.0, 1e-9) << "row " << j;    // held: the gap closed
      EXPECT_TRUE(j >= contacts || y(j) > 0) << "row " << j; // a contact pushes
    }
    else
    {
      ++lettingGo;
      EXPECT_EQ(y(j), 0.0) << "row " << j;
      EXPECT_GE(residual(j), -p.slack[j]) << "row " << j; // let go: the gap stays open
    }
  }
  EXPECT_GT(lettingGo, 0);            // the right-hand side lets some contacts go ...
  EXPECT_LT(lettingGo, contacts / 2); // ... and holds the most
  ASSERT_EQ(md::UnlinkedBlocks(p.system).size(), static_cast<size_t>(blocks));
  for (const std::vector<Eigen::Index>& rows : md::UnlinkedBlocks(p.system))
  {
    const Problem alone = Part(p, rows);
    std::vector<char> aloneActive(rows.size(), 1);
    const Eigen::VectorXd z = md::SolveActiveSet(alone.system, alone.rhs, alone.slack, aloneActive);
    for (size_t r = 0; r < rows.size(); ++r)
    {
      EXPECT_EQ(z(static_cast<Eigen::Index>(r)), y(rows[r])); // to the bit
      EXPECT_EQ(aloneActive[r], active[rows[r]]);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
  DenseAndSparse, ActiveSetBlocks, testing::Values(std::tuple{ 40, 5, 3 }, std::tuple{ 560, 40, 2 }));

TEST(ActiveSet, TwoContactsPushingAPointTheSameWayShareTheirPush)
{
  // The same contact twice: any y0 + y1 = 2 closes the gap; the nudge picks the smallest, 1 each.
  // Alone (factorised dense) and 150 times over (sparse).
  for (const Eigen::Index pairs : { 1, 150 })
  {
    Eigen::MatrixXd system = Eigen::MatrixXd::Zero(2 * pairs, 2 * pairs);
    for (Eigen::Index k = 0; k < pairs; ++k)
    {
      system.block<2, 2>(2 * k, 2 * k).setOnes();
    }
    const Eigen::VectorXd right = Eigen::VectorXd::Constant(2 * pairs, 2.0);
    const Eigen::VectorXd y = md::SolveNudged(system, right);
    EXPECT_NEAR((system * y - right).norm(), 0.0, 1e-9) << pairs << " pairs";
    EXPECT_NEAR((y - Eigen::VectorXd::Ones(2 * pairs)).cwiseAbs().maxCoeff(), 0.0, 1e-6) << pairs << " pairs";
  }
}

TEST(ActiveSet, ASystemWithAZeroOnItsDiagonalIsSolved)
{
  // A sample let go whose row's energy is exactly its share leaves a zero on the diagonal, which
  // a factorisation without pivoting cannot take first.
  Eigen::MatrixXd system(3, 3);
  system << 0, 1, 0, 1, 1, 0, 0, 0, 2;
  const Eigen::Vector3d right(1, 3, 4);
  const Eigen::VectorXd y = md::SolveNudged(system, right);
  EXPECT_NEAR((y - Eigen::Vector3d(2, 1, 2)).norm(), 0.0, 1e-10);
}
