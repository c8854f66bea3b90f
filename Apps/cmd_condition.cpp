// SPDX-License-Identifier: BSD-3-Clause
// `afam condition`: condition numbers of the per-axis fitting systems, for every NCP.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/spline/fit.hpp"
#include "commands.hpp"

namespace {

int parseInt(const std::string& option, const char* text) {
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (!text[0] || *end || v < -1000000000L || v > 1000000000L)
    throw afam::InvalidArgument("afam condition: " + option + " expects an integer, got '" +
                                std::string(text) + "'");
  return int(v);
}

void printHelp() {
  std::printf(
      "usage: afam condition [--n N] [--degree P] [--ncp K]\n"
      "Prints the 2-norm condition numbers of one axis of the fit: the n x NCP collocation\n"
      "matrix A (uniform parameters k/(n-1), knots implied by (NCP, p)) and the normal matrix\n"
      "A^T A that the fitter factors, for every NCP in [p+1, n] (or only --ncp K).\n"
      "  --n N       samples on the axis (default 64)\n"
      "  --degree P  spline degree 1..5 (default: 1, 2 and 3)\n"
      "  --ncp K     a single NCP instead of all\n");
}

}  // namespace

int runCondition(int argc, char** argv) {
  int n = 64, onlyNcp = 0;
  std::vector<int> degrees = {1, 2, 3};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      printHelp();
      return 0;
    }
    std::string key = a, value;
    const size_t eq = a.find('=');
    if (eq != std::string::npos) {
      key = a.substr(0, eq);
      value = a.substr(eq + 1);
    } else if (a == "--n" || a == "--degree" || a == "--ncp") {
      if (i + 1 >= argc) throw afam::InvalidArgument("afam condition: " + a + " needs a value");
      value = argv[++i];
    }
    if (key == "--n") {
      n = parseInt(key, value.c_str());
    } else if (key == "--degree") {
      degrees = {parseInt(key, value.c_str())};
    } else if (key == "--ncp") {
      onlyNcp = parseInt(key, value.c_str());
    } else {
      throw afam::InvalidArgument("afam condition: unknown argument '" + a + "' (see --help)");
    }
  }
  if (n < 2) throw afam::InvalidArgument("afam condition: --n must be at least 2");
  for (int p : degrees)
    if (p < 1 || p > 5) throw afam::InvalidArgument("afam condition: --degree must be in 1..5");

  std::printf("# n = %d samples, uniform parameters k/(n-1), de Boor-averaged implied knots\n", n);
  std::printf("%6s %4s %16s %16s\n", "ncp", "p", "cond(A)", "cond(A^T A)");
  for (int p : degrees) {
    const int pe = afam::effectiveDegree(p, n);
    const int lo = onlyNcp ? onlyNcp : pe + 1, hi = onlyNcp ? onlyNcp : n;
    for (int ncp = lo; ncp <= hi; ++ncp) {
      const afam::AxisConditioning c = afam::axisConditioning(n, ncp, p);
      std::printf("%6d %4d %16.6g %16.6g\n", ncp, pe, c.collocation, c.normal);
    }
  }
  return 0;
}
