#include "dsp/diagnosis/observation_choice.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <map>
#include <numeric>

#include "dsp/diagnosis/uncertainty.hpp"

namespace rsd::dsp {

namespace {

// Half the weight by information, half evenly: the mixture keeps every part of the recording in
// reach (the remainder must see what the table lacks, wherever it is).
std::vector<double> mixed(const std::vector<double>& information) {
  const double total = std::accumulate(information.begin(), information.end(), 0.0);
  const double even = 1.0 / static_cast<double>(information.size());
  std::vector<double> w(information.size(), even);
  if (total > 0)
    for (size_t k = 0; k < w.size(); ++k) w[k] = 0.5 * information[k] / total + 0.5 * even;
  return w;
}

// The observations of idx grouped by frame (pair), in time order.
std::vector<std::vector<int>> by_frame(const DiagnosisModel& m, const std::vector<int>& idx) {
  std::map<int, std::vector<int>> g;
  for (int i : idx) g[m.frame_rank(i)].push_back(i);
  std::vector<std::vector<int>> out;
  out.reserve(g.size());
  for (auto& [rank, obs] : g) out.push_back(std::move(obs));
  return out;
}

// The places of `frames` in runs of `run` consecutive ones (the last may be shorter).
std::vector<std::vector<size_t>> in_runs(size_t frames, size_t run) {
  std::vector<std::vector<size_t>> runs;
  for (size_t f = 0; f < frames; f += run) {
    runs.emplace_back();
    for (size_t g = f; g < std::min(f + run, frames); ++g) runs.back().push_back(g);
  }
  return runs;
}

// `count` of the items of v, evenly spread.
template <class T>
std::vector<T> evenly(const std::vector<T>& v, size_t count) {
  std::vector<T> out;
  for (size_t k : systematic_choice(std::vector<double>(v.size(), 1.0), count)) out.push_back(v[k]);
  return out;
}

// The gyro's mean rate over [t0, t1) and its change across it (the second half's mean less the
// first's); zeros where no sample falls in a half.
struct PairMotion {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), change = Eigen::Vector3d::Zero();
};

PairMotion pair_motion(const std::vector<GyroSample>& gyro, double t0, double t1) {
  const auto at = [&](double t) {
    return std::lower_bound(gyro.begin(), gyro.end(), t, [](const GyroSample& s, double x) { return s.t < x; });
  };
  const auto mean_over = [](auto b, auto e) {
    Eigen::Vector3d w = Eigen::Vector3d::Zero();
    for (auto i = b; i != e; ++i) w += i->w;
    return b == e ? w : Eigen::Vector3d(w / static_cast<double>(e - b));
  };
  const auto b = at(t0), mid = at(0.5 * (t0 + t1)), e = at(t1);
  PairMotion p;
  p.mean = mean_over(b, e);
  if (b != mid && mid != e) p.change = mean_over(mid, e) - mean_over(b, mid);
  return p;
}

}  // namespace

std::vector<bool> choose_frame_pairs(const std::vector<double>& frame_t, const std::vector<bool>& usable,
                                     const std::vector<GyroSample>& gyro, double motion_offset_s, size_t count) {
  std::vector<bool> chosen(frame_t.size(), false);
  std::vector<size_t> pairs;  // k of each pair (k-1, k) of usable frames
  for (size_t k = 1; k < frame_t.size(); ++k)
    if (usable[k - 1] && usable[k]) pairs.push_back(k);
  if (count == 0 || pairs.size() <= count) {
    for (size_t k : pairs) chosen[k] = true;
    return chosen;
  }
  // Each pair's span: from the first frame's stamp to one frame period past the second's (its
  // readout), on the motion clock.
  std::vector<double> rate2(pairs.size()), change2(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) {
    const double t0 = frame_t[pairs[i] - 1] + motion_offset_s, t1 = frame_t[pairs[i]] + motion_offset_s;
    const PairMotion p = pair_motion(gyro, t0, t1 + (t1 - t0));
    rate2[i] = p.mean.squaredNorm(), change2[i] = p.change.squaredNorm();
  }
  const double mean_rate2 = std::accumulate(rate2.begin(), rate2.end(), 0.0) / static_cast<double>(pairs.size());
  const double mean_change2 = std::accumulate(change2.begin(), change2.end(), 0.0) / static_cast<double>(pairs.size());
  std::vector<double> information(pairs.size(), 0.0);
  for (size_t i = 0; i < pairs.size(); ++i)
    information[i] = (mean_rate2 > 0 ? rate2[i] / mean_rate2 : 0.0) + (mean_change2 > 0 ? change2[i] / mean_change2 : 0.0);
  for (size_t i : systematic_choice(mixed(information), count)) chosen[pairs[i]] = true;
  return chosen;
}

