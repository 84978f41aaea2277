// The Pareto front of error against cost and the equal-error reading of it (stats/pareto.h):
// dominated configurations are off the front, an error between two front points reads a cost
// between theirs, the ends are bounds and say so, and the paired ratio's interval holds its median.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "stats/pareto.h"

namespace penumbra::stats {
namespace {

using Position = FrontReading::Position;

TEST(ParetoFront, DominatedInBothIsOffTheFront) {
  // error, cost: 2 is worse than 0 in both; 3 ties 1 in error at a higher cost.
  const std::vector<Candidate> c = {{0.04, 400}, {0.10, 250}, {0.06, 500}, {0.10, 260}, {0.02, 900}};
  const std::vector<std::size_t> front = pareto_front(c);
  EXPECT_EQ(front, (std::vector<std::size_t>{4, 0, 1}));  // error ascending, cost descending
}

TEST(ParetoFront, DegenerateInputs) {
  EXPECT_TRUE(pareto_front(std::vector<Candidate>{}).empty());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Candidate> c = {{nan, 1}, {0.1, nan}, {0.2, 3}};
  EXPECT_EQ(pareto_front(c), (std::vector<std::size_t>{2}));
  // Equal in both: the first is kept, once.
  const std::vector<Candidate> same = {{0.1, 5}, {0.1, 5}};
  EXPECT_EQ(pareto_front(same), (std::vector<std::size_t>{0}));
  // One candidate better in both than all others: a front of one.
  const std::vector<Candidate> one = {{0.3, 9}, {0.01, 1}, {0.2, 2}};
  EXPECT_EQ(pareto_front(one), (std::vector<std::size_t>{1}));
}

TEST(ParetoFront, AnErrorBetweenTwoFrontPointsReadsACostBetweenTheirs) {
  const std::vector<Candidate> c = {{0.02, 900}, {0.04, 400}, {0.10, 250}};
  const auto front = pareto_front(c);
  for (const double e : {0.02, 0.025, 0.03, 0.04, 0.07, 0.0999, 0.10}) {
    SCOPED_TRACE(e);
    const FrontReading r = read_front(c, front, e);
    EXPECT_EQ(r.position, Position::on_front);
    EXPECT_LE(c[r.lo].error, e);
    EXPECT_GE(c[r.hi].error, e);
    EXPECT_GE(r.cost, c[r.hi].cost);
    EXPECT_LE(r.cost, c[r.lo].cost);
  }
  EXPECT_DOUBLE_EQ(read_front(c, front, 0.03).cost, 600);  // halfway between 900 and 400, geometrically
  EXPECT_DOUBLE_EQ(interpolate_cost(0, 10, 0.5), 5);       // linear where a cost is not positive
  EXPECT_DOUBLE_EQ(read_front(c, front, 0.04).cost, 400);  // on a point: its cost
}

TEST(ParetoFront, OutsideTheFrontIsABoundAtTheNearestEnd) {
  const std::vector<Candidate> c = {{0.02, 900}, {0.04, 400}};
  const auto front = pareto_front(c);
  const FrontReading better = read_front(c, front, 0.01);
  EXPECT_EQ(better.position, Position::more_accurate);
  EXPECT_EQ(better.lo, 0u);
  EXPECT_EQ(better.cost, 900);
  const FrontReading worse = read_front(c, front, 0.5);
  EXPECT_EQ(worse.position, Position::less_accurate);
  EXPECT_EQ(worse.hi, 1u);
  EXPECT_EQ(worse.cost, 400);
  EXPECT_EQ(to_string(Position::more_accurate), "more_accurate_than_front");
  // A one-point front read at its own error.
  const std::vector<Candidate> single = {{0.05, 7}};
  EXPECT_EQ(read_front(single, pareto_front(single), 0.05).position, Position::on_front);
  EXPECT_THROW(read_front(c, std::vector<std::size_t>{}, 0.03), std::invalid_argument);
  EXPECT_THROW(read_front(c, front, std::nan("")), std::invalid_argument);
}

TEST(PairedRatio, MedianInsideItsIntervalAndReproducible) {
  // Engine frames at 400 ± noise, adaptive at 200 ± noise: ratios near 2.
  std::vector<double> engine, adaptive;
  for (int i = 0; i < 24; ++i) {
    engine.push_back(400 + 10 * std::sin(i));
    adaptive.push_back(200 + 8 * std::cos(1.7 * i));
  }
  const RatioInterval r = paired_ratio(engine, engine, 0.0, adaptive);
  EXPECT_EQ(r.n, 24u);
  EXPECT_NEAR(r.median, 2.0, 0.15);
  EXPECT_LE(r.lo, r.median);
  EXPECT_GE(r.hi, r.median);
  EXPECT_LT(r.hi - r.lo, 0.3);
  const RatioInterval again = paired_ratio(engine, engine, 0.0, adaptive);
  EXPECT_EQ(again.lo, r.lo);
  EXPECT_EQ(again.hi, r.hi);
  // The weight mixes the two neighbours frame by frame: halfway between 400s and 1600s
  // (geometrically: 800s) over 200s is 4.
  std::vector<double> quadrupled;
  for (double x : engine) quadrupled.push_back(4 * x);
  const std::vector<double> flat(24, 200.0);
  EXPECT_NEAR(paired_ratio(engine, quadrupled, 0.5, flat).median, 4.0, 0.15);
}

TEST(PairedRatio, DegenerateSeries) {
  const std::vector<double> a = {1, 2}, b = {1};
  EXPECT_THROW(paired_ratio(a, a, 0, b), std::invalid_argument);
  const RatioInterval none = paired_ratio(std::vector<double>{}, std::vector<double>{}, 0, std::vector<double>{});
  EXPECT_EQ(none.n, 0u);
  EXPECT_TRUE(std::isnan(none.median));
  // Zero or infinite frame costs are left out, not divided by.
  const std::vector<double> engine = {4, 4, 4}, adaptive = {2, 0, std::numeric_limits<double>::infinity()};
  const RatioInterval r = paired_ratio(engine, engine, 0, adaptive);
  EXPECT_EQ(r.n, 1u);
  EXPECT_EQ(r.median, 2);
  EXPECT_EQ(r.lo, 2);
  EXPECT_EQ(r.hi, 2);
}

}  // namespace
}  // namespace penumbra::stats
