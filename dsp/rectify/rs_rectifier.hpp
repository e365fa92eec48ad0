// Rolling-shutter rectification of whole frames: the global-shutter image at a reference time.
//
// For every output (global-shutter) pixel p at t_ref the rectifier needs the rolling-shutter
// pixel that saw the same scene point: the inverse of rectify_pixel (rs_backprojection.hpp).
// p's ray at t_ref meets the depth model in a point X; X's rolling-shutter image is the
// solution of the paper's constraint eq. (3), pi_y(P(t_c) X) = r t_c - v0
// (Meingast, Geyer, Sastry 2005, Sec. 2). That exact map is evaluated only at the nodes of a
// coarse grid and interpolated bilinearly in between; the grid is refined until an error bound
// (from the map's second differences, docs/rectification.md) is below the tolerance. The
// image is then resampled bilinearly in fixed point (SIMD kernels for the CPU's instruction set).
//
// Nothing is allocated after construction: the daemon's hot path calls rectify() per frame.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "dsp/core/image_planes.hpp"
#include "dsp/geometry/row_timing.hpp"
#include "dsp/geometry/rs_backprojection.hpp"

namespace rsd::dsp {

// Which instant the global-shutter output shows: the first row read (t = 0) or the middle
// row, which halves the largest correction.
enum class ReferenceRow { First, Middle };
double reference_time(const RowTiming& timing, ReferenceRow ref);

// The ground seen from a camera h metres above it: the plane y = h in the axes of the camera at
// the frame start (y down). Rays above the horizon miss it; there the rectifier uses infinite
// depth, which is where the plane's points tend as they approach the horizon.
DepthModel ground_plane(double camera_height_m);

// Threads the caller owns, lent to rectify() for the resampling (dsp starts none; the daemon's
// worker pool implements this). run(parts, fn, ctx) calls fn(ctx, part) exactly once for every
// part in [0, parts), possibly concurrently, and returns when every call has returned; it must
// not allocate. concurrency() is how many calls may run at once.
class RowExecutor {
 public:
  virtual ~RowExecutor() = default;
  virtual int concurrency() const = 0;
  virtual void run(int parts, void (*fn)(void* ctx, int part), void* ctx) = 0;
};

struct RectifierConfig {
  int initial_spacing = 64;     // node spacing tried first (output px, a power of two >= 2)
  int min_spacing = 4;          // the refinement halves the spacing down to this
  double tolerance_px = 0.05;   // wanted bound on |interpolated - exact source position|
  int table_step_rows = 8;      // pose table step (rows); halved while its error share is large
  bool use_simd = true;         // SIMD kernels of the CPU's best instruction set (same output bit for bit)
  // Row bands resampled at once through the executor (set_executor); scratch for this many is
  // allocated at construction. 1: the calling thread does every row. bands_for(threads) gives
  // an executor's threads their bands.
  int max_bands = 1;
  // The bands for an executor of `threads`: kBandsPerThread each (at most 256), claimed by the
  // threads as they come free, so that one the system takes away for a while leaves most of
  // its share to the others rather than holding the frame up by half of it.
  static constexpr int kBandsPerThread = 4;
  static int bands_for(int threads) { return threads > 1 ? std::min(256, kBandsPerThread * threads) : 1; }
};

struct RectifyReport {
  bool rectified = false;       // false: the frame was copied unrectified
  int spacing = 0;              // node spacing of the map used (of its coarse cells, if some are split)
  int levels_solved = 0;        // grids solved to reach it (levels predicted to miss are skipped)
  // Cells of `spacing` whose bound missed the tolerance, each split into four of fine_spacing
  // (the next level, solved only there); 0: one spacing over the whole map.
  int refined_cells = 0;
  int fine_spacing = 0;         // the finest spacing the map uses (= spacing when none is split)
  double error_bound_px = 0;    // bound on the map error over every cell that is sampled
  int invalid_nodes = 0;        // nodes without a solution in the capture window (cells black)
  int unbounded_cells = 0;      // cells whose bound could not be estimated (invalid neighbours)
  // The largest distance between an output pixel and the captured pixel it is sampled from,
  // over the map's nodes inside both images: the largest correction this frame needed. With an
  // output camera other than the source's it includes that change of camera.
  double max_displacement_px = 0;
  // Of the points that largest correction is taken over, those whose source lies inside the
  // captured image. A map with fewer than half inside would publish a frame that is mostly
  // black (an absurd camera model, a motion out of the model's reach): rectify() does not
  // publish it as rectified (the frame passes through, map_outside set).
  int points_checked = 0, points_inside = 0;
  bool map_outside = false;
  bool mostly_outside() const { return points_checked > 0 && 2 * points_inside < points_checked; }
  bool within_tolerance() const { return error_bound_px <= tolerance_px; }
  double tolerance_px = 0.05;
};

class Rectifier {
 public:
  // Output with the source camera's geometry.
  Rectifier(const CameraModel& cam, const RowTiming& timing, PixelFormat format,
            const RectifierConfig& cfg = {});
  // Output through another camera model (other size, or an undistorted pinhole).
  Rectifier(const CameraModel& cam, const RowTiming& timing, const CameraModel& out_cam,
            PixelFormat format, const RectifierConfig& cfg = {});

