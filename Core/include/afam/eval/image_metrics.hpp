// SPDX-License-Identifier: BSD-3-Clause
// Image error metrics against a reference: MSE, PSNR and SSIM, on 8-bit RGB (peak 255) or float
// RGB in [0, 1] (peak 1). SSIM is the standard Wang et al. (2004) index with an 11 x 11 Gaussian
// window (sigma 1.5), K1 = 0.01, K2 = 0.03, computed per channel over the valid window positions
// and averaged over channels. Sizes must match (InvalidArgument otherwise).
#pragma once

#include <vector>

#include "afam/render/image.hpp"

namespace afam {

struct ImageErrors {
  double mse = 0, psnr = 0, ssim = 1;
};

/// Planar float image: 3 channels, values on a scale with the given peak.
struct MetricImage {
  int width = 0, height = 0;
  std::vector<double> rgb;  ///< interleaved, 3 per pixel
  double peak = 1.0;
};

MetricImage toMetricImage(const ImageRGB8& image);
/// Composites premultiplied RGBA over black, clamps to [0, 1].
MetricImage toMetricImage(const ImageRGBA& image);

double mse(const MetricImage& a, const MetricImage& b);
/// 10 log10(peak^2 / mse); +infinity for identical images (reported as 99 dB by compare()).
double psnr(const MetricImage& a, const MetricImage& b);
double ssim(const MetricImage& a, const MetricImage& b);
ImageErrors compare(const MetricImage& test, const MetricImage& reference);
ImageErrors compare(const ImageRGB8& test, const ImageRGB8& reference);

}  // namespace afam
