// The rectifier against independent ground truth:
// - its interpolated map against the exact inverse at every pixel (exact_map.hpp): the
//   output pixel's ray meets the depth model in a Euclidean point, which the paper's bracketed
//   root finder (project_trajectory, eq. (3)) projects with the exact screw motion;
// - (its images against the renderer's global-shutter frame: test_rs_rectifier_render.cpp);
// - its sampling against a double-precision bilinear interpolation;
// - zero motion is the identity, SIMD equals scalar bit for bit, bands of rows on other threads
//   equal one thread's image, and rectify() allocates nothing (every global operator new counted: tests/support/allocation_counter.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <thread>
#include <vector>

#include "dsp/geometry/rs_projection.hpp"
#include "dsp/rectify/bilinear_sampling.hpp"
#include "dsp/rectify/rs_rectifier.hpp"
#include "tests/dsp/rectify/exact_map.hpp"
#include "tests/dsp/rectify/simd_targets.hpp"
#include "tests/support/allocation_counter.hpp"  // every C++ allocation of this process, counted
#include "tests/support/sanitizer.hpp"

using namespace rsd::dsp;
using namespace rsd::dsp::test;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

struct MapCheck {
  double worst = 0;
  long compared = 0, black_but_inside = 0;
  double largest_displacement = 0;  // the largest |exact source - output pixel| seen
};

MapCheck check_map(const Case& c, Rectifier& rect, int step) {
  const ScrewMotion motion(c.tw);
  MapCheck m;
  std::vector<double> sx(c.cam.width), sy(c.cam.width);
  for (int y = 0; y < c.cam.height; y += step) {
    rect.map_row(y, sx.data(), sy.data());
    for (int x = 0; x < c.cam.width; x += step) {
      const RsProjection e = exact_source(c, motion, Vector2d(x, y));
      if (!e.ok() || !c.cam.contains(e.pixel, 0.0)) continue;  // black in the output: fine
      m.largest_displacement = std::max(m.largest_displacement, (e.pixel - Vector2d(x, y)).norm());
      if (std::isnan(sx[x])) {
        m.black_but_inside += c.cam.contains(e.pixel, -1.0);
        continue;
      }
      ++m.compared;
      m.worst = std::max(m.worst, (Vector2d(sx[x], sy[x]) - e.pixel).norm());
    }
  }
  return m;
}

Image random_image(int w, int h, PixelFormat f, unsigned seed) {
  Image img(w, h, f);
  std::mt19937 rng(seed);
  for (auto& b : img.data) b = static_cast<std::uint8_t>(rng());
  return img;
}

}  // namespace

// The map against the exact inverse (the reference) at every pixel: within its own error bound
// and 0.05 px. And the largest correction the map reports is the largest |exact source -
// output pixel| over the image, to within the spacing of the nodes it is taken over (the edges
// and corners where it peaks lie within a node spacing): checked on the same exact inverse,
// which costs 15 s of the quick suite, so once for both.
TEST(RsRectifier, MapMatchesTheExactInverseAtEveryPixel) {
  // Under a sanitizer every fifth pixel of every fifth row, under qemu every tenth (the exact
  // inverse costs ten and thirty times as much there: 19 s at every third, 138 s at every
  // fifth), the map's own code runs whole either way. The largest displacement needs every
  // pixel: the normal build's.
  const int step = rsd::test::kEmulated ? 10 : rsd::test::kSanitized ? 5 : 1;
  int split_maps = 0;
  for (const Case& c : cases()) {
    Rectifier rect(c.cam, c.timing, PixelFormat::Mono8);
    const RectifyReport rep = rect.build_map(ScrewMotion(c.tw), c.depth, c.t_ref);
    const MapCheck m = check_map(c, rect, step);
    std::printf("[ map ] %-24s spacing %2d (%3d cells split to %2d)  worst %.4f px  bound %.4f px  (%ld px compared)\n",
                c.name, rep.spacing, rep.refined_cells, rep.fine_spacing, m.worst, rep.error_bound_px, m.compared);
    split_maps += rep.refined_cells > 0;
    EXPECT_GT(m.compared, c.cam.width * c.cam.height / (2 * step * step)) << c.name;
    EXPECT_EQ(m.black_but_inside, 0) << c.name;
    EXPECT_EQ(rep.invalid_nodes, 0) << c.name;
    EXPECT_TRUE(rep.within_tolerance()) << c.name << " bound " << rep.error_bound_px;
    EXPECT_LE(m.worst, rep.error_bound_px) << c.name;  // the bound holds
    EXPECT_LT(m.worst, 0.05) << c.name;
    if (step != 1) continue;
    const double brute = m.largest_displacement;
    std::printf("[ max ] %-24s map %.3f px  every pixel %.3f px\n", c.name, rep.max_displacement_px, brute);
    EXPECT_GT(brute, 5.0) << c.name;  // a visible correction, not a trivially small one
    EXPECT_LE(rep.max_displacement_px, brute + 0.05) << c.name;
    EXPECT_GE(rep.max_displacement_px, 0.97 * brute - 0.05) << c.name;
  }
  EXPECT_GE(split_maps, 2);  // the cases include maps whose missing cells alone are split
}

