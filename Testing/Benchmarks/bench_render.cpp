// SPDX-License-Identifier: BSD-3-Clause
// Renderer benchmarks. Run by hand; numbers and commands in docs/BENCHMARKS.md.
//
//  * BM_LookupVisibleBlocks/<level>: O(1) model lookup. A FAM (fixed NCP) encoding of ML 129^3
//    with 8 finest blocks per axis and 4 levels is rendered with every block forced to one level:
//    level 1 = 8 visible blocks, level 2 = 64, level 3 = 512. Image size, camera, sample distance
//    and the transfer function (constant low opacity, so no early termination and every sample
//    classified and shaded) are fixed, so every variant evaluates the same number of samples; only
//    the number of visible models changes. A linear scan of the visible list would grow ~64x.
//  * BM_LinearScanReference/<level>: the same frames with the authors' design (scan the visible
//    block list for every sample), as the side-by-side baseline.
//  * BM_TerminationOpacity/<termination>/<tf>: the cost of early ray termination at 1 - 1/255
//    (termination 1; every rank of a sort-last run must stop where one renderer would, within
//    1/255) against 0.95 (termination 0), ray casting only, on the same ML 129^3 file at its LOD
//    by distance, under the renderer's preset (tf 0: thin translucent shells, rays rarely reach
//    either opacity), an opaque ramp (tf 1: most rays stop at a surface) and a soft one (tf 2: a
//    cloud most rays cross deep into).
// The encoding is written once to $TMPDIR (or /tmp).
#include <benchmark/benchmark.h>

#include <unistd.h>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/render/cpu_raycaster.hpp"
#include "afam/render/renderer.hpp"
#include "afam/volume/marschner_lobb.hpp"

using namespace afam;

namespace {

std::shared_ptr<const AfamFile> lookupFile() {
  static std::shared_ptr<const AfamFile> file = [] {
    const char* tmp = std::getenv("TMPDIR");
    const std::string path = std::string(tmp ? tmp : "/tmp") + "/afam_bench_lookup_129_fixed.afam";
    if (::access(path.c_str(), R_OK) != 0) {
      const int n = 129;
      std::vector<float> data(size_t(n) * n * n);
      marschnerLobbSlab(MarschnerLobb{}, {n, n, n}, 0, n, data.data());
      ArraySource src(data.data(), {n, n, n});
      EncoderOptions o;
      o.levels = 4;
      o.blocksPerAxis = 8;
      o.mode = EncodingMode::Fixed;
      o.fixedNcp = 8;
      encodeVolume(src, o, path);
    }
    return AfamFile::open(path);
  }();
  return file;
}

RenderOptions lookupOptions(int level) {
  RenderOptions o;
  o.threads = 1;
  o.sampleDistance = 0.01f;
  o.cache = CacheBudget{};
  o.lod.forceLevel = level;
  o.lod.frustumCulling = o.lod.tfCulling = false;
  o.hasTransferFunction = true;
  o.transferFunction.colors = {{0.0, 0.2, 0.4, 0.9}, {1.0, 0.9, 0.5, 0.1}};
  o.transferFunction.opacities = {{0.0, 0.002}, {1.0, 0.002}};
  return o;
}

Camera lookupCamera() { return Camera::lookAt({3.2, 2.4, 2.0}, {0, 0, 0}, {0, 0, 1}, 40, 96, 96); }

/// The authors' design: scan the visible blocks for the one containing the sample.
struct LinearScanSampler {
  const std::vector<std::array<float, 6>>* boxes;  // voxel lo/hi per slot
  template <bool G>
  bool sample(const FrameView& f, const float* p, float& value, float* gradient) const {
    float x[3];
    toVoxel(f, p, x);
    int32_t slot = -1;
    for (size_t s = 0; s < boxes->size(); ++s) {
      const auto& b = (*boxes)[s];
      if (x[0] >= b[0] && x[0] <= b[3] && x[1] >= b[1] && x[1] <= b[4] && x[2] >= b[2] &&
          x[2] <= b[5]) {
        slot = int32_t(s);
        break;
      }
    }
    if (slot < 0) return false;
    const FrameSlot& s = f.slots[slot];
    float gv[3] = {0, 0, 0};
    value = sampleSplineSlot<G>(s, f.pool + s.offset, x, gv);
    if (G)
      for (int a = 0; a < 3; ++a) gradient[a] = gv[a] * f.voxelPerUnit[a];
    return true;
  }
};

/// Casts the lookup file's frame of `camera` on one thread, again and again.
void castRepeatedly(benchmark::State& state, const RenderOptions& o, const Camera& camera) {
  Renderer r(lookupFile(), o);
  PreparedFrame fr;
  FrameStats st;
  r.prepare(camera, fr, st);
  ImageRGBA img;
  for (auto _ : state) {
    renderCpu(fr.view, img, 1);
    benchmark::DoNotOptimize(img.rgba.data());
  }
  state.counters["visible_blocks"] = double(st.slots);
}

void BM_LookupVisibleBlocks(benchmark::State& state) {
  castRepeatedly(state, lookupOptions(int(state.range(0))), lookupCamera());
}
BENCHMARK(BM_LookupVisibleBlocks)
    ->Arg(1)
    ->Arg(2)
    ->Arg(3)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_LinearScanReference(benchmark::State& state) {
  Renderer r(lookupFile(), lookupOptions(int(state.range(0))));
  PreparedFrame fr;
  FrameStats st;
  r.prepare(lookupCamera(), fr, st);
  std::vector<std::array<float, 6>> boxes;
  const Partition& p = r.file().partition();
  for (int64_t e : fr.entries) {
    const ModelEntry& m = r.file().entries()[size_t(e)];
    const BlockExtent x = p.extent(m.level, m.block);
    boxes.push_back({float(x.lo[0]), float(x.lo[1]), float(x.lo[2]), float(x.hi[0]), float(x.hi[1]),
                     float(x.hi[2])});
  }
  LinearScanSampler s{&boxes};
  ImageRGBA img;
  for (auto _ : state) {
    renderCpuWith(fr.view, s, img, 1);
    benchmark::DoNotOptimize(img.rgba.data());
  }
  state.counters["visible_blocks"] = double(st.slots);
}
BENCHMARK(BM_LinearScanReference)
    ->Arg(1)
    ->Arg(2)
    ->Arg(3)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_TerminationOpacity(benchmark::State& state) {
  RenderOptions o;
  o.threads = 1;
  o.cache = CacheBudget{};
  o.terminationOpacity = state.range(0) ? 1.f - 1.f / 255.f : 0.95f;
  if (state.range(1)) {  // a ramp up to 0.5 (surfaces) or 0.05 (a soft cloud) per 0.01
    const double top = state.range(1) == 1 ? 0.5 : 0.05;
    o.hasTransferFunction = true;
    o.transferFunction.colors = {{0.0, 0.2, 0.4, 0.9}, {1.0, 0.9, 0.5, 0.1}};
    o.transferFunction.opacities = {{0.0, 0.0}, {0.45, 0.0}, {0.7, top}, {1.0, top}};
  }
  castRepeatedly(state, o, Camera::lookAt({2.2, 1.6, 1.3}, {0, 0, 0}, {0, 0, 1}, 40, 128, 128));
}
BENCHMARK(BM_TerminationOpacity)
    ->Args({0, 0})
    ->Args({1, 0})
    ->Args({0, 1})
    ->Args({1, 1})
    ->Args({0, 2})
    ->Args({1, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
