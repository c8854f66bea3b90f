// SPDX-License-Identifier: BSD-3-Clause
#include "gpu_scene.hpp"

#include <sys/stat.h>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <thread>

#include "afam/base/errors.hpp"
#include "afam/scene/lod.hpp"
#include "afam/scene/trajectory_gen.hpp"
#include "afam/scene/transfer_function.hpp"
#include "afam/volume/marschner_lobb.hpp"

namespace afam::gputest {

namespace {

void finishRange(Volume& v) {
  v.minValue = std::numeric_limits<float>::max();
  v.maxValue = -std::numeric_limits<float>::max();
  for (float x : v.data) {
    v.minValue = std::min(v.minValue, x);
    v.maxValue = std::max(v.maxValue, x);
  }
}

bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

int threadCount(int requested) {
  if (requested > 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw ? int(hw) : 1;
}

}  // namespace

Volume marschnerLobbVolume(int n) {
  Volume v;
  v.dims = {n, n, n};
  v.data.resize(size_t(n) * n * n);
  marschnerLobbSlab(MarschnerLobb{}, {n, n, n}, 0, n, v.data.data());
  finishRange(v);
  return v;
}

Volume loadRawVolume(const std::string& path, Index3 dims, const std::string& type) {
  const size_t count = size_t(dims[0]) * size_t(dims[1]) * size_t(dims[2]);
  const size_t size = type == "uint8" ? 1 : type == "int16" ? 2 : 4;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open volume " + path);
  std::vector<unsigned char> bytes(count * size);
  in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(bytes.size()));
  if (size_t(in.gcount()) != bytes.size()) throw IoError("short read in volume " + path);
  Volume v;
  v.dims = dims;
  v.data.resize(count);
  for (size_t i = 0; i < count; ++i) {
    if (size == 1) {
      v.data[i] = float(bytes[i]);
    } else if (size == 2) {
      int16_t s;
      std::memcpy(&s, &bytes[2 * i], 2);
      v.data[i] = float(s);
    } else {
      std::memcpy(&v.data[i], &bytes[4 * i], 4);
    }
  }
  finishRange(v);
  return v;
}

EncodedVolume encodeVolume(const Volume& v, int levels, int finestBlocks, int degree,
                           double ncpFraction, int threads) {
  EncodedVolume e;
  e.partition = Partition(v.dims, levels, finestBlocks);
  e.degree = degree;
  e.dims = v.dims;
  e.minValue = v.minValue;
  e.maxValue = v.maxValue;
  e.models.resize(size_t(levels));
  struct Job {
    int level;
    int64_t index;
  };
  std::vector<Job> jobs;
  for (int l = 0; l < levels; ++l) {
    e.models[size_t(l)].resize(size_t(e.partition.blockCount(l)));
    for (int64_t i = 0; i < e.partition.blockCount(l); ++i) jobs.push_back({l, i});
  }
  std::atomic<size_t> next{0};
  std::atomic<bool> failed{false};
  std::string failure;
  auto worker = [&] {
    BlockFitter fitter;
    std::vector<float> samples;
    for (size_t j = next.fetch_add(1); j < jobs.size() && !failed; j = next.fetch_add(1)) {
      try {
        const Job job = jobs[j];
        const Int3 ijk = e.partition.blockFromLinear(job.level, job.index);
        const BlockExtent ext = e.partition.extent(job.level, ijk);
        const Int3 n = ext.samples;
        // Separable linear interpolation at the partition's sample positions.
        std::array<std::vector<int64_t>, 3> i0;
        std::array<std::vector<float>, 3> fr;
        for (int a = 0; a < 3; ++a) {
          for (int k = 0; k < n[a]; ++k) {
            const double x = e.partition.samplePosition(ext, a, k);
            int64_t i = int64_t(std::floor(x));
            i = std::min<int64_t>(std::max<int64_t>(i, 0), std::max<int64_t>(v.dims[a] - 2, 0));
            i0[a].push_back(i);
            fr[a].push_back(v.dims[a] > 1 ? float(x - double(i)) : 0.f);
          }
        }
        samples.resize(size_t(n[0]) * n[1] * n[2]);
        const int64_t sx = v.dims[0] > 1 ? 1 : 0;
        const int64_t sy = v.dims[1] > 1 ? v.dims[0] : 0;
        const int64_t sz = v.dims[2] > 1 ? v.dims[0] * v.dims[1] : 0;
        for (int z = 0; z < n[2]; ++z)
          for (int y = 0; y < n[1]; ++y)
            for (int x = 0; x < n[0]; ++x) {
              const float* c =
                  v.data.data() + (i0[2][z] * v.dims[1] + i0[1][y]) * v.dims[0] + i0[0][x];
              const float fx = fr[0][x], fy = fr[1][y], fz = fr[2][z];
              const float c00 = c[0] + fx * (c[sx] - c[0]);
              const float c10 = c[sy] + fx * (c[sy + sx] - c[sy]);
              const float c01 = c[sz] + fx * (c[sz + sx] - c[sz]);
              const float c11 = c[sz + sy] + fx * (c[sz + sy + sx] - c[sz + sy]);
              const float c0 = c00 + fy * (c10 - c00), c1 = c01 + fy * (c11 - c01);
              samples[(size_t(z) * n[1] + y) * n[0] + x] = c0 + fz * (c1 - c0);
            }
        std::array<int, 3> degrees{}, ncp{};
        for (int a = 0; a < 3; ++a) degrees[a] = effectiveDegree(degree, n[a]);
        const int wanted = int(std::ceil(ncpFraction * double(std::max({n[0], n[1], n[2]}))));
        ncp = clampNcp(wanted, {n[0], n[1], n[2]}, degrees);
        e.models[size_t(job.level)][size_t(job.index)] =
            fitter.fit(samples.data(), {n[0], n[1], n[2]}, ncp, degree, false);
      } catch (const std::exception& ex) {
        if (!failed.exchange(true)) failure = ex.what();
      }
    }
  };
  std::vector<std::thread> pool;
  const int nThreads = threadCount(threads);
  for (int t = 1; t < nThreads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  if (failed) throw Error("encodeVolume: " + failure);
  return e;
}

EncodedVolume rawBlocks(const Volume& v, int levels, int finestBlocks) {
  EncodedVolume e;
  e.partition = Partition(v.dims, levels, finestBlocks);
  e.degree = 1;
  e.dims = v.dims;
  e.minValue = v.minValue;
  e.maxValue = v.maxValue;
  e.raw = true;
  e.models.resize(size_t(levels));
  for (int l = 0; l < levels; ++l) {
    e.models[size_t(l)].resize(size_t(e.partition.blockCount(l)));
    for (int64_t b = 0; b < e.partition.blockCount(l); ++b) {
      const Int3 ijk = e.partition.blockFromLinear(l, b);
      const BlockExtent ext = e.partition.extent(l, ijk);
      std::array<std::vector<int64_t>, 3> i0;
      std::array<std::vector<float>, 3> fr;
      std::array<int, 3> padded{};
      for (int a = 0; a < 3; ++a) {
        const int n = ext.samples[a];
        padded[size_t(a)] = n + 2;
        const double first = e.partition.samplePosition(ext, a, 0);
        const double step =
            n > 1 ? (e.partition.samplePosition(ext, a, n - 1) - first) / double(n - 1) : 0.0;
        for (int k = -1; k <= n; ++k) {
          double x = first + double(k) * step;
          x = std::min(std::max(x, 0.0), double(v.dims[a] - 1));
          int64_t i = int64_t(std::floor(x));
          i = std::min<int64_t>(std::max<int64_t>(i, 0), std::max<int64_t>(v.dims[a] - 2, 0));
          i0[size_t(a)].push_back(i);
          fr[size_t(a)].push_back(v.dims[a] > 1 ? float(x - double(i)) : 0.f);
        }
      }
      FitResult& m = e.models[size_t(l)][size_t(b)];
      m.ncp = padded;
      m.degree = {1, 1, 1};
      m.control.resize(size_t(padded[0]) * padded[1] * padded[2]);
      const int64_t sx = v.dims[0] > 1 ? 1 : 0;
      const int64_t sy = v.dims[1] > 1 ? v.dims[0] : 0;
      const int64_t sz = v.dims[2] > 1 ? v.dims[0] * v.dims[1] : 0;
      for (int z = 0; z < padded[2]; ++z)
        for (int y = 0; y < padded[1]; ++y)
          for (int x = 0; x < padded[0]; ++x) {
            const float* c = v.data.data() +
                             (i0[2][size_t(z)] * v.dims[1] + i0[1][size_t(y)]) * v.dims[0] +
                             i0[0][size_t(x)];
            const float fx = fr[0][size_t(x)], fy = fr[1][size_t(y)], fz = fr[2][size_t(z)];
            const float c00 = c[0] + fx * (c[sx] - c[0]);
            const float c10 = c[sy] + fx * (c[sy + sx] - c[sy]);
            const float c01 = c[sz] + fx * (c[sz + sx] - c[sz]);
            const float c11 = c[sz + sy] + fx * (c[sz + sy + sx] - c[sz + sy]);
            const float c0 = c00 + fy * (c10 - c00), c1 = c01 + fy * (c11 - c01);
            m.control[(size_t(z) * padded[1] + y) * padded[0] + x] = c0 + fz * (c1 - c0);
          }
    }
  }
  return e;
}

std::vector<BlockId> wholeLevel(const Partition& p, int level) {
  std::vector<BlockId> out;
  for (int64_t i = 0; i < p.blockCount(level); ++i)
    out.push_back({level, p.blockFromLinear(level, i)});
  return out;
}

std::vector<BlockId> distanceBands(const Partition& p, const Camera& camera) {
  std::vector<BlockId> out;
  for (const BlockRef& b : LodSelector().cut(p, camera)) out.push_back({b.level, b.ijk});
  return out;
}

void buildFrame(const EncodedVolume& e, const std::vector<BlockId>& blocks, const Camera& camera,
                const FrameOptions& options, Frame& f) {
  const Partition& p = e.partition;
  const int finest = p.levels() - 1;
  const Int3 bf = p.blocksPerAxis(finest);
  FrameView& v = f.view;
  v = FrameView{};
  v.camera = camera.toRayCamera();
  for (int a = 0; a < 3; ++a) {
    v.boxLo[a] = -1.f;
    v.boxHi[a] = 1.f;
    const double span = double(e.dims[a] - 1);
    v.voxelPerUnit[a] = float(span / 2.0);
    v.voxelMax[a] = float(span);
    v.gridDims[a] = bf[a];
    v.cellPerVoxel[a] = span > 0 ? float(double(bf[a]) / span) : 0.f;
    f.bounds[size_t(a)].resize(size_t(bf[a]) + 1);
    for (int c = 0; c < bf[a]; ++c) {
      Int3 ijk{0, 0, 0};
      ijk[a] = c;
      const BlockExtent ext = p.extent(finest, ijk);
      f.bounds[size_t(a)][size_t(c)] = float(ext.lo[a]);
      f.bounds[size_t(a)][size_t(c) + 1] = float(ext.hi[a]);
    }
    v.cellBounds[a] = f.bounds[size_t(a)].data();
  }
  f.cellSlot.assign(size_t(bf[0]) * bf[1] * bf[2], -1);
  f.slots.clear();
  f.keys.clear();
  f.pool.clear();
  for (const BlockId& b : blocks) {
    const FitResult& m = e.models[size_t(b.level)][size_t(p.linearIndex(b.level, b.ijk))];
    const BlockExtent ext = p.extent(b.level, b.ijk);
    FrameSlot s;
    s.kind = e.raw ? kSlotRaw : kSlotSpline;
    s.level = b.level;
    for (int a = 0; a < 3; ++a) {
      s.knots[a] = Knots::make(m.ncp[size_t(a)], m.degree[size_t(a)]);
      s.lo[a] = float(ext.lo[a]);
      const double extent = double(ext.hi[a] - ext.lo[a]);
      s.invExtent[a] = extent > 0 ? float(1.0 / extent) : 0.f;
    }
    s.offset = f.pool.size();
    f.pool.insert(f.pool.end(), m.control.begin(), m.control.end());
    const int32_t slot = int32_t(f.slots.size());
    f.slots.push_back(s);
    f.keys.push_back((uint64_t(b.level) << 40) | uint64_t(p.linearIndex(b.level, b.ijk)));
    const int r = p.stride(b.level);
    for (int cz = b.ijk[2] * r; cz < std::min((b.ijk[2] + 1) * r, bf[2]); ++cz)
      for (int cy = b.ijk[1] * r; cy < std::min((b.ijk[1] + 1) * r, bf[1]); ++cy)
        for (int cx = b.ijk[0] * r; cx < std::min((b.ijk[0] + 1) * r, bf[0]); ++cx)
          f.cellSlot[(size_t(cz) * bf[1] + cy) * bf[0] + cx] = slot;
  }
  v.cellSlot = f.cellSlot.data();
  v.slots = f.slots.data();
  v.slotCount = int32_t(f.slots.size());
  v.pool = f.pool.data();
  const TransferFunction tf = TransferFunction::preset(e.minValue, e.maxValue);
  f.tf = tf.table(options.tfSize, e.minValue, e.maxValue);
  // As Core's Renderer does: opacity corrected for the sample distance once per frame, which
  // castRay recognises by tfReferenceDistance == sampleDistance (no pow() per sample).
  const float ratio = float(double(options.sampleDistance) / tf.referenceDistance);
  for (size_t i = 3; i < f.tf.size(); i += 4) f.tf[i] = correctOpacity(f.tf[i], ratio);
  v.tf = f.tf.data();
  v.tfSize = options.tfSize;
  v.tfMin = e.minValue;
  v.tfMax = e.maxValue;
  v.tfReferenceDistance = options.sampleDistance;
  v.sampleDistance = options.sampleDistance;
  v.shading = options.shaded ? 1 : 0;
  v.gradientWithValue = e.raw ? 0 : 1;  // as Core's Renderer chooses per method
}

ImageDiff compareImages(const std::vector<float>& cpu, const std::vector<float>& gpu) {
  ImageDiff d;
  d.pixels = int64_t(cpu.size() / 4);
  auto to8 = [](float c) {
    const float x = c < 0.f ? 0.f : (c > 1.f ? 1.f : c);
    return int(std::lround(x * 255.f));
  };
  for (size_t i = 0; i + 3 < cpu.size() && i + 3 < gpu.size(); i += 4) {
    bool finite = true, differs = false;
    for (int c = 0; c < 4; ++c) {
      const float g = gpu[i + size_t(c)];
      if (!std::isfinite(g)) {
        finite = false;
        continue;
      }
      d.maxAbsFloat = std::max(d.maxAbsFloat, double(std::fabs(g - cpu[i + size_t(c)])));
      if (c < 3) {
        const int diff = std::abs(to8(g) - to8(cpu[i + size_t(c)]));
        d.maxAbs8 = std::max(d.maxAbs8, diff);
        differs = differs || diff != 0;
      }
    }
    if (!finite) ++d.nonFinite;
    if (differs) ++d.differing;
  }
  return d;
}

std::string dataDirectory() {
  if (const char* env = std::getenv("AFAM_GPU_DATA"))
    if (exists(std::string(env) + "/volumes")) return env;
  return std::string(AFAM_SOURCE_DIR) + "/Testing/Data";
}

std::vector<Pose> explorationPoses(const std::string& name, std::string* source) {
  for (const char* env : {"AFAM_TRAJECTORIES", "AFAM_GPU_DATA"}) {
    const char* dir = std::getenv(env);
    if (!dir) continue;
    const std::string path = std::string(dir) + (env[5] == 'G' ? "/trajectories/" : "/") + name;
    if (!exists(path)) continue;
    if (source) *source = "recorded " + path;
    return loadTrajectory(path);
  }
  const uint64_t seed = name == "user_2.dat" ? 2 : 1;
  if (source) *source = "generated walk, seed " + std::to_string(seed);
  return explorationWalk(400, seed);
}

}  // namespace afam::gputest
