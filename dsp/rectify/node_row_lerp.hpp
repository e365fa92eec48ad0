// The map's node columns interpolated to one image row: the first step of every resampled row
// (rs_rectifier_remap.cpp), a few dozen nodes per row and branch, on the SIMD units of the CPU
// (Google Highway, runtime dispatch) like the resampling itself.
#pragma once

#include <cstdint>

namespace rsd::dsp::rectify_detail {

// out[i] = top[i] + w (bot[i] - top[i]) for i in [0, n), and, when fixed is not null,
// fixed[i] = to_fixed(out[i]) (fixed_point.hpp: 16.16, half away from zero; kSentinel for a NaN
// or a value past kLimit). Every target computes the same doubles and fixed values as the scalar
// reference below (no fused multiply-add: the file is compiled with -ffp-contract=off), so the
// map does not depend on the instruction set.
void lerp_node_row(const double* top, const double* bot, double w, int n, double* out, std::int32_t* fixed);

// The scalar reference, for tests.
void lerp_node_row_scalar(const double* top, const double* bot, double w, int n, double* out, std::int32_t* fixed);

}  // namespace rsd::dsp::rectify_detail
