// Shared benchmark plumbing: per-query timing, medians, the machine description, and the JSON
// figure files (build/bench/<name>.json: a list of {name, unit, ours, baseline, ratio}).
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace bvh_collision::bench {

inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

inline double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / v.size();
}

inline double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(p * v.size()));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

// Microseconds taken by f(), measured with the steady clock.
template <class F>
double time_us(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  const auto end = std::chrono::steady_clock::now();
  return std::chrono::duration<double, std::micro>(end - start).count();
}

inline std::string machine_description() {
  std::ifstream cpu("/proc/cpuinfo");
  std::string line, model = "unknown CPU";
  while (std::getline(cpu, line)) {
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  }
  std::ostringstream out;
  out << model << ", " << std::thread::hardware_concurrency() << " cores, g++ " << __VERSION__;
  return out.str();
}

struct Figure {
  std::string name, unit;
  double ours = 0.0;
  std::optional<double> baseline;
};

// Collects the figures a benchmark prints and writes them as JSON for run-to-run tracking.
class FigureFile {
 public:
  explicit FigureFile(std::string name) : name_(std::move(name)) {}
  void add(const std::string& name, const std::string& unit, double ours, std::optional<double> baseline = {}) {
    figures_.push_back({name, unit, ours, baseline});
  }
  // ratio = baseline / ours (for times: how many times faster we are).
  void write(const std::string& dir) const {
    std::filesystem::create_directories(dir);
    std::ofstream out(dir + "/" + name_ + ".json");
    out << "[\n" << std::setprecision(6);
    for (std::size_t i = 0; i < figures_.size(); ++i) {
      const Figure& f = figures_[i];
      out << "  {\"name\": \"" << f.name << "\", \"unit\": \"" << f.unit << "\", \"ours\": " << number(f.ours);
      if (f.baseline) out << ", \"baseline\": " << number(*f.baseline) << ", \"ratio\": " << number(*f.baseline / f.ours);
      out << "}" << (i + 1 < figures_.size() ? "," : "") << "\n";
    }
    out << "]\n";
  }

 private:
  // JSON has no infinity or NaN (a ratio against 0 voxels, say): those are written as null.
  static std::string number(double x) {
    if (!std::isfinite(x)) return "null";
    std::ostringstream s;
    s << std::setprecision(6) << x;
    return s.str();
  }
  std::string name_;
  std::vector<Figure> figures_;
};

inline std::string output_dir(int argc, char** argv) {
  return argc > 1 ? std::string(argv[1]) : std::string("build/bench");
}

}  // namespace bvh_collision::bench
