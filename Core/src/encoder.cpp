// SPDX-License-Identifier: BSD-3-Clause
#include "afam/encoder.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <ctime>
#include <exception>
#include <limits>
#include <mutex>
#include <regex>
#include <sstream>
#include <thread>

#include "afam/fit.hpp"
#include "afam/marschner_lobb.hpp"

namespace afam {

namespace {

using Clock = std::chrono::steady_clock;
double processCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string blockName(int level, const Int3& b) {
  std::ostringstream s;
  s << "block (" << b[0] << ", " << b[1] << ", " << b[2] << ") of level " << level;
  return s.str();
}

/// Linear-interpolation taps of one axis: sample k reads i0[k] (weight 1-w[k]) and i1[k] (w[k]).
struct AxisTaps {
  std::vector<int64_t> i0, i1;
  std::vector<double> w;
  bool exact = true;  ///< every w is 0
};

AxisTaps axisTaps(const Partition& part, const BlockExtent& e, int axis, bool ghost, int64_t dim) {
  const int n = e.samples[axis];
  const int g = ghost ? 1 : 0;
  AxisTaps t;
  t.i0.resize(size_t(n + 2 * g));
  t.i1.resize(t.i0.size());
  t.w.resize(t.i0.size());
  const double step = n > 1 ? double(e.hi[axis] - e.lo[axis]) / double(n - 1) : 0.0;
  for (int k = -g; k < n + g; ++k) {
    double pos;
    if (k < 0)
      pos = double(e.lo[axis]) - step;
    else if (k >= n)
      pos = double(e.hi[axis]) + step;
    else
      pos = part.samplePosition(e, axis, k);
    pos = std::min(std::max(pos, 0.0), double(dim - 1));
    int64_t i0 = static_cast<int64_t>(std::floor(pos));
    double w = pos - double(i0);
    if (w < 1e-12) w = 0;
    if (w > 1 - 1e-12) {
      ++i0;
      w = 0;
    }
    i0 = std::min(i0, dim - 1);
    const size_t s = size_t(k + g);
    t.i0[s] = i0;
    t.i1[s] = std::min(i0 + 1, dim - 1);
    t.w[s] = w;
    if (w != 0) t.exact = false;
  }
  return t;
}

/// Keeps the two most recently used z-planes of the source.
class PlaneCache {
 public:
  PlaneCache(VolumeSource& src, Index3 dims) : src_(src), plane_(size_t(dims[0] * dims[1])) {
    for (auto& s : slot_) s.z = -1;
  }
  const float* get(int64_t z) {
    for (auto& s : slot_)
      if (s.z == z) {
        s.used = ++tick_;
        return s.data.data();
      }
    Slot& s = slot_[0].used <= slot_[1].used ? slot_[0] : slot_[1];
    s.data.resize(plane_);
    src_.readSlab(z, 1, s.data.data());
    bytesRead_ += plane_ * sizeof(float);
    s.z = z;
    s.used = ++tick_;
    return s.data.data();
  }
  uint64_t bytesRead() const { return bytesRead_; }

