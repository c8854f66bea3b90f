// SPDX-License-Identifier: BSD-3-Clause
#include "afam/ranks/rank_images.hpp"

#include <algorithm>
#include <string>

#include "afam/base/errors.hpp"
#include "afam/render/raycast.hpp"

namespace afam {

namespace {

void checkImages(const std::vector<ImageRGBA>& images, const std::vector<int>& order,
                 int blendMode) {
  if (blendMode != kBlendComposite && blendMode != kBlendMaximum)
    throw InvalidArgument("rank images: blend mode " + std::to_string(blendMode) +
                          " cannot be composited from colours (composite and maximum can)");
  if (images.empty()) throw InvalidArgument("rank images: no images");
  for (const ImageRGBA& im : images)
    if (im.width != images[0].width || im.height != images[0].height ||
        im.rgba.size() != images[0].rgba.size())
      throw InvalidArgument("rank images: images of different sizes");
  std::vector<char> seen(images.size(), 0);
  for (int r : order) {
    if (r < 0 || size_t(r) >= images.size() || seen[size_t(r)])
      throw InvalidArgument("rank images: the order is not a permutation of the " +
                            std::to_string(images.size()) + " ranks");
    seen[size_t(r)] = 1;
  }
  if (order.size() != images.size())
    throw InvalidArgument("rank images: the order lists " + std::to_string(order.size()) +
                          " ranks of " + std::to_string(images.size()));
}

RGBA pixel(const ImageRGBA& im, size_t p) {
  const float* c = &im.rgba[4 * p];
  return RGBA{c[0], c[1], c[2], c[3]};
}

}  // namespace

ImageRGBA compositeRankImages(const std::vector<ImageRGBA>& images, const std::vector<int>& order,
                              int blendMode) {
  checkImages(images, order, blendMode);
  ImageRGBA out;
  out.resize(images[0].width, images[0].height);
  const size_t pixels = out.rgba.size() / 4;
  for (size_t p = 0; p < pixels; ++p) {
    RGBA acc;
    for (int r : order) {
      const RGBA c = pixel(images[size_t(r)], p);
      if (blendMode == kBlendComposite) {
        compositeUnder(acc, c);
      } else {
        acc = RGBA{std::max(acc.r, c.r), std::max(acc.g, c.g), std::max(acc.b, c.b),
                   std::max(acc.a, c.a)};
      }
    }
    float* o = &out.rgba[4 * p];
    o[0] = acc.r;
    o[1] = acc.g;
    o[2] = acc.b;
    o[3] = acc.a;
  }
  return out;
}

}  // namespace afam