TEST(RsRectifier, RefinesTheGridOnlyWhenTheBoundNeedsIt) {
  const CameraModel cam = camera(480, 360, 60);
  const RowTiming timing = RowTiming::full_frame(360, 30);
  RectifierConfig cfg;
  cfg.initial_spacing = 64;
  Rectifier rect(cam, timing, PixelFormat::Mono8, cfg);
  const double mid = reference_time(timing, ReferenceRow::Middle);
  const RectifyReport slow = rect.build_map(ScrewMotion(twist({0, 0, 0}, {0, 0.2, 0})), DepthModel::at_infinity(), mid);
  EXPECT_EQ(slow.spacing, 64);
  const RectifyReport fast = rect.build_map(ScrewMotion(twist({0, 0, 0}, {1, 8, 3})), DepthModel::at_infinity(), mid);
  EXPECT_LT(fast.spacing, 64);
  EXPECT_TRUE(fast.within_tolerance());
  // The bound at the chosen spacing holds against the exact map (every 3rd pixel; every 9th
  // under qemu, where the exact inverse costs thirty times as much).
  Case c{"refined", cam, timing, twist({0, 0, 0}, {1, 8, 3}), DepthModel::at_infinity(), mid};
  const MapCheck m = check_map(c, rect, rsd::test::kEmulated ? 9 : 3);
  EXPECT_LE(m.worst, fast.error_bound_px);
}

// The refinement skips the levels the bound's scaling predicts to miss; on these cases its
// finest cells are those of the level a search one level at a time finds (the coarsest within
// the tolerance: rectifiers that each have a single spacing, the independent path), or coarser
// where only the cells that miss are split, so it costs no accuracy and wastes no resolution,
// and the fast motions solve fewer grids than that search.
TEST(RsRectifier, SkippedLevelsWouldHaveMissedTheTolerance) {
  std::vector<Case> all = cases();
  const CameraModel hd = camera(1920, 1080, 60);
  const RowTiming hd_timing = RowTiming::full_frame(1080, 30);
  const double hd_mid = reference_time(hd_timing, ReferenceRow::Middle);
  for (double wy : {0.2, 1.5, 6.0})  // slow, the benchmark's, fast
    all.push_back({"hd", hd, hd_timing, twist({0.5, 0.1, 1.0}, {0.3, wy, 0.4}), DepthModel::at_infinity(), hd_mid});
  int skipped = 0;
  for (const Case& c : all) {
    Rectifier rect(c.cam, c.timing, PixelFormat::Mono8);
    const RectifyReport rep = rect.build_map(ScrewMotion(c.tw), c.depth, c.t_ref);
    int coarsest = 0, searched = 0;
    for (int s = RectifierConfig{}.initial_spacing; s >= RectifierConfig{}.min_spacing && !coarsest; s /= 2) {
      RectifierConfig one;
      one.initial_spacing = one.min_spacing = s;
      Rectifier single(c.cam, c.timing, PixelFormat::Mono8, one);
      const RectifyReport r = single.build_map(ScrewMotion(c.tw), c.depth, c.t_ref);
      searched += r.levels_solved;  // its grids, once per pose table tried (a fisheye's is refined)
      if (r.within_tolerance()) coarsest = s;
    }
    std::printf("[ level ] %-24s spacing %2d (%3d cells split to %2d) after %d grids; one at a time %2d after %d\n",
                c.name, rep.spacing, rep.refined_cells, rep.fine_spacing, rep.levels_solved, coarsest, searched);
    if (rep.refined_cells == 0) EXPECT_EQ(rep.spacing, coarsest) << c.name;
    else EXPECT_EQ(rep.spacing, 2 * rep.fine_spacing) << c.name;  // split cells: the next level
    EXPECT_GE(rep.fine_spacing, coarsest) << c.name;
    EXPECT_LE(rep.spacing, std::max(2 * coarsest, RectifierConfig{}.min_spacing)) << c.name;
    EXPECT_TRUE(rep.within_tolerance()) << c.name;
    EXPECT_LE(rep.levels_solved, searched) << c.name;
    skipped += searched - rep.levels_solved;
  }
  EXPECT_GT(skipped, 0);  // the prediction does skip
}