 private:
  struct Slot {
    int64_t z = -1;
    uint64_t used = 0;
    std::vector<float> data;
  };
  VolumeSource& src_;
  size_t plane_;
  Slot slot_[2];
  uint64_t tick_ = 0, bytesRead_ = 0;
};

// Fills the samples of every block in `blocks` (all in the same z-row of one level) by walking
// the z-samples in order; out[b] is resized to the block's (ghosted) sample count.
void extractRow(const Partition& part, PlaneCache& planes, int level, const std::vector<Int3>& blocks,
                bool ghost, std::vector<std::vector<float>*>& out) {
  if (blocks.empty()) return;
  const Index3 dims = part.dims();
  const int g = ghost ? 1 : 0;
  struct Prep {
    AxisTaps tx, ty;
    int nx, ny;
  };
  std::vector<Prep> prep(blocks.size());
  const BlockExtent ez = part.extent(level, blocks[0]);
  const AxisTaps tz = axisTaps(part, ez, 2, ghost, dims[2]);
  const int nz = ez.samples[2] + 2 * g;
  for (size_t b = 0; b < blocks.size(); ++b) {
    const BlockExtent e = part.extent(level, blocks[b]);
    prep[b].tx = axisTaps(part, e, 0, ghost, dims[0]);
    prep[b].ty = axisTaps(part, e, 1, ghost, dims[1]);
    prep[b].nx = e.samples[0] + 2 * g;
    prep[b].ny = e.samples[1] + 2 * g;
    out[b]->resize(size_t(prep[b].nx) * size_t(prep[b].ny) * size_t(nz));
  }
  const int64_t X = dims[0];
  for (int k = 0; k < nz; ++k) {
    const double wz = tz.w[size_t(k)];
    const float* p0 = planes.get(tz.i0[size_t(k)]);
    const float* p1 = wz != 0 ? planes.get(tz.i1[size_t(k)]) : nullptr;
    if (p1) p0 = planes.get(tz.i0[size_t(k)]);  // both stay cached (two slots)
    for (size_t b = 0; b < blocks.size(); ++b) {
      const Prep& pr = prep[b];
      float* dst = out[b]->data() + size_t(k) * size_t(pr.nx) * size_t(pr.ny);
      const bool exactXY = pr.tx.exact && pr.ty.exact;
      for (int j = 0; j < pr.ny; ++j) {
        const int64_t y0 = pr.ty.i0[size_t(j)], y1 = pr.ty.i1[size_t(j)];
        const double wy = pr.ty.w[size_t(j)];
        float* row = dst + size_t(j) * size_t(pr.nx);
        if (exactXY && !p1) {
          const float* src = p0 + y0 * X;
          for (int i = 0; i < pr.nx; ++i) row[i] = src[pr.tx.i0[size_t(i)]];
          continue;
        }
        auto bilinear = [&](const float* p, int i) {
          const int64_t x0 = pr.tx.i0[size_t(i)], x1 = pr.tx.i1[size_t(i)];
          const double wx = pr.tx.w[size_t(i)];
          double a = p[y0 * X + x0];
          if (wx != 0) a += wx * (double(p[y0 * X + x1]) - a);
          if (wy != 0) {
            double c = p[y1 * X + x0];
            if (wx != 0) c += wx * (double(p[y1 * X + x1]) - c);
            a += wy * (c - a);
          }
          return a;
        };
        for (int i = 0; i < pr.nx; ++i) {
          double v = bilinear(p0, i);
          if (p1) v += wz * (bilinear(p1, i) - v);
          row[i] = static_cast<float>(v);
        }
      }
    }
  }
}

// Fixed-size worker pool: run(count, fn) calls fn(worker, task) for task in [0, count) on all
// workers; the calling thread waits and calls `tick` about every 100 ms (tick returning false
// stops the handing-out of tasks). The first exception thrown by a task is rethrown by run().
class Pool {
 public:
  explicit Pool(int workers) : workers_(std::max(1, workers)) {}
  template <typename Fn, typename Tick>
  void run(int64_t count, Fn&& fn, Tick&& tick) {
    std::atomic<int64_t> next{0}, done{0};
    std::atomic<bool> stop{false};
    std::exception_ptr error;
    std::mutex m;
    std::condition_variable cv;
    auto body = [&](int w) {
      for (;;) {
        if (stop.load()) break;
        const int64_t t = next.fetch_add(1);
        if (t >= count) break;
        try {
          fn(w, t);
        } catch (...) {
          std::lock_guard<std::mutex> lock(m);
          if (!error) error = std::current_exception();
          stop = true;
        }
        if (done.fetch_add(1) + 1 == count) {
          std::lock_guard<std::mutex> lock(m);
          cv.notify_all();
        }
      }
      std::lock_guard<std::mutex> lock(m);
      cv.notify_all();
    };
    std::vector<std::thread> threads;
    const int nThreads = int(std::min<int64_t>(workers_, std::max<int64_t>(count, 1)));
    threads.reserve(size_t(nThreads));
    for (int w = 0; w < nThreads; ++w) threads.emplace_back(body, w);
    {
      std::unique_lock<std::mutex> lock(m);
      while (done.load() < count && !stop.load()) {
        cv.wait_for(lock, std::chrono::milliseconds(100));
        lock.unlock();
        if (!tick()) stop = true;
        lock.lock();
      }
    }
    for (auto& t : threads) t.join();
    if (error) std::rethrow_exception(error);
  }
  int workers() const { return workers_; }

