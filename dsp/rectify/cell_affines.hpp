// A row's map cells as affine segments, source position a + k s at the k-th sample of a cell
// (16.16): the set-up of every resampled row (rs_rectifier_remap.cpp), a cell per lane on the
// SIMD units (Google Highway, runtime dispatch), the same integers on every target as the
// scalar reference below.
#pragma once

#include <cstdint>

#include "dsp/core/image_planes.hpp"
#include "dsp/rectify/rs_rectifier.hpp"

namespace rsd::dsp::rectify_detail {

// A sample plane's place in the image (image_planes.hpp) in whole numbers: its offsets are
// whole or half pixels, its scales 1 or 2.
struct PlaneScale {
  std::int32_t ox2 = 0, oy2 = 0;  // twice the offsets
  int scale_x = 1, scale_y = 1;
  std::int32_t sy_factor = 1;  // a step along the plane's row is scale_x image pixels, sy in its rows of scale_y
  explicit PlaneScale(const SamplePlane& g)
      : ox2(static_cast<std::int32_t>(2 * g.offset_x)), oy2(static_cast<std::int32_t>(2 * g.offset_y)),
        scale_x(g.scale_x), scale_y(g.scale_y), sy_factor(g.scale_x / g.scale_y) {}
  bool unit() const { return scale_x == 1 && scale_y == 1; }
};

// Cell i of a row whose node columns X, Y (16.16) lie 2^shift image pixels apart: it starts at
// node i and steps (node i + 1 - node i) / 2^shift a pixel, rounded to nearest. At the samples
// of plane g: its first sample c0 = i 2^shift / scale_x sits at image x = scale_x c0 + offset_x,
// offset_x into the cell, and a source position P in image pixels is sample (P - offset) /
// scale of the source plane; rounded to nearest, floor((num + scale) / 2 scale). An affine
// cell's nodes lie within kLimit px (fixed_point.hpp), so that every term fits int32.
Rectifier::Affine cell_affine(const std::int32_t* X, const std::int32_t* Y, int i, int shift, const PlaneScale& g);

// cell_affine for the cells [0, n) into out (X and Y hold n + 1 nodes). Cells that are not
// affine (their nodes out of range) get meaningless values: the caller does not use them.
void cell_affines(const std::int32_t* X, const std::int32_t* Y, int n, int shift, const PlaneScale& g, Rectifier::Affine* out);

// The scalar reference of cell_affines, for tests.
void cell_affines_scalar(const std::int32_t* X, const std::int32_t* Y, int n, int shift, const PlaneScale& g,
                         Rectifier::Affine* out);

}  // namespace rsd::dsp::rectify_detail
