// SPDX-License-Identifier: BSD-3-Clause
#include "afam/render/image.hpp"

#include <algorithm>
#include <cmath>

namespace afam {

ImageRGB8 toRGB8(const ImageRGBA& im, const float bg[3]) {
  ImageRGB8 out;
  out.width = im.width;
  out.height = im.height;
  const size_t n = size_t(im.width) * size_t(im.height);
  out.rgb.resize(3 * n);
  for (size_t i = 0; i < n; ++i) {
    const float a = im.rgba[4 * i + 3];
    for (int c = 0; c < 3; ++c) {
      const float v = im.rgba[4 * i + c] + (1.f - a) * bg[c];
      out.rgb[3 * i + c] = uint8_t(std::lround(std::clamp(v, 0.f, 1.f) * 255.f));
    }
  }
  return out;
}

}  // namespace afam