 private:
  int workers_;
};

struct BlockTask {
  Int3 ijk{};
  bool search = false;
  std::vector<float> samples;
  ModelEntry entry;
  std::vector<float> payload;
  int ncpStar = 0;
  int64_t fits = 0;
  bool complex = false;
};

}  // namespace

// ------------------------------------------------------------------------------------------------
// Sources

ArraySource::ArraySource(const float* data, Index3 dims, std::string name, std::array<double, 3> origin,
                         std::array<double, 3> spacing)
    : data_(data), dims_(dims), name_(std::move(name)), origin_(origin), spacing_(spacing) {
  if (!data) throw InvalidArgument("ArraySource: null data");
  for (int a = 0; a < 3; ++a)
    if (dims[a] < 1) throw InvalidArgument("ArraySource: dimensions must be >= 1");
}

void ArraySource::readSlab(int64_t z0, int64_t zCount, float* out) {
  if (z0 < 0 || zCount < 0 || z0 + zCount > dims_[2])
    throw InvalidArgument("ArraySource: planes [" + std::to_string(z0) + ", " + std::to_string(z0 + zCount) +
                          ") outside the volume");
  const size_t plane = size_t(dims_[0] * dims_[1]);
  std::memcpy(out, data_ + size_t(z0) * plane, size_t(zCount) * plane * sizeof(float));
}

const char* scalarTypeName(ScalarType t) {
  switch (t) {
    case ScalarType::Float32: return "float32";
    case ScalarType::Float64: return "float64";
    case ScalarType::UInt8: return "uint8";
    case ScalarType::UInt16: return "uint16";
    case ScalarType::Int16: return "int16";
  }
  return "unknown";
}

ScalarType parseScalarType(const std::string& s) {
  if (s == "float32" || s == "float") return ScalarType::Float32;
  if (s == "float64" || s == "double") return ScalarType::Float64;
  if (s == "uint8") return ScalarType::UInt8;
  if (s == "uint16") return ScalarType::UInt16;
  if (s == "int16") return ScalarType::Int16;
  throw InvalidArgument("unknown scalar type '" + s + "' (expected float32, float64, uint8, uint16 or int16)");
}

int scalarTypeSize(ScalarType t) {
  switch (t) {
    case ScalarType::Float32: return 4;
    case ScalarType::Float64: return 8;
    case ScalarType::UInt8: return 1;
    case ScalarType::UInt16: return 2;
    case ScalarType::Int16: return 2;
  }
  return 4;
}

bool parseRawName(const std::string& path, Index3& dims, ScalarType& type) {
  static const std::regex re(R"(_(\d+)x(\d+)x(\d+)_(float32|float64|uint8|uint16|int16)\.raw$)");
  std::smatch m;
  if (!std::regex_search(path, m, re)) return false;
  for (int a = 0; a < 3; ++a) {
    // A size the .afam header cannot hold (0, or above 2^31 - 1) is not a volume's name.
    const std::string digits = m[a + 1].str();
    if (digits.size() > 10) return false;
    const long long v = std::stoll(digits);
    if (v < 1 || v > std::numeric_limits<int32_t>::max()) return false;
    dims[a] = v;
  }
  type = parseScalarType(m[4].str());
  return true;
}

RawFileSource::RawFileSource(const std::string& path, Index3 dims, ScalarType type, std::array<double, 3> origin,
                             std::array<double, 3> spacing)
    : path_(path), dims_(dims), type_(type), origin_(origin), spacing_(spacing) {
  for (int a = 0; a < 3; ++a)
    if (dims[a] < 1) throw InvalidArgument(path + ": dimensions must be >= 1");
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw IoError(path + ": cannot open: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd_, &st) != 0) throw IoError(path + ": cannot stat: " + std::strerror(errno));
  uint64_t expected = uint64_t(scalarTypeSize(type));
  for (int a = 0; a < 3; ++a)
    if (__builtin_mul_overflow(expected, uint64_t(dims[a]), &expected)) {
      ::close(fd_);
      fd_ = -1;
      throw InvalidArgument(path + ": " + std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" +
                            std::to_string(dims[2]) + " " + scalarTypeName(type) + " is more than 2^64 bytes");
    }
  if (uint64_t(st.st_size) != expected) {
    ::close(fd_);
    fd_ = -1;
    throw InvalidArgument(path + ": file has " + std::to_string(st.st_size) + " bytes, " +
                          std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]) +
                          " " + scalarTypeName(type) + " needs " + std::to_string(expected));
  }
}

RawFileSource::~RawFileSource() {
  if (fd_ >= 0) ::close(fd_);
}

std::string RawFileSource::name() const {
  std::string base = path_.substr(path_.find_last_of('/') == std::string::npos ? 0 : path_.find_last_of('/') + 1);
  const size_t us = base.find('_');
  return us == std::string::npos || us == 0 ? base : base.substr(0, us);
}

void RawFileSource::readSlab(int64_t z0, int64_t zCount, float* out) {
  if (z0 < 0 || zCount < 0 || z0 + zCount > dims_[2])
    throw InvalidArgument(path_ + ": planes outside the volume");
  const int es = scalarTypeSize(type_);
  const uint64_t count = uint64_t(dims_[0]) * uint64_t(dims_[1]) * uint64_t(zCount);
  const uint64_t bytes = count * uint64_t(es);
  const uint64_t offset = uint64_t(z0) * uint64_t(dims_[0]) * uint64_t(dims_[1]) * uint64_t(es);
  unsigned char* dst;
  if (type_ == ScalarType::Float32) {
    dst = reinterpret_cast<unsigned char*>(out);
  } else {
    buffer_.resize(bytes);
    dst = buffer_.data();
  }
  uint64_t done = 0;
  while (done < bytes) {
    const ssize_t r = ::pread(fd_, dst + done, size_t(std::min<uint64_t>(bytes - done, 1u << 30)), off_t(offset + done));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) throw IoError(path_ + ": read failed at byte " + std::to_string(offset + done) + ": " +
                              (r == 0 ? std::string("unexpected end of file") : std::string(std::strerror(errno))));
    done += uint64_t(r);
  }
  switch (type_) {
    case ScalarType::Float32: break;
    case ScalarType::Float64:
      for (uint64_t i = 0; i < count; ++i) {
        double v;
        std::memcpy(&v, dst + i * 8, 8);
        out[i] = static_cast<float>(v);
      }
      break;
    case ScalarType::UInt8:
      for (uint64_t i = 0; i < count; ++i) out[i] = float(dst[i]);
      break;
    case ScalarType::UInt16:
      for (uint64_t i = 0; i < count; ++i) {
        uint16_t v;
        std::memcpy(&v, dst + i * 2, 2);
        out[i] = float(v);
      }
      break;
    case ScalarType::Int16:
      for (uint64_t i = 0; i < count; ++i) {
        int16_t v;
        std::memcpy(&v, dst + i * 2, 2);
        out[i] = float(v);
      }
      break;
  }
}

