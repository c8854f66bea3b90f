// SPDX-License-Identifier: BSD-3-Clause
// The CPU ray caster: threads over 16 x 16 image tiles (dynamic scheduling through an atomic tile
// counter), each pixel calling the shared castRay logic of raycast.hpp. Shading on/off selects
// castRay<true> or castRay<false>, so an unshaded frame never computes a gradient.
#pragma once

#include <atomic>
#include <thread>
#include <vector>

#include "afam/render/image.hpp"
#include "afam/render/raycast.hpp"

namespace afam {

/// Number of threads used for `requested` (<= 0: hardware concurrency).
int resolveThreads(int requested);

/// Renders a frame with any sampler (ModelSampler for the resident models; ground_truth.hpp's
/// analytic sampler for the reference). `image` is resized to the camera's size.
template <typename Sampler>
void renderCpuWith(const FrameView& f, const Sampler& sampler, ImageRGBA& image, int threads) {
  const int w = f.camera.width, h = f.camera.height;
  image.resize(w, h);
  constexpr int kTile = 16;
  const int tilesX = (w + kTile - 1) / kTile, tilesY = (h + kTile - 1) / kTile;
  const int tiles = tilesX * tilesY;
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int t = next.fetch_add(1); t < tiles; t = next.fetch_add(1)) {
      const int x0 = (t % tilesX) * kTile, y0 = (t / tilesX) * kTile;
      for (int y = y0; y < y0 + kTile && y < h; ++y)
        for (int x = x0; x < x0 + kTile && x < w; ++x) {
          const RGBA c = f.blendMode != kBlendComposite ? castProjectionRayWith(f, sampler, x, y)
                         : f.shading                    ? castRayWith<true>(f, sampler, x, y)
                                                        : castRayWith<false>(f, sampler, x, y);
          float* o = &image.rgba[(size_t(y) * size_t(w) + size_t(x)) * 4];
          o[0] = c.r;
          o[1] = c.g;
          o[2] = c.b;
          o[3] = c.a;
        }
    }
  };
  const int n = std::max(1, std::min(resolveThreads(threads), tiles));
  std::vector<std::thread> pool;
  for (int i = 1; i < n; ++i) pool.emplace_back(worker);
  worker();
  for (auto& th : pool) th.join();
}

/// Renders the frame's resident models (ModelSampler).
void renderCpu(const FrameView& f, ImageRGBA& image, int threads);

}  // namespace afam
