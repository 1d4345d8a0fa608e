// SmallVector against std::vector, the oracle: the same random operations on both give the
// same contents, inline and on the heap, through copies and moves.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "core/util/small_vector.h"

namespace subd2nurbs {
namespace {

template <class T, std::size_t N>
void expect_same(const SmallVector<T, N>& s, const std::vector<T>& v, int step) {
  ASSERT_EQ(s.size(), v.size()) << "after step " << step;
  ASSERT_GE(s.capacity(), s.size()) << "after step " << step;
  for (std::size_t i = 0; i < v.size(); ++i) ASSERT_EQ(s[i], v[i]) << "element " << i << " after step " << step;
}

TEST(SmallVector, RandomOperationsMatchStdVector) {
  std::mt19937 rng(7);
  for (int run = 0; run < 200; ++run) {
    SmallVector<int, 3> s;
    std::vector<int> v;
    for (int step = 0; step < 300; ++step) {
      const int x = static_cast<int>(rng() % 1000);
      const std::size_t at = v.empty() ? 0 : rng() % (v.size() + 1);
      switch (rng() % 11) {
        case 0: case 1: case 2: s.push_back(x); v.push_back(x); break;
        case 3: if (!v.empty()) { s.pop_back(); v.pop_back(); } break;
        case 4: s.insert(s.begin() + at, x); v.insert(v.begin() + at, x); break;
        case 5: {  // a range, sometimes taken from the vector itself
          const std::vector<int> add(rng() % 5, x);
          if (!v.empty() && rng() % 2) {
            const std::vector<int> self(v.begin(), v.begin() + 1);
            s.insert(s.begin() + at, s.begin(), s.begin() + 1);
            v.insert(v.begin() + at, self.begin(), self.end());
          } else {
            s.insert(s.begin() + at, add.begin(), add.end());
            v.insert(v.begin() + at, add.begin(), add.end());
          }
          break;
        }
        case 6: if (at < v.size()) { s.erase(s.begin() + at); v.erase(v.begin() + at); } break;
        case 7: { const std::size_t n = rng() % 9; s.resize(n, x); v.resize(n, x); break; }
        case 8: { SmallVector<int, 3> copy(s); s = std::move(copy); break; }
        case 9: { SmallVector<int, 3> moved(std::move(s)); s = moved; break; }
        default: if (rng() % 8 == 0) { s.clear(); v.clear(); } break;
      }
      expect_same(s, v, step);
      if (HasFatalFailure()) return;
    }
  }
}

TEST(SmallVector, StaysInlineUpToNAndGrowsGeometrically) {
  SmallVector<double, 4> s{0.0, 1.0};
  EXPECT_EQ(s.capacity(), 4u);
  const double* inline_data = s.data();
  s.push_back(2);
  s.push_back(3);
  EXPECT_EQ(s.data(), inline_data) << "four elements fit inline";
  std::size_t reallocations = 0;
  for (int i = 0; i < 1000; ++i) {
    const double* before = s.data();
    // One at a time, alone and as a range: growth must be geometric, not per call.
    const double x = 1.0 * i;
    if (i % 2) s.insert(s.end(), x); else s.insert(s.end(), &x, &x + 1);
    reallocations += s.data() != before;
  }
  EXPECT_LE(s.capacity(), 2048u);
  EXPECT_LE(reallocations, 10u);
  SmallVector<double, 4> moved(std::move(s));
  EXPECT_TRUE(s.empty());
  EXPECT_EQ(moved.size(), 1004u);
  EXPECT_EQ(moved[1003], 999.0);
  EXPECT_THROW(moved.at(1004), std::out_of_range);
}

}  // namespace
}  // namespace subd2nurbs
