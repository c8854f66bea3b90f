// SPDX-License-Identifier: BSD-3-Clause
// GPU benchmarks (a timing program: CUDA events, medians over repetitions).
//   bench_gpu [--volume N] [--reps R] [--table FILE]   full benchmark, table printed last
//   bench_gpu --sanitize                               one small frame (for compute-sanitizer)
// Measures: the anchor views 0/100/200/300 of user_1.dat (512 x 512, sample distance 0.005,
// degree 2, distance bands) with full-ray-caster and bare value+gradient throughput on the same
// rays, GPU vs CPU on the same frame (and the image difference), and 8 vs 512 visible blocks.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "afam/cuda/render/gpu_renderer.hpp"
#include "afam/render/cpu_raycaster.hpp"
#include "gpu_scene.hpp"

using namespace afam;
using namespace afam::gputest;

namespace {

double seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

int sanitizeOneFrame() {
  std::string why;
  if (!gpuAvailable(&why)) {
    std::printf("no usable GPU: %s\n", why.c_str());
    return 0;
  }
  const EncodedVolume e = encodeVolume(marschnerLobbVolume(33), 2, 4, 2, 0.75);
  const Camera camera = Camera::fromPose({1.8, 50.0, 20.0}, 96, 80);
  GpuRenderer gpu(size_t(16) << 20);
  gpu.setPoisonOutput(true);
  std::vector<float> image(size_t(96) * 80 * 4);
  for (int shaded = 0; shaded < 2; ++shaded) {
    Frame frame;
    FrameOptions options;
    options.shaded = shaded != 0;
    buildFrame(e, distanceBands(e.partition, camera), camera, options, frame);
    gpu.render(frame.view, frame.keys.data(), image.data());
    gpu.setDegreeSpecialisation(false);
    gpu.render(frame.view, frame.keys.data(), image.data());
    gpu.setDegreeSpecialisation(true);
    (void)gpu.timeKernel(frame.view, frame.keys.data(), GpuKernelKind::BareValueGradient, 1);
    (void)gpu.timeKernel(frame.view, frame.keys.data(), GpuKernelKind::Full, 1);
  }
  std::printf("sanitize frame rendered\n");
  return 0;
}

struct Row {
  std::string name;
  double ms = 0, gsps = 0, bareMs = 0, bareGsps = 0, cpuMs = 0, maxDiff = 0;
  long long blocks = 0, differing = 0;
  uint64_t samples = 0;
};

}  // namespace