  // The frame whose first row is read at its frame start, moving with the constant twist tw
  // (camera-frame velocities, camera_motion.hpp); depth in the axes of the camera at the frame
  // start; t_ref after the frame start. A twist with a non-finite component is no valid
  // velocity: the frame goes out unrectified (pass_through).
  RectifyReport rectify(const ImageView& src, const ImageView& dst, const Twist& tw,
                        const DepthModel& depth, double t_ref);
  // Any motion relative to the camera at the frame start (at(0) = identity).
  RectifyReport rectify(const ImageView& src, const ImageView& dst, const CameraMotion& motion,
                        const DepthModel& depth, double t_ref);
  // Without a valid velocity: the frame unchanged (copied; through the output camera if any).
  RectifyReport pass_through(const ImageView& src, const ImageView& dst);

  // The two halves of rectify(): the map for a motion, then resampling with it.
  RectifyReport build_map(const CameraMotion& motion, const DepthModel& depth, double t_ref);
  void remap(const ImageView& src, const ImageView& dst);
  // Diagnostics: the interpolated source position of every pixel of output row y (the
  // positions the sampler uses, to 1/65536 px); NaN where the output is black by construction.
  void map_row(int y, double* sx, double* sy);

  // Solve the map's node columns and resample the rows in up to
  // min(RectifierConfig::bands_for(executor->concurrency()), cfg.max_bands) bands, which the
  // executor's threads share (nullptr: all on the calling thread). The map and the output are
  // the same byte for byte.
  void set_executor(RowExecutor* executor) { executor_ = executor; }

  bool uses_simd() const { return simd_; }
  const CameraModel& output_camera() const { return out_; }

  // Node arrays and per-frame state (public for the implementation's helpers only).
  struct Level {
    int spacing = 0, shift = 0, nx = 0, ny = 0;
    std::vector<double> ray_x, ray_y;   // unit-z viewing ray of each node pixel, output camera
    std::vector<std::uint8_t> ray_ok;
  };
  struct Branch {                        // source positions of the nodes for one depth choice
    std::vector<double> x, y;
    std::vector<std::uint8_t> ok;
    std::vector<float> d2x, d2y;         // |second difference| along x / y, max over components
  };
  struct Pose {                          // X_c = R X + T at table row v_k, and its increment
    double R[9], T[3], dR[9], dT[3];
  };
  struct Affine {                        // source positions along a cell of a row: a + k s, 16.16
    std::int32_t ax, ay, sx, sy;
  };
  struct Grid {                          // one level's node solutions and cell classes
    std::size_t level = 0;               // index into levels_
    Branch plane, inf;
    std::vector<double> rho;             // inverse depth of each node's point on the plane
    std::vector<std::uint8_t> cell_mode; // CellMode of each cell (fixed_point.hpp)
  };
  struct NodeRow {                       // one grid's node columns interpolated to a row
    std::vector<double> px, py, ix, iy, rho;
    std::vector<std::int32_t> fpx, fpy, fix, fiy;  // the same in 16.16, rounded once per node
    std::vector<Affine> plane_cells, inf_cells;  // the row's cells of each branch (cell_affines.hpp)
  };
  struct RowScratch {                    // one band's state: node values at the row, positions
    NodeRow coarse, fine;                // fine: for the cells split into the next level
    std::vector<std::int32_t> xs, ys;
    double gain = 0;                     // its node columns' largest table-error gain
  };