TEST(RsRectifier, MotionBeyondTheFinestGridIsReportedNotHidden) {
  // 20 rad/s: even 4 px cells cannot keep the bound under 0.05 px. The frame is rectified
  // anyway, the report says so, and the bound still holds (every 2nd pixel; every 6th under
  // qemu, where the exact inverse costs thirty times as much).
  const CameraModel cam = camera(480, 360, 60);
  const RowTiming timing = RowTiming::full_frame(360, 30);
  const Case c{"extreme", cam, timing, twist({0, 0, 0}, {2, 20, 5}), DepthModel::at_infinity(),
               reference_time(timing, ReferenceRow::Middle)};
  Rectifier rect(cam, timing, PixelFormat::Mono8);
  const RectifyReport rep = rect.build_map(ScrewMotion(c.tw), c.depth, c.t_ref);
  EXPECT_TRUE(rep.rectified);
  EXPECT_FALSE(rep.within_tolerance());
  EXPECT_EQ(rep.spacing, 4);
  const MapCheck m = check_map(c, rect, rsd::test::kEmulated ? 6 : 2);
  EXPECT_LE(m.worst, rep.error_bound_px);
  EXPECT_EQ(m.black_but_inside, 0);
}

TEST(RsRectifier, FirstRowReferenceLeavesTheFirstRowInPlace) {
  // At infinite depth a point on row 0 at t_ref = 0 is captured at t = 0 by row 0.
  const CameraModel cam = camera(480, 360, 60);
  const RowTiming timing = RowTiming::full_frame(360, 30);
  Rectifier rect(cam, timing, PixelFormat::Mono8);
  rect.build_map(ScrewMotion(twist({1, 0, 0}, {0.5, 3, 1})), DepthModel::at_infinity(),
                 reference_time(timing, ReferenceRow::First));
  std::vector<double> sx(480), sy(480);
  rect.map_row(0, sx.data(), sy.data());
  for (int x = 0; x < 480; ++x) {
    if (std::isnan(sx[x])) continue;  // mapped outside the frame
    EXPECT_NEAR(sx[x], x, 0.05);
    EXPECT_NEAR(sy[x], 0, 0.05);
  }
  EXPECT_DOUBLE_EQ(reference_time(timing, ReferenceRow::First), 0.0);
  EXPECT_DOUBLE_EQ(reference_time(timing, ReferenceRow::Middle), 179.5 * timing.line_delay_s);
  const RowTiming bt = RowTiming::full_frame(360, 30, Readout::BottomToTop);
  EXPECT_NEAR(reference_time(bt, ReferenceRow::Middle), 179.5 * bt.line_delay_s, 1e-15);
}

TEST(RsRectifier, ZeroMotionIsTheIdentity) {
  const CameraModel cam = camera(203, 117, 50);  // odd sizes: the SIMD tails and edges
  const RowTiming timing = RowTiming::full_frame(117, 30);
  for (PixelFormat f : {PixelFormat::Mono8, PixelFormat::Mono16, PixelFormat::Rgb8})
    for (bool simd : {false, true}) {
      RectifierConfig cfg;
      cfg.use_simd = simd;
      Rectifier rect(cam, timing, f, cfg);
      Image src = random_image(cam.width, cam.height, f, 7), dst(cam.width, cam.height, f);
      const RectifyReport rep = rect.rectify(src.view(), dst.view(), Twist{}, DepthModel::fronto_parallel(2), 0.0);
      EXPECT_TRUE(rep.rectified);
      EXPECT_EQ(dst.data, src.data) << "format " << static_cast<int>(f) << " simd " << simd;
    }
}

TEST_F(EveryTarget, SimdRectifierEqualsScalarBitForBit) {
  // Every case: spacings 8 (positions through the row arrays) to 32 (generated per cell);
  // every instruction set compiled in that this CPU runs.
  RectifierConfig scalar_cfg;
  scalar_cfg.use_simd = false;
  for_every_target([&](std::int64_t target) {
    for (const Case& c : cases())
      for (PixelFormat f : {PixelFormat::Mono8, PixelFormat::Mono16, PixelFormat::Rgb8}) {
        Rectifier simd(c.cam, c.timing, f), scalar(c.cam, c.timing, f, scalar_cfg);
        Image src = random_image(c.cam.width, c.cam.height, f, 11);
        Image a(c.cam.width, c.cam.height, f), b(c.cam.width, c.cam.height, f);
        simd.rectify(src.view(), a.view(), c.tw, c.depth, c.t_ref);
        scalar.rectify(src.view(), b.view(), c.tw, c.depth, c.t_ref);
        EXPECT_EQ(a.data, b.data) << rectify_detail::target_name(target) << " " << c.name << ", format "
                                  << static_cast<int>(f);
      }
  });
}