void MarschnerLobbSource::readSlab(int64_t z0, int64_t zCount, float* out) {
  marschnerLobbSlab(MarschnerLobb{}, dims_, z0, zCount, out);
}

// ------------------------------------------------------------------------------------------------
// Sinks

void InMemoryModels::begin(const VolumeHeader& h) {
  header = h;
  partition = Partition(h.dims, h.levels, h.blocksPerAxis);
  const int64_t total = partition.totalBlockCount();
  entries.assign(size_t(total), ModelEntry{});
  payloads.assign(size_t(total), {});
  levelStart.assign(size_t(h.levels) + 1, 0);
  for (int l = 0; l < h.levels; ++l) levelStart[size_t(l) + 1] = levelStart[size_t(l)] + partition.blockCount(l);
}

int64_t InMemoryModels::entryIndex(int level, Int3 ijk) const {
  if (level < 0 || level >= header.levels) return -1;
  const Int3 b = partition.blocksPerAxis(level);
  for (int a = 0; a < 3; ++a)
    if (ijk[a] < 0 || ijk[a] >= b[a]) return -1;
  return levelStart[size_t(level)] + partition.linearIndex(level, ijk);
}

void InMemoryModels::add(const ModelEntry& entry, const float* payload) {
  const int64_t i = entryIndex(entry.level, entry.block);
  if (i < 0) throw InvalidArgument("InMemoryModels: block out of range");
  ModelEntry e = entry;
  e.size = payloadBytes(e.ncp);
  payloads[size_t(i)].assign(payload, payload + e.size / 4);
  e.checksum = crc32(payload, e.size);
  entries[size_t(i)] = e;
}

void InMemoryModels::write(const std::string& path) const {
  AfamWriter w(path, header);
  for (size_t i = 0; i < entries.size(); ++i) w.add(entries[i], payloads[i].data());
  w.commit();
}

namespace {
class FileSink : public ModelSink {
 public:
  explicit FileSink(std::string path) : path_(std::move(path)) {}
  void begin(const VolumeHeader& h) override { writer_ = std::make_unique<AfamWriter>(path_, h); }
  void add(const ModelEntry& e, const float* payload) override { writer_->add(e, payload); }
  uint64_t commit() {
    const uint64_t size = writer_->bytesWritten();
    writer_->commit();
    return size;
  }

 private:
  std::string path_;
  std::unique_ptr<AfamWriter> writer_;
};
}  // namespace

// ------------------------------------------------------------------------------------------------
// Search

int searchNcp(BlockFitter& fitter, const float* samples, Int3 n, int degree, double bound, SearchMethod method,
              int window, FitResult& result, int64_t& fits) {
  Int3 degs{};
  int nmax = 1;
  for (int a = 0; a < 3; ++a) {
    degs[a] = effectiveDegree(degree, n[a]);
    nmax = std::max(nmax, n[a]);
  }
  const int lo = std::min(degree + 1, nmax), hi = nmax;
  FitResult tmp, best, top;
  int bestK = std::numeric_limits<int>::max();
  bool haveTop = false;
  std::vector<signed char> state(size_t(hi) + 1, -1);  // -1 unknown, 0 fails, 1 passes
  auto pass = [&](int k) -> bool {
    if (state[size_t(k)] >= 0) return state[size_t(k)] == 1;
    fitter.fitInto(samples, n, clampNcp(k, n, degs), degree, true, tmp);
    ++fits;
    const bool ok = tmp.error.rmse <= bound;
    state[size_t(k)] = ok ? 1 : 0;
    if (ok && k < bestK) {
      bestK = k;
      std::swap(best, tmp);
    } else if (k == hi) {
      std::swap(top, tmp);
      haveTop = true;
    }
    return ok;
  };
  auto finish = [&]() {
    if (bestK <= hi) {
      result = std::move(best);
      return bestK;
    }
    if (!haveTop) pass(hi);
    result = std::move(top);
    return hi;
  };
  if (method == SearchMethod::Exhaustive || hi - lo < 2) {
    for (int k = lo; k <= hi; ++k) pass(k);
    return finish();
  }
  if (pass(lo)) return finish();
  if (!pass(hi)) {
    for (int k = lo + 1; k < hi; ++k)
      if (pass(k)) break;
    return finish();
  }
  int a = lo, b = hi;  // a fails, b passes
  while (b - a > 1) {
    const int m = a + (b - a) / 2;
    if (pass(m))
      b = m;
    else
      a = m;
  }
  // Local check below the boundary: a non-monotone error curve may pass again just below it.
  int stop = std::max(lo + 1, b - 1 - window);
  for (int j = b - 2; j >= stop; --j)
    if (pass(j)) stop = std::max(lo + 1, j - 1 - window);
  return finish();
}