int main(int argc, char** argv) {
  int volumeN = 257, reps = 20;
  std::string tablePath;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--sanitize") return sanitizeOneFrame();
    if (a == "--volume" && i + 1 < argc)
      volumeN = std::atoi(argv[++i]);
    else if (a == "--reps" && i + 1 < argc)
      reps = std::atoi(argv[++i]);
    else if (a == "--table" && i + 1 < argc)
      tablePath = argv[++i];
  }
  std::string why;
  if (!gpuAvailable(&why)) {
    std::printf("bench_gpu: no usable GPU (%s); nothing measured\n", why.c_str());
    return 0;
  }
  try {
    std::ostringstream table;
    const std::string device = gpuDescription(0);
    std::printf("device: %s\n", device.c_str());
    double t0 = seconds();
    const Volume ml = marschnerLobbVolume(volumeN);
    const EncodedVolume e = encodeVolume(ml, 4, 16, 2, 0.75);
    std::printf(
        "Marschner-Lobb %d^3, 4 levels, 16 finest blocks/axis, p=2, NCP=0.75n: encoded "
        "in %.1f s\n",
        volumeN, seconds() - t0);
    GpuRenderer gpu(size_t(4) << 30);
    std::vector<Row> rows;

    // --- Anchor views of user_1.dat.
    std::string trajectorySource;
    const std::vector<Pose> poses = explorationPoses("user_1.dat", &trajectorySource);
    std::printf("points of view: %s\n", trajectorySource.c_str());
    for (int view : {0, 100, 200, 300}) {
      const Pose pose = size_t(view) < poses.size() ? poses[size_t(view)]
                                                    : Pose{1.5, 40.0 + view * 0.1, view * 0.9};
      const Camera camera = Camera::fromPose(pose, 512, 512);
      Frame frame;
      buildFrame(e, distanceBands(e.partition, camera), camera, FrameOptions{}, frame);
      std::vector<float> image(size_t(512) * 512 * 4);
      GpuFrameTimes cold;
      gpu.render(frame.view, frame.keys.data(), image.data(), &cold);
      const GpuKernelTiming full =
          gpu.timeKernel(frame.view, frame.keys.data(), GpuKernelKind::Full, reps);
      const std::string fullInfo = gpu.lastKernelInfo();
      const GpuKernelTiming bare =
          gpu.timeKernel(frame.view, frame.keys.data(), GpuKernelKind::BareValueGradient, reps);
      const std::string bareInfo = gpu.lastKernelInfo();
      GpuFrameTimes warm;
      gpu.render(frame.view, frame.keys.data(), image.data(), &warm);
      ImageRGBA cpu;
      const double c0 = seconds();
      renderCpu(frame.view, cpu, 0);
      const double cpuMs = (seconds() - c0) * 1e3;
      const ImageDiff d = compareImages(cpu.rgba, image);
      Row r;
      r.name = "user_1 view " + std::to_string(view);
      r.ms = full.median();
      r.samples = full.samples;
      r.gsps = double(full.samples) / (r.ms * 1e-3) / 1e9;
      r.bareMs = bare.median();
      r.bareGsps = double(bare.samples) / (r.bareMs * 1e-3) / 1e9;
      r.cpuMs = cpuMs;
      r.maxDiff = d.maxAbs8;
      r.differing = d.differing;
      r.blocks = frame.view.slotCount;
      rows.push_back(r);
      std::printf(
          "%s: pose (%.3f, %.2f, %.2f), %d blocks; kernel median %.3f ms (%llu samples, "
          "%.1f G/s) [%s]; bare %.3f ms (%llu samples, %.1f G/s) [%s]; render cold %.2f "
          "ms (upload %.2f ms, %llu models, %.1f MB), warm %.2f ms; CPU %.1f ms; "
          "max diff %d/255, %lld px differ\n",
          r.name.c_str(), pose.distance, pose.thetaDeg, pose.phiDeg, frame.view.slotCount, r.ms,
          (unsigned long long)full.samples, r.gsps, fullInfo.c_str(), r.bareMs,
          (unsigned long long)bare.samples, r.bareGsps, bareInfo.c_str(), cold.totalMs,
          cold.uploadMs, (unsigned long long)cold.modelsUploaded, double(cold.bytesUploaded) / 1e6,
          warm.totalMs, cpuMs, d.maxAbs8, (long long)d.differing);
    }

    // --- Floating-point contract and occupancy variants on view 0 (the default is exact).
    std::ostringstream variants;
    {
      const Pose pose = !poses.empty() ? poses[0] : Pose{1.5, 40.0, 0.0};
      const Camera camera = Camera::fromPose(pose, 512, 512);
      Frame frame;
      buildFrame(e, distanceBands(e.partition, camera), camera, FrameOptions{}, frame);
      ImageRGBA cpu;
      renderCpu(frame.view, cpu, 0);
      std::vector<float> image(size_t(512) * 512 * 4);
      variants << "| variant (view 0, shaded, p=2) | kernel ms | G samples/s | bare G samples/s | "
                  "max diff /255 | px differ | kernel |\n|---|---|---|---|---|---|---|\n";
      const std::pair<GpuFloatMode, const char*> modes[] = {
          {GpuFloatMode::Exact, "exact"}, {GpuFloatMode::Fma, "fma"}, {GpuFloatMode::Fast, "fast"}};
      for (const auto& mode : modes) {
        for (int minBlocks : {0, 8}) {
          gpu.setFloatMode(mode.first);
          gpu.setMinBlocksPerSm(minBlocks);
          gpu.render(frame.view, frame.keys.data(), image.data());
          const ImageDiff d = compareImages(cpu.rgba, image);
          const GpuKernelTiming full =
              gpu.timeKernel(frame.view, frame.keys.data(), GpuKernelKind::Full, reps);
          const std::string info = gpu.lastKernelInfo();
          const GpuKernelTiming bare =
              gpu.timeKernel(frame.view, frame.keys.data(), GpuKernelKind::BareValueGradient, reps);
          char line[512];
          std::snprintf(line, sizeof(line), "| %s%s | %.3f | %.1f | %.1f | %d | %lld | %s |\n",
                        mode.second, minBlocks ? " + 64 registers" : "", full.median(),
                        double(full.samples) / (full.median() * 1e-3) / 1e9,
                        double(bare.samples) / (bare.median() * 1e-3) / 1e9, d.maxAbs8,
                        (long long)d.differing, info.c_str());
          variants << line;
          std::printf("%s", line);
        }
      }
      gpu.setFloatMode(GpuFloatMode::Exact);
      gpu.setMinBlocksPerSm(0);
    }

    // --- DS baseline on view 0: raw blocks, castRay's software trilinear vs 3D textures.
    std::ostringstream ds;
    {
      const EncodedVolume raw = rawBlocks(ml, 4, 16);
      const Pose pose = !poses.empty() ? poses[0] : Pose{1.5, 40.0, 0.0};
      const Camera camera = Camera::fromPose(pose, 512, 512);
      Frame frame;
      buildFrame(raw, distanceBands(raw.partition, camera), camera, FrameOptions{}, frame);
      ImageRGBA cpu;
      renderCpu(frame.view, cpu, 0);
      std::vector<float> image(size_t(512) * 512 * 4);
      ds << "| DS (raw blocks + ghosts, view 0, shaded) | blocks | kernel ms | G samples/s | "
            "max diff /255 | px differ | kernel |\n|---|---|---|---|---|---|---|\n";
      for (bool textures : {false, true}) {
        gpu.setDsTextures(textures);
        gpu.render(frame.view, frame.keys.data(), image.data());
        const ImageDiff d = compareImages(cpu.rgba, image);
        const GpuKernelTiming full =
            gpu.timeKernel(frame.view, frame.keys.data(), GpuKernelKind::Full, reps);
        char line[512];
        std::snprintf(line, sizeof(line), "| %s | %d | %.3f | %.1f | %d | %lld | %s |\n",
                      textures ? "3D textures, hardware trilinear" : "castRay, software trilinear",
                      frame.view.slotCount, full.median(),
                      double(full.samples) / (full.median() * 1e-3) / 1e9, d.maxAbs8,
                      (long long)d.differing, gpu.lastKernelInfo().c_str());
        ds << line;
        std::printf("%s", line);
      }
      gpu.setDsTextures(false);
    }

    // --- 8 vs 512 visible blocks: the same data at full resolution, one level each.
    std::vector<Row> blockRows;
    for (int blocks : {2, 8}) {
      const EncodedVolume one = encodeVolume(ml, 1, blocks, 2, 1.0);
      const Camera camera = Camera::fromPose({2.6, 55.0, 30.0}, 512, 512);
      for (int shaded = 1; shaded >= 0; --shaded) {
        Frame frame;
        FrameOptions options;
        options.shaded = shaded != 0;
        buildFrame(one, wholeLevel(one.partition, 0), camera, options, frame);
        const GpuKernelTiming full =
            gpu.timeKernel(frame.view, frame.keys.data(), GpuKernelKind::Full, reps);
        Row r;
        r.name =
            std::to_string(frame.view.slotCount) + " blocks, " + (shaded ? "shaded" : "unshaded");
        r.ms = full.median();
        r.samples = full.samples;
        r.gsps = double(full.samples) / (r.ms * 1e-3) / 1e9;
        r.blocks = frame.view.slotCount;
        blockRows.push_back(r);
        std::printf("%s: kernel median %.3f ms, %llu samples, %.1f G/s\n", r.name.c_str(), r.ms,
                    (unsigned long long)r.samples, r.gsps);
      }
    }

    // --- The table.
    table << "GPU: " << device << "\n";
    table << "Marschner-Lobb " << volumeN << "^3, p=2, 512x512, sample distance 0.005, medians of "
          << reps << " launches\n";
    table << "Anchor views, default kernels (exact floating point):\n";
    table << "| frame | blocks | kernel ms | G samples/s | bare G samples/s | full/bare | CPU ms | "
             "GPU speed-up | max diff /255 | px differ |\n";
    table << "|---|---|---|---|---|---|---|---|---|---|\n";
    char line[512];
    for (const Row& r : rows) {
      std::snprintf(line, sizeof(line),
                    "| %s | %lld | %.3f | %.1f | %.1f | %.0f%% | %.1f | %.0fx | %.0f | %lld |\n",
                    r.name.c_str(), r.blocks, r.ms, r.gsps, r.bareGsps, 100.0 * r.gsps / r.bareGsps,
                    r.cpuMs, r.cpuMs / r.ms, r.maxDiff, r.differing);
      table << line;
    }
    table << "\n" << variants.str();
    table << "\n" << ds.str();
    table << "\n| 8 vs 512 visible blocks (same data, full resolution) | blocks | kernel ms | "
             "G samples/s |\n|---|---|---|---|\n";
    for (const Row& r : blockRows) {
      std::snprintf(line, sizeof(line), "| %s | %lld | %.3f | %.1f |\n", r.name.c_str(), r.blocks,
                    r.ms, r.gsps);
      table << line;
    }
    for (int shaded = 0; shaded < 2 && blockRows.size() == 4; ++shaded) {
      const Row& a = blockRows[size_t(shaded)];      // 8 blocks
      const Row& b = blockRows[size_t(shaded) + 2];  // 512 blocks
      std::snprintf(line, sizeof(line), "%s: 512 vs 8 blocks kernel time %+.1f%%\n",
                    shaded == 0 ? "shaded" : "unshaded", 100.0 * (b.ms - a.ms) / a.ms);
      table << line;
    }
    std::printf("\n%s", table.str().c_str());
    if (!tablePath.empty()) std::ofstream(tablePath) << table.str();
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "bench_gpu: %s\n", ex.what());
    return 1;
  }
  return 0;
}
