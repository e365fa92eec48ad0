// Rectification cost per frame: map rebuilt every frame + remap, single-threaded, in ns per
// output pixel (the "ns/px" counter), at the daemon's sizes, for Mono8 and RGB24, at infinite
// depth and before a plane; and a memcpy of the frame as the memory floor.
//
//   cmake --build build-rect --target bench_rs_rectifier && build-rect/tests/bench_rs_rectifier
//
// The performance goal (rectification at most 1.0x, aiming for 0.33x, the time of cv::remap
// with precomputed CV_16SC2 maps, ~3.5 ns/px single-threaded on a 2.1 GHz core) is judged from
// these numbers; docs/rectification.md keeps the latest.
#include <benchmark/benchmark.h>

#include <cstring>
#include <random>

#include "dsp/rs_rectifier.hpp"

using namespace rsd::dsp;

namespace {

struct Size {
  int w, h;
};
constexpr Size kSizes[] = {{640, 480}, {1280, 720}, {1920, 1080}};

Image noise_image(int w, int h, PixelFormat f) {
  Image img(w, h, f);
  std::mt19937 rng(1);
  for (auto& b : img.data) b = static_cast<std::uint8_t>(rng());
  return img;
}

// A brisk hand-held motion: 1.5 rad/s pan, some tilt and roll, walking speed.
Twist motion() {
  Twist tw;
  tw.v = {0.5, 0.1, 1.0};
  tw.w = {0.3, 1.5, 0.4};
  return tw;
}

// args: size index, format (0 Mono8, 1 Rgb8), depth (0 infinite, 1 plane at 3 m), simd (0/1).
void BM_Rectify(benchmark::State& state) {
  const Size sz = kSizes[state.range(0)];
  const PixelFormat f = state.range(1) ? PixelFormat::Rgb8 : PixelFormat::Mono8;
  const DepthModel depth = state.range(2) ? DepthModel::fronto_parallel(3.0) : DepthModel::at_infinity();
  const CameraModel cam = CameraModel::from_hfov(sz.w, sz.h, 1.0);
  const RowTiming timing = RowTiming::full_frame(sz.h, 30);
  RectifierConfig cfg;
  cfg.use_simd = state.range(3) != 0;
  Rectifier rect(cam, timing, f, cfg);
  Image src = noise_image(sz.w, sz.h, f), dst(sz.w, sz.h, f);
  const double t_ref = reference_time(timing, ReferenceRow::Middle);
  RectifyReport rep;
  Twist tw = motion();
  for (auto _ : state) {
    tw.w.y() += 1e-9;  // a new velocity every frame: the map is rebuilt, never cached
    rep = rect.rectify(src.view(), dst.view(), tw, depth, t_ref);
    benchmark::DoNotOptimize(dst.data.data());
    benchmark::ClobberMemory();
  }
  const double pixels = static_cast<double>(sz.w) * sz.h;
  state.counters["ns/px"] = benchmark::Counter(pixels * state.iterations(),
                                               benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["spacing"] = rep.spacing;
  state.counters["bound_px"] = rep.error_bound_px;
  state.counters["simd"] = rect.uses_simd();
  state.SetLabel(std::to_string(sz.w) + "x" + std::to_string(sz.h) + (state.range(1) ? " rgb24 " : " mono8 ") +
                 (state.range(2) ? "plane" : "infinite"));
}

// The map alone (nodes, bound, refinement): what the remap adds to is the rest.
void BM_BuildMap(benchmark::State& state) {
  const Size sz = kSizes[state.range(0)];
  const CameraModel cam = CameraModel::from_hfov(sz.w, sz.h, 1.0);
  const RowTiming timing = RowTiming::full_frame(sz.h, 30);
  Rectifier rect(cam, timing, PixelFormat::Mono8);
  const DepthModel depth = state.range(1) ? DepthModel::fronto_parallel(3.0) : DepthModel::at_infinity();
  Twist tw = motion();
  for (auto _ : state) {
    tw.w.y() += 1e-9;
    benchmark::DoNotOptimize(rect.build_map(ScrewMotion(tw), depth, reference_time(timing, ReferenceRow::Middle)));
  }
  state.counters["ns/px"] = benchmark::Counter(static_cast<double>(sz.w) * sz.h * state.iterations(),
                                               benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// Memory floor: copying the frame.
void BM_Memcpy(benchmark::State& state) {
  const Size sz = kSizes[state.range(0)];
  const PixelFormat f = state.range(1) ? PixelFormat::Rgb8 : PixelFormat::Mono8;
  Image src = noise_image(sz.w, sz.h, f), dst(sz.w, sz.h, f);
  for (auto _ : state) {
    std::memcpy(dst.data.data(), src.data.data(), src.data.size());
    benchmark::ClobberMemory();
  }
  state.counters["ns/px"] = benchmark::Counter(static_cast<double>(sz.w) * sz.h * state.iterations(),
                                               benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

}  // namespace

BENCHMARK(BM_Rectify)
    ->ArgsProduct({{0, 1, 2}, {0, 1}, {0, 1}, {1}})
    ->ArgsProduct({{0, 1, 2}, {0, 1}, {0}, {0}})  // scalar kernels, for comparison
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_BuildMap)->ArgsProduct({{0, 1, 2}, {0, 1}})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Memcpy)->ArgsProduct({{0, 1, 2}, {0, 1}})->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