TEST(RsRectifier, SamplingIsBilinearWithABlackBorder) {
  // Against a double-precision bilinear interpolation, taps outside the image reading 0, at the
  // map's positions rounded to the sampler's 1/256 px: equal up to the two roundings (one per
  // direction, together at most 1 grey level).
  const Case c = cases()[2];
  for (PixelFormat f : {PixelFormat::Mono8, PixelFormat::Rgb8}) {
    Rectifier rect(c.cam, c.timing, f);
    Image src = random_image(c.cam.width, c.cam.height, f, 5), dst(c.cam.width, c.cam.height, f);
    rect.rectify(src.view(), dst.view(), c.tw, c.depth, c.t_ref);
    const int C = channels(f);
    auto px = [&](int x, int y, int ch) -> double {
      if (x < 0 || y < 0 || x >= src.width || y >= src.height) return 0;
      return src.data[(static_cast<size_t>(y) * src.width + x) * C + ch];
    };
    std::vector<double> sx(c.cam.width), sy(c.cam.width);
    double worst = 0;
    long border = 0;
    for (int y = 0; y < c.cam.height; ++y) {
      rect.map_row(y, sx.data(), sy.data());
      for (int x = 0; x < c.cam.width; ++x)
        for (int ch = 0; ch < C; ++ch) {
          double ref = 0;
          if (!std::isnan(sx[x])) {
            const double qx = std::floor(sx[x] * 256 + 0.5) / 256, qy = std::floor(sy[x] * 256 + 0.5) / 256;
            const int x0 = static_cast<int>(std::floor(qx)), y0 = static_cast<int>(std::floor(qy));
            const double a = qx - x0, b = qy - y0;
            ref = (1 - b) * ((1 - a) * px(x0, y0, ch) + a * px(x0 + 1, y0, ch)) +
                  b * ((1 - a) * px(x0, y0 + 1, ch) + a * px(x0 + 1, y0 + 1, ch));
            border += x0 < 0 || y0 < 0 || x0 >= src.width - 1 || y0 >= src.height - 1;
          }
          worst = std::max(worst, std::abs(ref - dst.data[(static_cast<size_t>(y) * dst.width + x) * C + ch]));
        }
    }
    EXPECT_LE(worst, 1.0) << "format " << static_cast<int>(f);
    EXPECT_GT(border, 100);  // the motion does push part of the frame over the border
  }
}

TEST(RsRectifier, WithoutAValidVelocityTheFrameGoesOutUnrectified) {
  const CameraModel cam = camera(64, 48, 60);
  Rectifier rect(cam, RowTiming::full_frame(48, 30), PixelFormat::Rgb8);
  Image src = random_image(64, 48, PixelFormat::Rgb8, 1), dst(64, 48, PixelFormat::Rgb8);
  Twist bad;
  bad.w.x() = std::nan("");
  const RectifyReport rep = rect.rectify(src.view(), dst.view(), bad, DepthModel::at_infinity(), 0.0);
  EXPECT_FALSE(rep.rectified);
  EXPECT_EQ(dst.data, src.data);
}

TEST(RsRectifier, RejectsViewsThatDoNotMatch) {
  const CameraModel cam = camera(64, 48, 60);
  Rectifier rect(cam, RowTiming::full_frame(48, 30), PixelFormat::Mono8);
  Image src(64, 48, PixelFormat::Mono8), wrong_size(60, 48, PixelFormat::Mono8), wrong_format(64, 48, PixelFormat::Rgb8);
  EXPECT_THROW(rect.rectify(src.view(), wrong_size.view(), Twist{}, DepthModel::at_infinity(), 0), std::invalid_argument);
  EXPECT_THROW(rect.rectify(wrong_format.view(), src.view(), Twist{}, DepthModel::at_infinity(), 0), std::invalid_argument);
  RectifierConfig bad;
  bad.initial_spacing = 24;
  EXPECT_THROW(Rectifier(cam, RowTiming::full_frame(48, 30), PixelFormat::Mono8, bad), std::invalid_argument);
}

