// SPDX-License-Identifier: BSD-3-Clause
// An interpolant's decoding (rounded_points.hpp): the spline of NCP = n on every axis fitted
// through a block's samples, one line at a time, for the CPU reference and the GPU decoder (host
// and device). BlockFitter::fitInto (fit.hpp) computes the same fit with its row kernels, many
// lines a vector; every value here takes the operations it takes there, in the same order and
// rounding (no fused multiply-add on either side), so both give the same control points bit for
// bit (test_interpolation_passes.cpp).
//
// The passes, on a block of n0 x n1 x n2 values (x fastest), in the fitter's order: b = A^T d
// along z (from the float samples into a), y (a into b) and x (b into a); then the banded Cholesky
// solves of the normal equations along x, z and y, in place in a. The control points are then
// float(a), each checked as the fitter checks them (finite) and, for a rounded interpolant,
// rounded to its point step (roundedPoint, rounded_points.hpp).
#pragma once

#include <cstdint>
#include <vector>

#include "afam/base/host_device.hpp"
#include "afam/base/types.hpp"

namespace afam {

/// One axis's interpolation system (NCP = n samples, degree p) as the fitter builds and factors it
/// (interpolationAxis, fit.hpp): sample i weighs on control points first .. first + p; control
/// point j is supported by samples rowFirst[j] .. rowLast[j], their weights at
/// columnWeight[columnOffset[j] ...] in sample order; the normal matrix's Cholesky factor L in a
/// band (L(j, k) at lower[j * (p + 1) + k - j + p], k in [j - p, j]) and 1 / L(j, j).
struct InterpolationAxisView {
  int n = 0, p = 0;
  const int* rowFirst = nullptr;
  const int* rowLast = nullptr;
  const int* columnOffset = nullptr;
  const double* columnWeight = nullptr;
  const double* lower = nullptr;
  const double* invDiag = nullptr;
};

/// What interpolationAxis returns: the arrays an InterpolationAxisView points to.
struct InterpolationAxis {
  int n = 0, p = 0;
  std::vector<int> rowFirst, rowLast, columnOffset;
  std::vector<double> columnWeight, lower, invDiag;
  InterpolationAxisView view() const {
    return {n,
            p,
            rowFirst.data(),
            rowLast.data(),
            columnOffset.data(),
            columnWeight.data(),
            lower.data(),
            invDiag.data()};
  }
};

/// The six passes, in the order they run.
enum class InterpolationPass : int {
  ProjectZ = 0,
  ProjectY = 1,
  ProjectX = 2,
  SolveX = 3,
  SolveZ = 4,
  SolveY = 5
};
constexpr int kInterpolationPasses = 6;

/// The axis a pass works along (0 x, 1 y, 2 z).
AFAM_HD int interpolationPassAxis(InterpolationPass pass) {
  switch (pass) {
    case InterpolationPass::ProjectZ:
    case InterpolationPass::SolveZ:
      return 2;
    case InterpolationPass::ProjectY:
    case InterpolationPass::SolveY:
      return 1;
    default:
      return 0;
  }
}

/// Lines of a pass: the values of the other two axes.
AFAM_HD int64_t interpolationLines(InterpolationPass pass, Int3 n) {
  const int a = interpolationPassAxis(pass);
  return int64_t(n[0]) * n[1] * n[2] / n[a];
}

/// out[j] = sum over i from rowFirst[j] to rowLast[j], in order and from 0, of weight *
/// double(in[i]) (A^T along one line; `in` and `out` step by their strides).
template <typename In>
AFAM_HD void projectLine(const InterpolationAxisView& s, const In* in, int64_t inStride,
                         double* out, int64_t outStride) {
  for (int j = 0; j < s.n; ++j) {
    const int i0 = s.rowFirst[j], i1 = s.rowLast[j];
    const double* w = s.columnWeight + s.columnOffset[j];
    double acc = 0;
    for (int i = i0; i <= i1; ++i) acc += w[i - i0] * double(in[int64_t(i) * inStride]);
    out[int64_t(j) * outStride] = acc;
  }
}

/// x <- (L L^T)^{-1} x along one line: forward, then backward substitution.
AFAM_HD void solveLine(const InterpolationAxisView& s, double* x, int64_t stride) {
  const int m = s.n, p = s.p, w = p + 1;
  for (int j = 0; j < m; ++j) {
    double xj = x[int64_t(j) * stride];
    for (int k = j - p < 0 ? 0 : j - p; k < j; ++k)
      xj -= s.lower[j * w + k - j + p] * x[int64_t(k) * stride];
    x[int64_t(j) * stride] = xj * s.invDiag[j];
  }
  for (int j = m - 1; j >= 0; --j) {
    double xj = x[int64_t(j) * stride];
    const int last = j + p < m - 1 ? j + p : m - 1;
    for (int k = j + 1; k <= last; ++k) xj -= s.lower[k * w + j - k + p] * x[int64_t(k) * stride];
    x[int64_t(j) * stride] = xj * s.invDiag[j];
  }
}

/// Line `line` of `pass` (line < interpolationLines(pass, n)) on an n0 x n1 x n2 block: samples
/// (floats) for ProjectZ, then the double buffers a and b of n0 n1 n2 values each.
/// axes[a]: the system of axis a.
AFAM_HD void interpolationPassLine(InterpolationPass pass, const InterpolationAxisView* axes,
                                   Int3 n, int64_t line, const float* samples, double* a,
                                   double* b) {
  const int axis = interpolationPassAxis(pass);
  const int64_t nx = n[0], plane = int64_t(n[0]) * n[1];
  // The line's first value and the stride along it.
  int64_t first = 0, stride = 1;
  if (axis == 2) {
    first = line;  // (x, y) = line % plane
    stride = plane;
  } else if (axis == 1) {
    first = (line / nx) * plane + line % nx;  // line = x + nx * z
    stride = nx;
  } else {
    first = line * nx;  // line = y + n1 * z
  }
  const InterpolationAxisView& s = axes[axis];
  switch (pass) {
    case InterpolationPass::ProjectZ:
      projectLine(s, samples + first, stride, a + first, stride);
      break;
    case InterpolationPass::ProjectY:
      projectLine(s, a + first, stride, b + first, stride);
      break;
    case InterpolationPass::ProjectX:
      projectLine(s, b + first, stride, a + first, stride);
      break;
    default:
      solveLine(s, a + first, stride);
  }
}

}  // namespace afam