std::vector<float> extractBlock(const Partition& part, const float* volume, int level, Int3 ijk, bool ghost) {
  ArraySource src(volume, part.dims());
  PlaneCache planes(src, part.dims());
  std::vector<float> out;
  std::vector<std::vector<float>*> outs{&out};
  extractRow(part, planes, level, {ijk}, ghost, outs);
  return out;
}

struct BlockRowReader::Impl {
  Impl(VolumeSource& s, const Partition& p) : part(p), planes(s, p.dims()) {}
  const Partition& part;
  PlaneCache planes;
};

BlockRowReader::BlockRowReader(VolumeSource& source, const Partition& partition)
    : impl_(std::make_unique<Impl>(source, partition)) {}
BlockRowReader::~BlockRowReader() = default;
uint64_t BlockRowReader::bytesRead() const { return impl_->planes.bytesRead(); }

void BlockRowReader::readRow(int level, int kz, bool ghost, std::vector<std::vector<float>>& out) {
  const Int3 nb = impl_->part.blocksPerAxis(level);
  std::vector<Int3> row;
  for (int j = 0; j < nb[1]; ++j)
    for (int i = 0; i < nb[0]; ++i) row.push_back({i, j, kz});
  out.resize(row.size());
  std::vector<std::vector<float>*> outs(row.size());
  for (size_t r = 0; r < row.size(); ++r) outs[r] = &out[r];
  extractRow(impl_->part, impl_->planes, level, row, ghost, outs);
}

void decodeBlockSamples(const ModelEntry& e, const float* payload, EncodingMode mode, std::vector<float>& out) {
  const Int3 n = e.samples;
  if (mode == EncodingMode::Downsampled) {
    out.resize(size_t(n[0]) * size_t(n[1]) * size_t(n[2]));
    const size_t gx = size_t(e.ncp[0]), gy = size_t(e.ncp[1]);
    for (int z = 0; z < n[2]; ++z)
      for (int y = 0; y < n[1]; ++y)
        std::memcpy(out.data() + (size_t(z) * size_t(n[1]) + size_t(y)) * size_t(n[0]),
                    payload + ((size_t(z) + 1) * gy + size_t(y) + 1) * gx + 1, size_t(n[0]) * sizeof(float));
    return;
  }
  FitResult model;
  model.ncp = e.ncp;
  model.degree = e.degree;
  model.control.assign(payload, payload + size_t(e.ncp[0]) * size_t(e.ncp[1]) * size_t(e.ncp[2]));
  evaluateOnGrid(model, n, out);
}

LevelGrid levelGrid(const Partition& part, int level) {
  if (level < 0 || level >= part.levels())
    throw InvalidArgument("level " + std::to_string(level) + " outside [0, " + std::to_string(part.levels() - 1) + "]");
  LevelGrid g;
  const Int3 nb = part.blocksPerAxis(level);
  for (int a = 0; a < 3; ++a) {
    Int3 ijk{0, 0, 0};
    int64_t pos = 0;
    for (int i = 0; i < nb[a]; ++i) {
      ijk[a] = i;
      g.start[size_t(a)].push_back(pos);
      pos += part.extent(level, ijk).samples[a] - 1;
    }
    g.dims[a] = pos + 1;
  }
  return g;
}

