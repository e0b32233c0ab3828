#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "energy/vertex_partition.h"

namespace modal_deform {
namespace {

TEST(VertexPartition, RangesCoverTheVerticesWithBalancedWork) {
  const std::vector<int> work{5, 1, 1, 1, 1, 1, 0, 5, 1, 0};
  const VertexPartition two = balanced_partition(work, 2);
  EXPECT_EQ(two.begin, (std::vector<int>{0, 4, 10}));  // work 8 and 8
  const VertexPartition one = balanced_partition(work, 1);
  EXPECT_EQ(one.begin, (std::vector<int>{0, 10}));
  // More parts than vertices with work: the last parts are empty, never out of range.
  const VertexPartition many = balanced_partition({0, 3, 0}, 4);
  EXPECT_EQ(many.begin.front(), 0);
  EXPECT_EQ(many.begin.back(), 3);
  for (int part = 0; part < many.parts(); ++part) EXPECT_LE(many.begin[part], many.begin[part + 1]);
}

TEST(VertexPartition, EveryElementIsListedByEachPartItTouches) {
  struct Element {
    std::array<int, 2> vertices;
  };
  const std::vector<Element> elements{{{0, 1}}, {{1, 5}}, {{6, 7}}, {{2, 8}}, {{4, 3}}};
  VertexPartition partition;
  partition.begin = {0, 4, 9};
  const auto lists = elements_by_part(partition, elements);
  ASSERT_EQ(lists.size(), 2u);
  EXPECT_EQ(lists[0], (std::vector<int>{0, 1, 3, 4}));
  EXPECT_EQ(lists[1], (std::vector<int>{1, 2, 3, 4}));
  EXPECT_TRUE(partition.range(1).contains(8));
  EXPECT_FALSE(partition.range(1).contains(9));
  EXPECT_FALSE(partition.range(1).contains(3));
}

}  // namespace
}  // namespace modal_deform