 private:
  void allocate_levels();
  void build_pose_table(const CameraMotion& motion, int step_rows);
  bool solve_node(const double* Y, double rho, double& v, double* px, double* gain) const;
  double node_rho(const Level& L, std::size_t n) const;
  bool solve_at(const Grid& g, std::size_t n, bool plane_branch, double& v, double* px, double* gain) const;
  void solve_branch(Branch& b, bool plane_branch);
  double solve_columns(Branch& b, bool plane_branch, int i0, int i1);
  void second_differences(Branch& b) const;
  RectifyReport solve_level();
  RectifyReport assess_level();
  std::uint8_t classify_cell(const Grid& g, const std::size_t* c) const;
  // Local refinement: the cells of coarse_ that miss, split into fine_'s next level.
  bool refine_cells(RectifyReport& rep);
  bool solve_fine_node(int a, int b);
  double patch_bound(const Branch& fine, const Branch& coarse, int i, int j) const;
  // max_displacement_px, points_checked and points_inside of the current map.
  void measure_displacement(RectifyReport& rep) const;
  double cell_bound(const Branch& b, int i, int j) const;
  double table_error() const;
  static double fixed_point_error(int spacing);
  std::size_t next_level(std::size_t level, double bound) const;
  int interpolate_row(const Grid& g, double y, NodeRow& r) const;
  bool split(int i, int j) const { return refined_ && split_[static_cast<std::size_t>(j) * (levels_[coarse_.level].nx - 1) + i]; }
  void generate_row(double y, const SamplePlane& g, RowScratch& s) const;
  void generate_cell(const Grid& g, const NodeRow& r, int j, int i, const SamplePlane& p, RowScratch& s) const;
  void kink_segment(const Grid& g, const NodeRow& r, int i, int c0, int c1, const SamplePlane& p, RowScratch& s) const;
  void remap_rows(const SamplePlane& src, const SamplePlane& dst, int j0, int j1, RowScratch& s) const;
  void check_views(const ImageView& src, const ImageView& dst) const;

  CameraModel cam_, out_;
  RowTiming timing_;
  PixelFormat format_;
  RectifierConfig cfg_;
  bool simd_ = false;
  // The kernels of each kind of sample plane (bilinear_sampling.hpp's SampleKind).
  static constexpr int kKinds = 8;  // rectify_detail::kSampleKinds (bilinear_sampling.hpp, not included here)
  void (*sample_row_[kKinds])(const SamplePlane&, const std::int32_t*, const std::int32_t*, std::uint8_t*, int) = {};
  void (*sample_cells_[kKinds])(const SamplePlane&, const Affine*, int, int, std::uint8_t*) = {};

  std::vector<Level> levels_;
  std::vector<Pose> table_;                // allocated for a step of one row
  std::size_t table_n_ = 0;                // entries in use
  double table_v0_ = 0, table_inv_step_ = 0;
  double table_d2R_ = 0, table_d2T_ = 0;   // largest second differences of the table
  double table_error_px_ = 0;              // its share of the bound
  // Per frame: reference geometry and the node solutions of the current level.
  double Rt_ref_[9] = {}, o_ref_[3] = {};  // R_ref^T and the camera centre at t_ref
  bool plane_ = false, need_infinite_ = false;
  double plane_n_[3] = {}, plane_den_ = 1;
  Grid coarse_;                            // the level every cell starts from
  Grid fine_;                              // the next level, solved in the split cells only
  bool refined_ = false;                   // some cells of coarse_ are split
  std::vector<float> cell_error_;          // coarse_'s bound per cell (interpolation part)
  std::vector<std::uint8_t> split_;        // per cell of coarse_: sampled through fine_
  std::vector<std::uint8_t> split_row_;    // per cell row of coarse_: any cell split
  std::vector<std::uint8_t> fine_done_;    // per node of fine_: solved this frame
  double gain_max_ = 0;                    // table-error sensitivity, max over nodes
  std::vector<double> v_start_;            // Newton's start per node column (row solved last)
  bool map_ready_ = false;
  // Per band of rows (max_bands of them): node values interpolated to the row, and the source
  // coordinates (16.16).
  std::vector<RowScratch> bands_;
  RowExecutor* executor_ = nullptr;
};

}  // namespace rsd::dsp
