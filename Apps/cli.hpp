// SPDX-License-Identifier: BSD-3-Clause
// Small helpers shared by the `afam` sub-commands: argument parsing and a progress bar.
#pragma once

#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"

namespace afam::cli {

/// Parses `--key value`, `--key=value` and `--flag` options and positional arguments.
/// Unknown options are an error (InvalidArgument naming the option).
class Args {
 public:
  Args(int argc, char** argv, const std::set<std::string>& valueOptions,
       const std::set<std::string>& flags) {
    for (int i = 1; i < argc; ++i) {
      std::string a = argv[i];
      if (a == "-h" || a == "--help") {
        help_ = true;
        continue;
      }
      if (a.size() > 2 && a.compare(0, 2, "--") == 0) {
        std::string key = a.substr(2), value;
        const size_t eq = key.find('=');
        const bool hasEq = eq != std::string::npos;
        if (hasEq) {
          value = key.substr(eq + 1);
          key = key.substr(0, eq);
        }
        if (flags.count(key)) {
          if (hasEq) throw InvalidArgument("option --" + key + " takes no value");
          values_[key] = "1";
        } else if (valueOptions.count(key)) {
          if (!hasEq) {
            if (i + 1 >= argc) throw InvalidArgument("option --" + key + " needs a value");
            value = argv[++i];
          }
          values_[key] = value;
        } else {
          throw InvalidArgument("unknown option --" + key + " (see --help)");
        }
      } else {
        positional_.push_back(a);
      }
    }
  }
  bool help() const { return help_; }
  bool has(const std::string& k) const { return values_.count(k) != 0; }
  std::string str(const std::string& k, const std::string& def = "") const {
    auto it = values_.find(k);
    return it == values_.end() ? def : it->second;
  }
  long long integer(const std::string& k, long long def) const {
    if (!has(k)) return def;
    return parseInt(str(k), "--" + k);
  }
  double real(const std::string& k, double def) const {
    if (!has(k)) return def;
    return parseReal(str(k), "--" + k);
  }
  const std::vector<std::string>& positional() const { return positional_; }
  void expectPositional(size_t n, const std::string& usage) const {
    if (positional_.size() != n)
      throw InvalidArgument("expected " + std::to_string(n) + " argument(s), got " +
                            std::to_string(positional_.size()) + "; usage: " + usage);
  }

  static long long parseInt(const std::string& s, const std::string& what) {
    try {
      size_t pos = 0;
      const long long v = std::stoll(s, &pos);
      if (pos != s.size()) throw 0;
      return v;
    } catch (...) {
      throw InvalidArgument(what + ": '" + s + "' is not an integer");
    }
  }
  static double parseReal(const std::string& s, const std::string& what) {
    try {
      size_t pos = 0;
      const double v = std::stod(s, &pos);
      if (pos != s.size()) throw 0;
      return v;
    } catch (...) {
      throw InvalidArgument(what + ": '" + s + "' is not a number");
    }
  }
  /// "X,Y,Z" (or "XxYxZ") -> dims.
  static std::array<int64_t, 3> parseDims(const std::string& s) {
    std::array<int64_t, 3> d{};
    std::string t = s;
    for (char& c : t)
      if (c == 'x') c = ',';
    size_t start = 0;
    for (int a = 0; a < 3; ++a) {
      const size_t comma = t.find(',', start);
      if ((a < 2) != (comma != std::string::npos))
        throw InvalidArgument("--dims: '" + s + "' is not X,Y,Z");
      d[a] = parseInt(t.substr(start, a < 2 ? comma - start : std::string::npos), "--dims");
      if (d[a] < 1)
        throw InvalidArgument(std::string("--dims: axis ") + "xyz"[a] + " has " +
                              std::to_string(d[a]) + " samples; every axis needs at least 1");
      start = comma + 1;
    }
    return d;
  }

 private:
  bool help_ = false;
  std::map<std::string, std::string> values_;
  std::vector<std::string> positional_;
};

/// A one-line progress bar on stderr, drawn only when stderr is a terminal (or when forced).
class ProgressBar {
 public:
  ProgressBar(std::string label, bool force = false)
      : label_(std::move(label)),
        enabled_(force || ::isatty(2)),
        t0_(std::chrono::steady_clock::now()) {}
  ~ProgressBar() { finish(); }
  bool operator()(double f) {
    if (!enabled_) return true;
    const auto now = std::chrono::steady_clock::now();
    if (f < 1.0 && now - last_ < std::chrono::milliseconds(200)) return true;
    last_ = now;
    const int width = 40, filled = int(f * width + 0.5);
    const double s = std::chrono::duration<double>(now - t0_).count();
    std::fprintf(stderr, "\r%s [%s%s] %5.1f%% %6.1fs", label_.c_str(),
                 std::string(size_t(filled), '#').c_str(),
                 std::string(size_t(width - filled), ' ').c_str(), 100.0 * f, s);
    std::fflush(stderr);
    drawn_ = true;
    return true;
  }
  void finish() {
    if (drawn_) std::fprintf(stderr, "\n");
    drawn_ = false;
  }

 private:
  std::string label_;
  bool enabled_, drawn_ = false;
  std::chrono::steady_clock::time_point t0_, last_{};
};

}  // namespace afam::cli