void decodeLevelBox(const AfamFile& f, int level, const Index3& lo, const Index3& hi, float* out,
                    const std::function<void(double)>& progress) {
  const Partition& part = f.partition();
  const LevelGrid g = levelGrid(part, level);
  const Int3 nb = part.blocksPerAxis(level);
  Index3 n{};
  int first[3], last[3];  // blocks owning samples of the box, per axis
  for (int a = 0; a < 3; ++a) {
    if (lo[a] < 0 || hi[a] >= g.dims[a] || lo[a] > hi[a])
      throw InvalidArgument("decode box outside the level grid on axis " + std::to_string(a));
    n[a] = hi[a] - lo[a] + 1;
    const auto& st = g.start[size_t(a)];
    // Block i owns [start[i], start[i+1]) (the last block up to dims-1).
    first[a] = int(std::upper_bound(st.begin(), st.end(), lo[a]) - st.begin()) - 1;
    last[a] = int(std::upper_bound(st.begin(), st.end(), hi[a]) - st.begin()) - 1;
  }
  const double total = double(last[0] - first[0] + 1) * (last[1] - first[1] + 1) * (last[2] - first[2] + 1);
  double done = 0;
  std::vector<float> payload, dec;
  for (int k = first[2]; k <= last[2]; ++k)
    for (int j = first[1]; j <= last[1]; ++j)
      for (int i = first[0]; i <= last[0]; ++i) {
        const int64_t ei = f.entryIndex(level, {i, j, k});
        const ModelEntry& m = f.entries()[size_t(ei)];
        payload.resize(m.size / 4);
        f.readPayload(ei, payload.data());
        decodeBlockSamples(m, payload.data(), f.header().mode, dec);
        const int ijk[3] = {i, j, k};
        int64_t b0[3], b1[3];  // owned samples of the block inside the box, level-grid indices
        for (int a = 0; a < 3; ++a) {
          const auto& st = g.start[size_t(a)];
          const int64_t s0 = st[size_t(ijk[a])];
          const int64_t ownedEnd = ijk[a] + 1 < nb[a] ? st[size_t(ijk[a]) + 1] - 1 : g.dims[a] - 1;
          b0[a] = std::max(s0, lo[a]);
          b1[a] = std::min(ownedEnd, hi[a]);
        }
        for (int64_t z = b0[2]; z <= b1[2]; ++z)
          for (int64_t y = b0[1]; y <= b1[1]; ++y) {
            const int64_t sz = z - g.start[2][size_t(k)], sy = y - g.start[1][size_t(j)];
            const int64_t sx = b0[0] - g.start[0][size_t(i)];
            std::memcpy(out + ((z - lo[2]) * n[1] + (y - lo[1])) * n[0] + (b0[0] - lo[0]),
                        dec.data() + (sz * m.samples[1] + sy) * m.samples[0] + sx,
                        size_t(b1[0] - b0[0] + 1) * sizeof(float));
          }
        if (progress) progress(++done / total);
      }
}

// ------------------------------------------------------------------------------------------------
// Encoder

