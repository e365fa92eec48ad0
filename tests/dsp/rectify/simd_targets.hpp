// Tests that hold on every SIMD target this CPU runs (bilinear_sampling.hpp's simd_targets):
// each target forced in turn, and the default dispatch restored when the test ends.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "dsp/rectify/bilinear_sampling.hpp"

namespace rsd::dsp::test {

// The fixture of such tests: a failed assertion would otherwise leave its target forced for the
// tests after it.
class EveryTarget : public ::testing::Test {
 protected:
  void TearDown() override { rectify_detail::force_simd_target(0); }
};

// fn(target) with every target forced in turn; a CPU with none fails the test.
template <class Fn>
void for_every_target(Fn fn) {
  const std::vector<std::int64_t> targets = rectify_detail::simd_targets();
  ASSERT_FALSE(targets.empty());
  for (std::int64_t target : targets) {
    rectify_detail::force_simd_target(target);
    fn(target);
  }
}

}  // namespace rsd::dsp::test
