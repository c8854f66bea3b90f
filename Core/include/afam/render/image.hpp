// SPDX-License-Identifier: BSD-3-Clause
// Image buffers of the renderers: float premultiplied RGBA (what castRay returns, row 0 = top)
// and 8-bit RGB (what PNG files and the metrics use).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace afam {

struct ImageRGBA {
  int width = 0, height = 0;
  std::vector<float> rgba;  ///< premultiplied, 4 floats per pixel, row 0 = top
  void resize(int w, int h) {
    width = w;
    height = h;
    rgba.assign(std::size_t(w) * std::size_t(h) * 4, 0.f);
  }
};

struct ImageRGB8 {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  ///< 3 bytes per pixel, row 0 = top
};

/// Composites premultiplied RGBA over a background colour and rounds to 8 bits.
ImageRGB8 toRGB8(const ImageRGBA& image, const float background[3]);
inline ImageRGB8 toRGB8(const ImageRGBA& image) {
  const float black[3] = {0.f, 0.f, 0.f};
  return toRGB8(image, black);
}

}  // namespace afam