EncodeStats encodeVolume(VolumeSource& source, const EncoderOptions& opt, ModelSink& sink) {
  const auto t0 = Clock::now();
  const double cpu0 = processCpuSeconds();
  if (opt.degree < 1 || opt.degree > 5) throw InvalidArgument("encode: degree " + std::to_string(opt.degree) + " outside [1, 5]");
  if (!(opt.errorBound >= 0) || !std::isfinite(opt.errorBound))
    throw InvalidArgument("encode: error bound must be finite and >= 0");
  if (opt.fixedNcp < 0) throw InvalidArgument("encode: --ncp must be >= 0");
  const Index3 dims = source.dims();
  const Partition part(dims, opt.levels, opt.blocksPerAxis);  // validates levels, blocks, dims
  const int L = part.levels();
  int threads = opt.threads > 0 ? opt.threads : int(std::thread::hardware_concurrency());
  threads = std::max(1, threads);

  EncodeStats stats;
  stats.threads = threads;
  stats.inputVoxels = dims[0] * dims[1] * dims[2];
  stats.bytesIn = uint64_t(stats.inputVoxels) * uint64_t(source.bytesPerVoxel());

  // Progress weights: samples per level.
  std::vector<double> levelWork(size_t(L), 0);
  double totalWork = 0;
  for (int l = 0; l < L; ++l) {
    const Int3 b = part.blocksPerAxis(l);
    double s = 1;
    for (int a = 0; a < 3; ++a) {
      Int3 ijk{0, 0, 0};
      double sum = 0;
      for (int i = 0; i < b[a]; ++i) {
        ijk[a] = i;
        sum += part.extent(l, ijk).samples[a];
      }
      s *= sum;
    }
    levelWork[size_t(l)] = s;
    totalWork += s;
  }
  const double rangeWork = opt.relativeBound ? 0.05 * totalWork : 0.02 * totalWork;
  totalWork += rangeWork;
  double workDone = 0;
  auto report = [&](double extra) {
    if (!opt.progress) return true;
    return opt.progress(std::min(1.0, (workDone + extra) / totalWork));
  };
  auto cancelled = []() { return Cancelled("encoding cancelled"); };

  // Value range (and NaN/Inf check) in one streaming pass unless the source knows it.
  double vmin = 0, vmax = 0;
  if (!source.knownRange(vmin, vmax)) {
    const int64_t plane = dims[0] * dims[1];
    const int64_t chunk = std::max<int64_t>(1, (int64_t(4) << 20) / std::max<int64_t>(plane, 1));
    std::vector<float> buf;
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (int64_t z = 0; z < dims[2]; z += chunk) {
      const int64_t nz = std::min(chunk, dims[2] - z);
      buf.resize(size_t(nz * plane));
      source.readSlab(z, nz, buf.data());
      for (size_t i = 0; i < buf.size(); ++i) {
        const float v = buf[i];
        if (!std::isfinite(v)) {
          const int64_t x = int64_t(i) % dims[0], y = (int64_t(i) / dims[0]) % dims[1], zz = z + int64_t(i) / plane;
          // Name the finest-level block holding the sample.
          const int lf = L - 1;
          const Int3 nb = part.blocksPerAxis(lf);
          Int3 blk{0, 0, 0};
          const int64_t xyz[3] = {x, y, zz};
          for (int a = 0; a < 3; ++a) {
            Int3 probe{0, 0, 0};
            for (int j = 0; j < nb[a]; ++j) {
              probe[a] = j;
              if (part.extent(lf, probe).hi[a] >= xyz[a]) {
                blk[a] = j;
                break;
              }
            }
          }
          std::ostringstream msg;
          msg << "encode: sample (" << x << ", " << y << ", " << zz << ") of " << source.name() << " is "
              << (std::isnan(v) ? "NaN" : "Inf") << ", in " << blockName(lf, blk)
              << "; the encoder needs finite values";
          throw NumericError(msg.str());
        }
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
      if (!report(rangeWork * double(z + nz) / double(dims[2]))) throw cancelled();
    }
    vmin = lo;
    vmax = hi;
  }
  workDone += rangeWork;
  stats.valueMin = vmin;
  stats.valueMax = vmax;
  const double bound = opt.relativeBound ? opt.errorBound * (vmax - vmin) : opt.errorBound;
  stats.bound = bound;

  VolumeHeader header;
  header.dims = dims;
  header.origin = source.origin();
  header.spacing = source.spacing();
  header.valueMin = vmin;
  header.valueMax = vmax;
  header.scalarName = source.name();
  header.levels = L;
  header.blocksPerAxis = opt.blocksPerAxis;
  header.degree = opt.degree;
  header.errorBound = opt.errorBound;
  header.relativeBound = opt.relativeBound;
  header.mode = opt.mode;
  header.fixedNcp = opt.fixedNcp;
  sink.begin(header);

  const bool ds = opt.mode == EncodingMode::Downsampled;
  std::vector<BlockFitter> fitters;
  fitters.resize(size_t(threads));
  Pool pool(threads);
  PlaneCache planes(source, dims);
  std::vector<uint8_t> complexPrev, complexCur;
  // Buffer budget for one batch of block rows (samples as float).
  const size_t budgetFloats = size_t(24) << 20;
  stats.levels.resize(size_t(L));
  const auto tFit0 = Clock::now();

  for (int l = 0; l < L; ++l) {
    const auto tl = Clock::now();
    LevelStats& ls = stats.levels[size_t(l)];
    const Int3 nb = part.blocksPerAxis(l);
    ls.blocks = part.blockCount(l);
    complexCur.assign(size_t(ls.blocks), 0);
    double levelDone = 0;
    int kz = 0;
    while (kz < nb[2]) {
      // Gather rows of blocks until the sample budget is reached.
      std::vector<BlockTask> tasks;
      size_t floats = 0;
      while (kz < nb[2] && (tasks.empty() || floats < budgetFloats)) {
        std::vector<Int3> row;
        for (int j = 0; j < nb[1]; ++j)
          for (int i = 0; i < nb[0]; ++i) row.push_back({i, j, kz});
        const size_t first = tasks.size();
        tasks.resize(first + row.size());
        std::vector<std::vector<float>*> outs(row.size());
        for (size_t r = 0; r < row.size(); ++r) {
          BlockTask& t = tasks[first + r];
          t.ijk = row[r];
          t.search = !ds && opt.mode != EncodingMode::Fixed &&
                     (opt.mode == EncodingMode::InLevel || l == 0 ||
                      complexPrev[size_t(part.linearIndex(l - 1, part.parent(l, t.ijk)))] != 0);
          outs[r] = &t.samples;
        }
        extractRow(part, planes, l, row, ds, outs);
        for (size_t r = 0; r < row.size(); ++r) floats += tasks[first + r].samples.size();
        ++kz;
        if (!report(levelDone)) throw cancelled();
      }
      // Fit the batch in parallel.
      std::mutex doneMutex;
      bool cancelRequested = false;
      double batchDoneValue = 0;
      pool.run(
          int64_t(tasks.size()),
          [&](int w, int64_t ti) {
            BlockTask& t = tasks[size_t(ti)];
            const BlockExtent e = part.extent(l, t.ijk);
            ModelEntry& m = t.entry;
            m.level = l;
            m.block = t.ijk;
            m.samples = e.samples;
            if (ds) {
              for (int a = 0; a < 3; ++a) {
                m.ncp[a] = e.samples[a] + 2;
                m.degree[a] = 1;
              }
              // min/max over the block's own samples (the ghost layer belongs to neighbours).
              float lo = std::numeric_limits<float>::infinity(), hi = -lo;
              const int gx = m.ncp[0], gy = m.ncp[1];
              for (int z = 1; z <= e.samples[2]; ++z)
                for (int y = 1; y <= e.samples[1]; ++y)
                  for (int x = 1; x <= e.samples[0]; ++x) {
                    const float v = t.samples[(size_t(z) * size_t(gy) + size_t(y)) * size_t(gx) + size_t(x)];
                    lo = std::min(lo, v);
                    hi = std::max(hi, v);
                  }
              m.minValue = lo;
              m.maxValue = hi;
              t.payload = std::move(t.samples);
            } else {
              BlockFitter& fitter = fitters[size_t(w)];
              FitResult fr;
              Int3 degs{};
              int nmax = 1;
              for (int a = 0; a < 3; ++a) {
                degs[a] = effectiveDegree(opt.degree, e.samples[a]);
                nmax = std::max(nmax, e.samples[a]);
              }
              const int lo = std::min(opt.degree + 1, nmax);
              try {
                if (t.search) {
                  t.ncpStar = searchNcp(fitter, t.samples.data(), e.samples, opt.degree, bound, opt.search,
                                        opt.fastWindow, fr, t.fits);
                  t.complex = t.ncpStar > lo;
                } else {
                  const Int3 ncp = opt.mode == EncodingMode::Fixed
                                       ? (opt.fixedNcp > 0 ? clampNcp(opt.fixedNcp, e.samples, degs) : e.samples)
                                       : clampNcp(lo, e.samples, degs);
                  fitter.fitInto(t.samples.data(), e.samples, ncp, opt.degree, true, fr);
                  ++t.fits;
                  t.ncpStar = std::max({ncp[0], ncp[1], ncp[2]});
                }
              } catch (const NumericError& ex) {
                throw NumericError("encode: " + blockName(l, t.ijk) + " of " + source.name() + ": " + ex.what());
              }
              m.ncp = fr.ncp;
              m.degree = fr.degree;
              m.minValue = float(fr.error.minValue);
              m.maxValue = float(fr.error.maxValue);
              m.rmse = float(fr.error.rmse);
              m.maxError = float(fr.error.maxError);
              t.payload = std::move(fr.control);
              std::vector<float>().swap(t.samples);
            }
            std::lock_guard<std::mutex> lock(doneMutex);
            batchDoneValue += double(e.samples[0]) * e.samples[1] * e.samples[2];
          },
          [&]() {
            double v;
            {
              std::lock_guard<std::mutex> lock(doneMutex);
              v = batchDoneValue;
            }
            if (!report(levelDone + v)) cancelRequested = true;
            return !cancelRequested;
          });
      if (cancelRequested) throw cancelled();
      // Hand the models to the sink in order and collect statistics.
      for (BlockTask& t : tasks) {
        const ModelEntry& m = t.entry;
        sink.add(m, t.payload.data());
        const int64_t li = part.linearIndex(l, t.ijk);
        complexCur[size_t(li)] = t.complex ? 1 : 0;
        ls.searched += t.search ? 1 : 0;
        ls.complex += t.complex ? 1 : 0;
        ls.fits += t.fits;
        ls.samples += int64_t(m.samples[0]) * m.samples[1] * m.samples[2];
        const uint64_t pb = payloadBytes(m.ncp);
        ls.payloadBytes += pb;
        ls.paperBytes += ds ? pb : paperModelBytes(m.ncp, m.degree);
        ls.maxRmse = std::max(ls.maxRmse, double(m.rmse));
        ls.maxError = std::max(ls.maxError, double(m.maxError));
        const int k = std::max({m.ncp[0], m.ncp[1], m.ncp[2]});
        if (ls.ncpHistogram.size() <= size_t(k)) ls.ncpHistogram.resize(size_t(k) + 1, 0);
        ++ls.ncpHistogram[size_t(k)];
        levelDone += double(m.samples[0]) * m.samples[1] * m.samples[2];
      }
      if (!report(levelDone)) throw cancelled();
    }
    workDone += levelWork[size_t(l)];
    complexPrev.swap(complexCur);
    ls.seconds = secondsSince(tl);
    stats.fits += ls.fits;
    stats.blocks += ls.blocks;
    stats.payloadBytes += ls.payloadBytes;
    stats.paperBytes += ls.paperBytes;
    stats.maxRmse = std::max(stats.maxRmse, ls.maxRmse);
    stats.maxError = std::max(stats.maxError, ls.maxError);
  }
  stats.fitSeconds = secondsSince(tFit0);
  stats.bytesOut = 1024 + uint64_t(stats.blocks) * 40 + stats.payloadBytes;  // file layout, no padding
  stats.seconds = secondsSince(t0);
  stats.cpuSeconds = processCpuSeconds() - cpu0;
  report(0);
  return stats;
}

EncodeStats encodeVolume(VolumeSource& source, const EncoderOptions& options, const std::string& outPath) {
  FileSink sink(outPath);
  const auto t0 = Clock::now();
  const double cpu0 = processCpuSeconds();
  EncodeStats stats = encodeVolume(source, options, sink);
  stats.bytesOut = sink.commit();
  stats.seconds = secondsSince(t0);
  stats.cpuSeconds = processCpuSeconds() - cpu0;
  return stats;
}

}  // namespace afam