std::vector<size_t> systematic_choice(const std::vector<double>& w, size_t count) {
  std::vector<size_t> out;
  if (count >= w.size()) {
    out.resize(w.size());
    std::iota(out.begin(), out.end(), size_t{0});
    return out;
  }
  if (count == 0) return out;
  // Inclusion probabilities min(1, c w_k) summing to count: raise c until the capped items and
  // the scaled rest make up count (a few rounds: each caps at least one more item or ends).
  std::vector<bool> capped(w.size(), false);
  double c = 0;
  for (bool again = true; again;) {
    again = false;
    double rest = 0;
    size_t n_capped = 0;
    for (size_t k = 0; k < w.size(); ++k) {
      if (capped[k]) ++n_capped;
      else rest += std::max(w[k], 0.0);
    }
    if (rest <= 0) break;
    c = static_cast<double>(count - n_capped) / rest;
    for (size_t k = 0; k < w.size(); ++k)
      if (!capped[k] && c * std::max(w[k], 0.0) >= 1) capped[k] = true, again = true;
  }
  // One start at the middle of the first unit, then every unit: item k is taken when the
  // running sum of probabilities passes a start (at most once: its probability is at most 1).
  double acc = 0, next = 0.5;
  for (size_t k = 0; k < w.size() && out.size() < count; ++k) {
    acc += capped[k] ? 1.0 : c * std::max(w[k], 0.0);
    if (acc > next) {
      out.push_back(k);
      while (next < acc) next += 1;
    }
  }
  return out;
}

std::vector<double> observation_leverage(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& at,
                                         const ParamMask& mask) {
  const std::vector<Param> free = params_in(mask);
  std::vector<double> h(idx.size(), 0.0);
  if (free.empty() || idx.empty()) return h;
  Eigen::MatrixXd J = residual_jacobian(m, at, free, idx);
  // Columns to unit length: leverage does not depend on the parameters' units, the threshold
  // below on the information's conditioning does.
  for (Eigen::Index j = 0; j < J.cols(); ++j)
    if (const double n = J.col(j).norm(); n > 0) J.col(j) /= n;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(J.transpose() * J);
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  const double floor = 1e-10 * std::max(lambda.maxCoeff(), 0.0);
  // (J^T J)^+ = V diag(1/lambda) V^T over the directions the data see; h_i = |J_i V diag(lambda^-1/2)|^2.
  Eigen::MatrixXd W = eig.eigenvectors();
  for (Eigen::Index j = 0; j < W.cols(); ++j) W.col(j) *= lambda[j] > floor ? 1 / std::sqrt(lambda[j]) : 0.0;
  const Eigen::MatrixXd G = J * W;
  for (size_t i = 0; i < idx.size(); ++i) h[i] = G.middleRows(2 * static_cast<Eigen::Index>(i), 2).squaredNorm();
  return h;
}

std::vector<int> choose_observations(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& at,
                                     const ParamMask& mask, const ObservationChoice& choice) {
  if (choice.budget == 0 || idx.size() <= choice.budget) return idx;
  const std::vector<std::vector<int>> frames = by_frame(m, idx);
  // Enough per frame for its own translation and its cluster; as many frames as that allows.
  const size_t per = std::max(choice.per_frame_min, choice.budget / frames.size());
  const size_t n_frames = std::max<size_t>(1, choice.budget / per);
  std::vector<int> out;
  if (n_frames >= frames.size()) {  // every frame: nothing to choose between them
    for (const auto& f : frames)
      for (int i : evenly(f, per)) out.push_back(i);
    return out;
  }
  // Runs of consecutive frames by information: a pool of leverage_pool times as many runs as are
  // kept, evenly spread, each frame's information (the sum of its observations' leverage)
  // estimated from 2 x per of its observations, so that ten minutes cost what one does; a run's
  // is its frames' sum.
  const size_t run = std::clamp<size_t>(choice.run, 1, n_frames);  // a run longer than the budget's frames would pass it
  const std::vector<std::vector<size_t>> runs = in_runs(frames.size(), run);
  const size_t n_runs = std::max<size_t>(1, n_frames / run);
  const std::vector<std::vector<size_t>> pool = evenly(runs, std::max<size_t>(1, choice.leverage_pool) * n_runs);
  std::vector<int> sampled;
  std::vector<size_t> begin;
  for (const auto& r : pool)
    for (size_t f : r) {
      begin.push_back(sampled.size());
      for (int i : evenly(frames[f], 2 * per)) sampled.push_back(i);
    }
  begin.push_back(sampled.size());
  const std::vector<double> h = observation_leverage(m, sampled, at, mask);
  std::vector<double> run_info(pool.size(), 0.0);
  for (size_t r = 0, k = 0; r < pool.size(); ++r)
    for (size_t f : pool[r]) {
      double info = 0;
      for (size_t j = begin[k]; j < begin[k + 1]; ++j) info += h[j];
      run_info[r] += info * static_cast<double>(frames[f].size()) /
                     static_cast<double>(std::max<size_t>(1, begin[k + 1] - begin[k]));
      ++k;
    }
  for (size_t r : systematic_choice(mixed(run_info), n_runs))
    for (size_t f : pool[r])
      for (int i : evenly(frames[f], per)) out.push_back(i);
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<int> evenly_in_runs(const DiagnosisModel& m, const std::vector<int>& idx, size_t runs, size_t run,
                                size_t per_frame) {
  const std::vector<std::vector<int>> frames = by_frame(m, idx);
  std::vector<int> out;
  for (const auto& r : evenly(in_runs(frames.size(), std::max<size_t>(1, run)), runs))
    for (size_t f : r)
      for (int i : evenly(frames[f], per_frame)) out.push_back(i);
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace rsd::dsp
