// Shared benchmark plumbing: per-query timing, medians and spreads, the machine description, and
// the report's tables (build/bench/tables/<id>.json, rendered by scripts/bench_report.py).
#pragma once

#include <nlohmann/json.hpp>

#include "bvh_collision/model/proxy_batch.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <variant>
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

// The CPU, its cores, the compiler and the SIMD path each run-time-dispatched kernel takes here
// (docs/performance.md: a kernel slower on one CPU family is a finding, not a surprise).
inline std::string machine_description() {
  std::ifstream cpu("/proc/cpuinfo");
  std::string line, model = "unknown CPU", flags;
  while (std::getline(cpu, line)) {
    if (line.rfind("model name", 0) == 0 && model == "unknown CPU") model = line.substr(line.find(':') + 2);
    if (line.rfind("flags", 0) == 0 && flags.empty()) flags = " " + line.substr(line.find(':') + 1) + " ";
    if (model != "unknown CPU" && !flags.empty()) break;
  }
  auto has = [&](const char* flag) { return flags.find(std::string(" ") + flag + " ") != std::string::npos; };
  std::string simd = has("avx512f") ? "AVX-512F" : has("avx2") ? "AVX2" : has("sse4_2") ? "SSE4.2" : "SSE2";
  std::ostringstream out;
  out << model << " (widest SIMD: " << simd << "), " << std::thread::hardware_concurrency() << " cores, g++ " << __VERSION__
      << "; proxy batch kernel: " << (avx2_available() ? "AVX2, 4 lanes" : "SSE2, 2 lanes")
      << "; scans' ray walk: " << (avx2_available() ? "AVX2" : "SSE2") << " (both chosen at run time)";
  return out.str();
}

inline std::string output_dir(int argc, char** argv) {
  return argc > 1 ? std::string(argv[1]) : std::string("build/bench");
}

// `--quick` anywhere after the output folder: small inputs, for the report's test in make test.
inline bool quick_mode(int argc, char** argv) {
  for (int i = 2; i < argc; ++i) {
    if (std::string(argv[i]) == "--quick") return true;
  }
  return false;
}

// A number in a note: three significant digits.
inline std::string format(double x) {
  std::ostringstream s;
  s << std::setprecision(3) << x;
  return s.str();
}

// The median of repeated runs of one measurement, with the spread (smallest and largest run).
struct Spread {
  double median = 0.0, low = 0.0, high = 0.0;
};

inline Spread spread(const std::vector<double>& runs) {
  if (runs.empty()) return {};
  return {bench::median(runs), *std::min_element(runs.begin(), runs.end()), *std::max_element(runs.begin(), runs.end())};
}

// Microseconds per item of `count` items: f() runs over all of them once.
template <class F>
double us_per_item(std::size_t count, F&& f) {
  return time_us(std::forward<F>(f)) / static_cast<double>(std::max<std::size_t>(count, 1));
}

// Boolean answers against exact distances (<= 0: colliding): false positives, false negatives
// and the farthest false positive, as the speed-against-error tables report them.
struct AnswerErrors {
  std::size_t false_positives = 0, false_negatives = 0;
  double farthest_false_positive = 0.0;
};
inline AnswerErrors answer_errors(const std::vector<char>& hits, const std::vector<double>& distance) {
  AnswerErrors e;
  for (std::size_t i = 0; i < hits.size(); ++i) {
    const bool hit = hits[i] != 0, colliding = distance[i] <= 0.0;
    e.false_negatives += colliding && !hit;
    if (hit && !colliding) ++e.false_positives, e.farthest_false_positive = std::max(e.farthest_false_positive, distance[i]);
  }
  return e;
}

// One table of the report: columns, rows of numbers or text, notes. Written as
// <dir>/tables/<id>.json ({id, title, machine, columns, rows, notes}; a number that is not
// finite is null) and printed as markdown, so that a benchmark's console output reads alone.
class Table {
 public:
  using Cell = std::variant<double, std::string>;
  Table(std::string id, std::string title, std::vector<std::string> columns)
      : id_(std::move(id)), title_(std::move(title)), columns_(std::move(columns)) {}

  Table& row(std::vector<Cell> cells) {
    if (cells.size() != columns_.size()) throw std::logic_error("table " + id_ + ": row of the wrong width");
    rows_.push_back(std::move(cells));
    return *this;
  }
  Table& note(std::string text) {
    notes_.push_back(std::move(text));
    return *this;
  }
  // A median and its spread as three cells (median, low, high).
  static std::vector<Cell> cells(const Spread& s) { return {s.median, s.low, s.high}; }

  void write(const std::string& dir) const {
    std::filesystem::create_directories(dir + "/tables");
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& r : rows_) {
      nlohmann::json row = nlohmann::json::array();
      for (const Cell& c : r) {
        if (const double* x = std::get_if<double>(&c)) {
          row.push_back(std::isfinite(*x) ? nlohmann::json(*x) : nlohmann::json(nullptr));
        } else {
          row.push_back(std::get<std::string>(c));
        }
      }
      rows.push_back(row);
    }
    const nlohmann::json out = {{"id", id_}, {"title", title_}, {"machine", machine_description()},
                                {"columns", columns_}, {"rows", rows}, {"notes", notes_}};
    std::ofstream(dir + "/tables/" + id_ + ".json") << out.dump(1) << "\n";
    print();
  }

  void print() const {
    std::cout << "\n### " << title_ << "\n|";
    for (const auto& c : columns_) std::cout << " " << c << " |";
    std::cout << "\n|";
    for (std::size_t i = 0; i < columns_.size(); ++i) std::cout << "---|";
    std::cout << "\n";
    for (const auto& r : rows_) {
      std::cout << "|";
      for (const Cell& c : r) {
        if (const double* x = std::get_if<double>(&c)) {
          std::cout << " " << std::setprecision(4) << *x << " |";
        } else {
          std::cout << " " << std::get<std::string>(c) << " |";
        }
      }
      std::cout << "\n";
    }
    for (const auto& n : notes_) std::cout << "\n" << n << "\n";
    std::cout.flush();
  }

 private:
  std::string id_, title_;
  std::vector<std::string> columns_;
  std::vector<std::vector<Cell>> rows_;
  std::vector<std::string> notes_;
};

}  // namespace bvh_collision::bench
