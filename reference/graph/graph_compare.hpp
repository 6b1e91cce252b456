// Tests: every field of two layout graphs, compared one by one so that a failure names the array.
#pragma once

#include <gtest/gtest.h>

#include "r1/spec/graph.hpp"

namespace r1::test {

inline void expect_same_graph(const Graph& a, const Graph& b) {
  EXPECT_EQ(a.n, b.n);
  EXPECT_EQ(a.row_ptr, b.row_ptr);
  EXPECT_EQ(a.col, b.col);
  EXPECT_EQ(a.w, b.w);
  EXPECT_EQ(a.a2, b.a2);
  EXPECT_EQ(a.out_ptr, b.out_ptr);
  EXPECT_EQ(a.out_col, b.out_col);
  EXPECT_EQ(a.out_w, b.out_w);
  EXPECT_EQ(a.degree, b.degree);
  EXPECT_EQ(a.prior, b.prior);
  EXPECT_EQ(a.dangling, b.dangling);
  EXPECT_EQ(a.max_degree, b.max_degree);
  EXPECT_EQ(a.component, b.component);
  EXPECT_EQ(a.component_size, b.component_size);
  EXPECT_TRUE(a.weight_scale == b.weight_scale);
  EXPECT_EQ(a.links, b.links);
  EXPECT_EQ(a.self_loops_dropped, b.self_loops_dropped);
}

}  // namespace r1::test
