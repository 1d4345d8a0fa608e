// The field sweeps' rounding (core/remesh/quad_remesh.h remesh_detail::round_half_away) against
// std::round, the oracle: the same value, bit for bit (sign of zero included), at the halves,
// next to them, at large magnitudes, at the special values and at random doubles.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "core/remesh/quad_remesh.h"

namespace subd2nurbs::testing {
namespace {

bool same_bits(double a, double b) {
  if (std::isnan(a) && std::isnan(b)) return true;
  std::uint64_t x, y;
  std::memcpy(&x, &a, sizeof a);
  std::memcpy(&y, &b, sizeof b);
  return x == y;
}

TEST(RemeshRounding, MatchesStdRoundBitForBit) {
  std::vector<double> xs = {0.0, -0.0, 0.5, -0.5, 1.5, -1.5, 2.5, -2.5, 0.49999999999999994, -0.49999999999999994,
                            1e-300, -1e-300, 4503599627370495.5, -4503599627370495.5, 4503599627370496.0,
                            9007199254740993.0, 1e300, -1e300, std::numeric_limits<double>::infinity(),
                            -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN(),
                            std::numeric_limits<double>::denorm_min()};
  for (int k = -40; k <= 40; ++k) {
    const double half = k + 0.5;
    for (double x : {half, std::nextafter(half, -1e9), std::nextafter(half, 1e9), static_cast<double>(k),
                     std::nextafter(static_cast<double>(k), -1e9), std::nextafter(static_cast<double>(k), 1e9)})
      xs.push_back(x);
  }
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1e6, 1e6);
  std::uniform_int_distribution<std::uint64_t> bits;
  for (int i = 0; i < 20000; ++i) {
    xs.push_back(u(rng));
    const std::uint64_t b = bits(rng);
    double x;
    std::memcpy(&x, &b, sizeof x);
    xs.push_back(x);
  }
  int mismatches = 0;
  for (double x : xs)
    if (!same_bits(remesh_detail::round_half_away(x), std::round(x))) {
      if (++mismatches <= 5) ADD_FAILURE() << "x = " << x;
    }
  EXPECT_EQ(mismatches, 0);
}

}  // namespace
}  // namespace subd2nurbs::testing
