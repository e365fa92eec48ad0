// rsd-diagnose-suite: the diagnosis benchmark on concealed effects (docs/diagnosis-benchmark.md).
// Simulates every case in code, calibrates each effect to one noise sigma, runs the diagnosis,
// checks the goals, writes the Markdown table and exits 1 if any goal fails.
#include <CLI/CLI.hpp>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <mutex>
#include <sstream>
#include <thread>

#include "tools/common/cli_util.hpp"
#include "tools/report/diagnosis_suite.hpp"

using namespace rsd;
using namespace rsd::tools;

namespace {

constexpr const char* kDescription =
    "rsd-diagnose-suite: simulates recordings in which each named effect moves the observations by\n"
    "about one noise sigma RMS (alone, in pairs, a triple, and none), and recordings with physics\n"
    "outside the effect table (parallax, a saturating gyro, a clock jump), diagnoses them, and checks\n"
    "the goals: the named set exact, parameters within tolerance, held-out RMS within 10% of\n"
    "the noise floor, the remainder significant exactly when physics outside the table is in.\n"
    "Writes a Markdown table; exit status 1 if any goal fails.\n\n"
    "Full table (docs/diagnosis-benchmark.md), from the repository root:\n"
    "  rsd-diagnose-suite --out docs/diagnosis-benchmark.md --example docs/diagnosis-benchmark\n"
    "CI (reduced: 11 of the cases):             rsd-diagnose-suite --reduced";

std::vector<dsp::ObservationKind> parse_kinds(const std::string& s) {
  std::vector<dsp::ObservationKind> out;
  std::stringstream in(s);
  for (std::string k; std::getline(in, k, ',');) {
    if (k == "landmarks") out.push_back(dsp::ObservationKind::Landmarks);
    else if (k == "matches") out.push_back(dsp::ObservationKind::Matches);
    else throw UsageError("--kinds: expected landmarks and/or matches, got '" + k + "'");
  }
  return out;
}

// --cases: comma-separated case keys ("none,rolling_shutter+time_offset,outside:parallax").
std::vector<SuiteCase> select(const std::vector<SuiteCase>& all, const std::string& names) {
  if (names.empty()) return all;
  std::vector<SuiteCase> out;
  std::stringstream in(names);
  for (std::string n; std::getline(in, n, ',');) {
    bool found = false;
    for (const auto& c : all)
      if (c.key() == n) out.push_back(c), found = true;
    if (!found)
      throw UsageError("--cases: no case '" + n + "' in this suite (effects joined by '+', 'outside:PHYSICS', or 'none')");
  }
  return out;
}

std::string command_line(int argc, char** argv) {
  std::string s = "rsd-diagnose-suite";
  for (int i = 1; i < argc; ++i) s += std::string(" ") + argv[i];
  return s;
}

int run(int argc, char** argv) {
  std::string out, kinds = "landmarks,matches", cases;
  bool reduced = false, verbose = false;
  int threads = 2;
  double duration = 0;
  unsigned seed_shift = 0;
  std::string example;
  CLI::App app(kDescription, "rsd-diagnose-suite");
  app.add_flag("--reduced", reduced, "The CI suite: fewer cases (the same rows as the full table)");
  app.add_option("--out", out, "Write the Markdown table here (stdout if not given)");
  app.add_option("--kinds", kinds, "Observation kinds: landmarks,matches")->capture_default_str();
  app.add_option("--cases", cases, "Only these cases, e.g. none,rolling_shutter+time_offset");
  app.add_option("--duration", duration, "Recording length in s (default 20)")->check(positive("s"));
  app.add_option("--example", example,
                 "Write rsd-diagnose's report of one case (landmarks, rolling_shutter + time_offset if run) here, "
                 "and link it from the table");
  app.add_option("--seed-shift", seed_shift, "Added to every case's seed (the table uses 0)");
  app.add_flag("--verbose", verbose, "Print each diagnosis's progress (what it names, refuses and why), prefixed by its case");
  app.add_option("--threads", threads, "Cases run in parallel")->check(int_range(1, 64))->capture_default_str();
  if (const auto rc = parse_command_line(app, argc, argv)) return *rc;
  if (!out.empty()) require_writable(out, "--out");
  if (!(duration > 0)) duration = default_duration_s(reduced);
  std::vector<SuiteCase> todo = select(suite_cases(reduced, parse_kinds(kinds)), cases);
  for (auto& c : todo) c.seed += seed_shift;
  size_t example_index = 0;
  for (size_t k = 0; k < todo.size(); ++k)
    if (todo[k].kind == dsp::ObservationKind::Landmarks && todo[k].name() == "rolling_shutter + time_offset")
      example_index = k;

  std::string load = "unknown";
  if (std::ifstream la("/proc/loadavg"); la) {
    std::string a, b, c;
    if (la >> a >> b >> c) load = a + " " + b + " " + c;
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<CaseResult> results(todo.size());
  std::atomic<size_t> next{0};
  std::atomic<int> done{0};
  std::mutex print;
  size_t limit = 0;  // the worker takes cases up to this index
  auto worker = [&] {
    for (size_t k; (k = next++) < limit;) {
      {
        std::lock_guard<std::mutex> lock(print);
        std::cerr << "rsd-diagnose-suite: start " << dsp::to_string(todo[k].kind) << " / " << todo[k].name() << "\n";
      }
      std::function<void(const std::string&)> progress;
      if (verbose)
        progress = [&, name = todo[k].name()](const std::string& line) {
          std::lock_guard<std::mutex> lock(print);
          std::cerr << "rsd-diagnose-suite: " << name << ": " << line << "\n";
        };
      results[k] = run_case(todo[k], duration, k == example_index ? example : "", progress);
      std::lock_guard<std::mutex> lock(print);
      std::cerr << "rsd-diagnose-suite: [" << ++done << "/" << todo.size() << "] " << case_line(results[k]) << "\n";
    }
  };
  // Speed cases come last and run alone, so that their time is not shared with another case.
  size_t parallel = 0;
  while (parallel < todo.size() && !todo[parallel].speed) ++parallel;
  const size_t total = todo.size();
  auto run_pool = [&](int n) {
    std::vector<std::thread> pool;
    for (int t = 0; t < n; ++t) pool.emplace_back(worker);
    for (auto& t : pool) t.join();
  };
  limit = parallel;
  run_pool(std::min<int>(threads, static_cast<int>(parallel)));
  next = parallel;  // each worker of the first pool drew one index past its limit
  limit = total;
  run_pool(1);

  SuiteSummary s;
  s.command = command_line(argc, argv);
  s.reduced = reduced, s.duration_s = duration, s.threads = threads, s.load = load;
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!example.empty() && !todo.empty()) {
    s.example_case = std::string(dsp::to_string(todo[example_index].kind)) + " / " + todo[example_index].name();
    // Links in the table are relative to the table's own directory.
    namespace fs = std::filesystem;
    const fs::path base = out.empty() ? fs::current_path() : fs::absolute(out).parent_path();
    s.example_dir = fs::relative(fs::absolute(example), base).string();
  }
  const std::string md = suite_markdown(results, s);
  if (out.empty()) {
    std::cout << md;
  } else {
    std::ofstream f(out);
    f << md;
    if (!f) throw std::runtime_error(out + ": cannot write");
  }
  int pass = 0;
  for (const auto& r : results) pass += r.pass();
  std::cerr << "rsd-diagnose-suite: " << pass << " of " << results.size() << " cases pass ("
            << format_number(s.seconds, 3) << " s)\n";
  return pass == static_cast<int>(results.size()) ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  return run_tool("rsd-diagnose-suite", [&] { return run(argc, argv); });
}
