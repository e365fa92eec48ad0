// A row's cells as affine segments (cell_affines.hpp) on every instruction set this CPU runs,
// against the scalar reference (the same integers), and the reference against the exact
// positions of the plane's samples along each cell.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "dsp/rectify/bilinear_sampling.hpp"
#include "dsp/rectify/cell_affines.hpp"
#include "dsp/rectify/fixed_point.hpp"
#include "tests/dsp/rectify/simd_targets.hpp"

using namespace rsd::dsp;
using namespace rsd::dsp::rectify_detail;
using namespace rsd::dsp::test;

namespace {

// The sample planes of every format (image_planes.cpp): a unit plane, 4:2:0 chroma (half-pixel
// offsets), 4:2:2 chroma (full rows), and the four sites of a mosaic.
std::vector<SamplePlane> planes() {
  std::vector<SamplePlane> out;
  auto plane = [](int sx, int sy, double ox, double oy) {
    SamplePlane g;
    g.scale_x = sx, g.scale_y = sy, g.offset_x = ox, g.offset_y = oy;
    return g;
  };
  out.push_back(plane(1, 1, 0, 0));
  out.push_back(plane(2, 2, 0.5, 0.5));
  out.push_back(plane(2, 1, 0, 0));
  for (int k = 0; k < 4; ++k) out.push_back(plane(2, 2, k & 1, k >> 1));
  return out;
}

// Node columns as the map has them (16.16): anywhere within kLimit px, neighbours up to a few
// hundred pixels apart and in either order (a map that magnifies, shrinks or mirrors), and the
// extremes of the range.
void random_nodes(std::mt19937& rng, int n, std::vector<std::int32_t>& X, std::vector<std::int32_t>& Y) {
  std::uniform_real_distribution<double> pos(-kLimit, kLimit), step(-300, 300);
  X.resize(n + 1), Y.resize(n + 1);
  double x = pos(rng) / 2, y = pos(rng) / 2;
  for (int i = 0; i <= n; ++i, x = std::clamp(x + step(rng), -kLimit, kLimit), y = std::clamp(y + step(rng) / 10, -kLimit, kLimit))
    X[i] = to_fixed(x), Y[i] = to_fixed(y);
  if (n > 2) X[1] = to_fixed(kLimit), X[2] = to_fixed(-kLimit), Y[2] = to_fixed(kLimit);  // the range's ends, a jump of 2 kLimit
}

// Nodes with no solution, as the map's rows hold them (any int32: a NaN or a far value
// converted), at every third node from `first` on; returns whether cell i has both its nodes.
std::vector<bool> unsolve(std::vector<std::int32_t>& X, std::vector<std::int32_t>& Y, int first) {
  const int n = static_cast<int>(X.size()) - 1;
  std::vector<bool> solved(X.size(), true), affine(n);
  for (int k = first; k <= n; k += 3) {
    X[k] = k % 2 ? std::numeric_limits<std::int32_t>::min() : std::numeric_limits<std::int32_t>::max();
    Y[k] = -X[k] - 1, solved[k] = false;
  }
  for (int i = 0; i < n; ++i) affine[i] = solved[i] && solved[i + 1];
  return affine;
}

bool operator==(const Rectifier::Affine& a, const Rectifier::Affine& b) {
  return a.ax == b.ax && a.ay == b.ay && a.sx == b.sx && a.sy == b.sy;
}

TEST_F(EveryTarget, ComputesTheReferenceIntegers) {
  std::mt19937 rng(11);
  std::vector<std::int32_t> X, Y;
  for_every_target([&](std::int64_t target) {
    for (const SamplePlane& g : planes())
      for (int shift : {2, 3, 4, 5, 6})
        for (int n : {1, 3, 4, 7, 8, 9, 15, 16, 17, 30, 61}) {
          random_nodes(rng, n, X, Y);
          const PlaneScale scale(g);
          std::vector<Rectifier::Affine> got(n + 1, {7, 7, 7, 7}), want(n);
          cell_affines_scalar(X.data(), Y.data(), n, shift, scale, want.data());
          // Unsolved nodes beside them (some rows): their cells are not compared, but computing
          // them must not disturb the others (nor, in the sanitizer tree, overflow an int).
          const std::vector<bool> affine = n > 2 && shift % 2 ? unsolve(X, Y, n % 3) : std::vector<bool>(n, true);
          cell_affines(X.data(), Y.data(), n, shift, scale, got.data());
          for (int i = 0; i < n; ++i) {
            if (!affine[i]) continue;
            EXPECT_TRUE(got[i] == want[i]) << target_name(target) << " scale " << g.scale_x << "x" << g.scale_y << " offset "
                                           << g.offset_x << "," << g.offset_y << " shift " << shift << " n " << n << " cell " << i
                                           << ": " << got[i].ax << " " << got[i].ay << " " << got[i].sx << " " << got[i].sy
                                           << " vs " << want[i].ax << " " << want[i].ay << " " << want[i].sx << " " << want[i].sy;
          }
          EXPECT_TRUE(got[n] == (Rectifier::Affine{7, 7, 7, 7})) << target_name(target) << ": wrote past the cells, n " << n;
        }
  });
}

// Sample k of a cell's segment in plane g lies at image x = scale_x (c0 + k) + offset_x, a
// fraction of the way between the cell's nodes; the map's position there, in the source
// plane's samples, is (P - offset) / scale. The segment matches it to rounding: the start within
// a 16.16 unit, the step within one (both rounded to nearest), so sample k within k + 1 units.
TEST(Reference, IsTheInterpolatedPositionInThePlanesSamples) {
  std::mt19937 rng(3);
  std::vector<std::int32_t> X, Y;
  for (const SamplePlane& g : planes())
    for (int shift : {3, 5}) {
      const int spacing = 1 << shift, n = 12, per_cell = spacing / g.scale_x;
      random_nodes(rng, n, X, Y);
      std::vector<Rectifier::Affine> aff(n);
      cell_affines_scalar(X.data(), Y.data(), n, shift, PlaneScale(g), aff.data());
      for (int i = 0; i < n; ++i)
        for (int k = 0; k < per_cell; ++k) {
          const double x = g.scale_x * (i * per_cell + k) + g.offset_x;  // image column of the sample
          const double t = (x - i * spacing) / spacing;                  // its place in the cell
          const double px = (X[i] + t * (static_cast<double>(X[i + 1]) - X[i])) / kFix;
          const double py = (Y[i] + t * (static_cast<double>(Y[i + 1]) - Y[i])) / kFix;
          const double want_x = (px - g.offset_x) / g.scale_x, want_y = (py - g.offset_y) / g.scale_y;
          const double got_x = (aff[i].ax + static_cast<double>(k) * aff[i].sx) / kFix;
          const double got_y = (aff[i].ay + static_cast<double>(k) * aff[i].sy) / kFix;
          const double tol = (k + 1.5) / kFix;
          EXPECT_NEAR(got_x, want_x, tol) << "scale " << g.scale_x << "x" << g.scale_y << " cell " << i << " sample " << k;
          EXPECT_NEAR(got_y, want_y, tol) << "scale " << g.scale_x << "x" << g.scale_y << " cell " << i << " sample " << k;
        }
    }
}

}  // namespace
