// common/stats/summary.h: the one percentile, median and spread, on degenerate inputs too.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "stats/summary.h"

namespace penumbra::stats {
namespace {

TEST(Stats, PercentileInterpolatesBetweenOrderStatistics) {
  const std::vector<double> v = {4, 1, 3, 2};  // unsorted on purpose
  EXPECT_DOUBLE_EQ(percentile(v, 0), 1);
  EXPECT_DOUBLE_EQ(percentile(v, 1), 4);
  EXPECT_DOUBLE_EQ(percentile(v, 0.5), 2.5);
  EXPECT_DOUBLE_EQ(percentile(v, 1.0 / 3.0), 2);
  EXPECT_DOUBLE_EQ(percentile(v, 0.1), 1.3);
  EXPECT_DOUBLE_EQ(percentile(v, -5), 1) << "q is clamped";
  EXPECT_DOUBLE_EQ(percentile(v, 7), 4);
}

TEST(Stats, MedianOfOddEvenOneAndNone) {
  EXPECT_DOUBLE_EQ(median({5, 1, 3}), 3);
  EXPECT_DOUBLE_EQ(median({5, 1, 3, 100}), 4) << "the mean of the two middle values";
  EXPECT_DOUBLE_EQ(median({7}), 7);
  EXPECT_TRUE(std::isnan(median({}))) << "nothing measured is not 0";
  EXPECT_DOUBLE_EQ(median({-1e300, 1e300}), 0) << "no overflow between extremes";
  EXPECT_EQ(median({INFINITY, 1, 2}), 2);
}

TEST(Stats, SpreadIsTheSameDefinitionAndZeroWhenEmpty) {
  std::vector<double> v;
  for (int i = 10; i >= 0; --i) v.push_back(i);  // 0..10
  const Spread s = spread(v);
  EXPECT_DOUBLE_EQ(s.median, 5);
  EXPECT_DOUBLE_EQ(s.p10, 1);
  EXPECT_DOUBLE_EQ(s.p90, 9);
  EXPECT_DOUBLE_EQ(s.min, 0);
  EXPECT_DOUBLE_EQ(s.max, 10);
  const Spread twelve = spread({1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12});
  EXPECT_DOUBLE_EQ(twelve.median, median({1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}));
  const Spread none = spread({});
  EXPECT_EQ(none.median, 0);
  EXPECT_EQ(none.max, 0);
}

}  // namespace
}  // namespace penumbra::stats