namespace {

// Runs the parts in reverse order on the calling thread: bands out of order, no threads.
struct ReverseExecutor : RowExecutor {
  int n;
  explicit ReverseExecutor(int bands) : n(bands) {}
  int concurrency() const override { return n; }
  void run(int parts, void (*fn)(void*, int), void* ctx) override {
    for (int p = parts - 1; p >= 0; --p) fn(ctx, p);
  }
};

// One thread per part, started per call (a test executor; the daemon's pool keeps its threads).
struct ThreadExecutor : RowExecutor {
  int n;
  explicit ThreadExecutor(int bands) : n(bands) {}
  int concurrency() const override { return n; }
  void run(int parts, void (*fn)(void*, int), void* ctx) override {
    std::vector<std::thread> threads;
    for (int p = 1; p < parts; ++p) threads.emplace_back(fn, ctx, p);
    fn(ctx, 0);
    for (auto& t : threads) t.join();
  }
};

}  // namespace

TEST(RsRectifier, BandsOfRowsOnOtherThreadsGiveTheSameImage) {
  // A rotation and the ground plane (cells the horizon crosses), every format: byte for byte the
  // single-threaded image, in bands on threads and out of order (max_bands 4: executors of 2, 3
  // and 5 threads, asking for 8, 12 and 20 bands, use 4).
  const std::vector<Case> all = cases();
  for (const Case& c : {all[0], all[3]})
    for (PixelFormat f : {PixelFormat::Mono8, PixelFormat::Rgb8, PixelFormat::Mono16}) {
      Rectifier one(c.cam, c.timing, f);
      Image src = random_image(c.cam.width, c.cam.height, f, 13), want(c.cam.width, c.cam.height, f);
      one.rectify(src.view(), want.view(), c.tw, c.depth, c.t_ref);
      RectifierConfig cfg;
      cfg.max_bands = 4;
      Rectifier many(c.cam, c.timing, f, cfg);
      ThreadExecutor threads(2);
      ReverseExecutor reverse(3), too_many(5);
      std::vector<RowExecutor*> executors{&reverse, &too_many};
      if (!std::getenv("RSD_TEST_NO_THREADS")) executors.push_back(&threads);  // (qemu-user: tests/cross)
      for (RowExecutor* e : executors) {
        many.set_executor(e);
        Image got(c.cam.width, c.cam.height, f);
        many.rectify(src.view(), got.view(), c.tw, c.depth, c.t_ref);
        EXPECT_EQ(got.data, want.data) << c.name << ", format " << static_cast<int>(f) << ", " << e->concurrency()
                                       << " bands asked";
      }
    }
}

TEST(RsRectifier, RectifyAllocatesNothingAfterConstruction) {
  // Also in bands over an executor that itself allocates nothing.
  const CameraModel cam = camera(320, 240, 60);
  const RowTiming timing = RowTiming::full_frame(240, 30);
  RectifierConfig cfg;
  cfg.max_bands = 3;
  Rectifier rect(cam, timing, PixelFormat::Mono8, cfg);
  ReverseExecutor reverse(3);
  rect.set_executor(&reverse);
  Image src = random_image(320, 240, PixelFormat::Mono8, 2), dst(320, 240, PixelFormat::Mono8);
  const double mid = reference_time(timing, ReferenceRow::Middle);
  const DepthModel depths[3] = {DepthModel::at_infinity(), DepthModel::fronto_parallel(2), ground_plane(1.5)};
  Twist bad;
  bad.v.x() = std::nan("");
  auto frame = [&](int i) {
    const Twist tw = twist({0.1 * (i % 7), 0, 3}, {0.2, 0.5 + 0.05 * (i % 50), 0.3});
    if (i % 10 == 9) return rect.rectify(src.view(), dst.view(), bad, depths[0], mid);
    return rect.rectify(src.view(), dst.view(), tw, depths[i % 3], mid);
  };
  for (int i = 0; i < 10; ++i) frame(i);  // warm-up
  // Under a sanitizer or qemu 200 calls, every motion, depth and bad twist of the cycle still met.
  const int calls = rsd::test::kSlowBuild ? 200 : 1000;
  int split = 0;  // frames whose map split some cells into the next level (its own arrays)
  const uint64_t before = g_allocations.load();
  for (int i = 0; i < calls; ++i) split += frame(i).refined_cells > 0;
  const uint64_t allocations = g_allocations.load() - before;
  std::printf("[ alloc ] %llu allocations in %d rectify() calls (%d with split cells)\n",
              static_cast<unsigned long long>(allocations), calls, split);
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(split, calls / 10);
}
