// SPDX-License-Identifier: BSD-3-Clause
#include "afam/predict/appa.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <thread>

#include "afam/base/atomic_write.hpp"
#include "afam/base/errors.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/scene/lod.hpp"

namespace afam {

namespace {

int cellsOf(double span, double step) {
  return std::max(1, static_cast<int>(std::ceil(span / step - 1e-9)));
}

template <class T>
void put(std::vector<unsigned char>& b, const T& v) {
  const auto* p = reinterpret_cast<const unsigned char*>(&v);  // little-endian hosts only
  b.insert(b.end(), p, p + sizeof(T));
}

struct In {
  const std::vector<unsigned char>& b;
  std::size_t pos;
  const std::string& path;
  template <class T>
  T get(const char* what) {
    if (pos + sizeof(T) > b.size())
      throw FormatError("APPA table '" + path + "': truncated while reading " + what);
    T v;
    std::memcpy(&v, b.data() + pos, sizeof(T));
    pos += sizeof(T);
    return v;
  }
};

// The cell of x along an axis of cells `step` wide: floor quantisation with a tolerance of 1e-9
// cell, so that a value on a boundary stays in the cell above it after a round trip through a
// camera (pose -> eye -> pose loses a few ulps).
int floorCell(double x, double step) { return static_cast<int>(std::floor(x / step + 1e-9)); }

}  // namespace

int AppaGrid::distanceCells() const { return cellsOf(dMax - dMin, dStep); }
int AppaGrid::thetaCells() const { return cellsOf(180.0, angleStep); }
int AppaGrid::phiCells() const { return cellsOf(360.0, angleStep); }

int AppaGrid::cellOf(const Pose& pose) const {
  const int nd = distanceCells(), nt = thetaCells(), np = phiCells();
  const int id = std::clamp(floorCell(pose.distance - dMin, dStep), 0, nd - 1);
  const int it = std::clamp(floorCell(pose.thetaDeg, angleStep), 0, nt - 1);
  double phi = std::fmod(pose.phiDeg, 360.0);
  if (phi < 0) phi += 360.0;
  const int ip = floorCell(phi, angleStep) % np;
  return (id * nt + it) * np + ip;
}

Pose AppaGrid::samplePose(int cell) const {
  const int nt = thetaCells(), np = phiCells();
  const int ip = cell % np, it = (cell / np) % nt, id = cell / (np * nt);
  const double f = sample == Sample::Centre ? 0.5 : 0.0;
  Pose p;
  p.distance = dMin + (id + f) * dStep;
  p.thetaDeg = std::min(180.0, (it + f) * angleStep);
  p.phiDeg = std::fmod((ip + f) * angleStep, 360.0);
  return p;
}

AppaTable AppaTable::build(const AppaGrid& grid, const VisibleFn& visible, int threads) {
  const int cells = grid.cellCount();
  std::vector<std::vector<int64_t>> per(static_cast<std::size_t>(cells));
  threads = std::max(1, threads);
  auto work = [&](int t) {
    for (int c = t; c < cells; c += threads)
      per[static_cast<std::size_t>(c)] = visible(grid.samplePose(c));
  };
  if (threads == 1) {
    work(0);
  } else {
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t) pool.emplace_back(work, t);
    for (auto& th : pool) th.join();
  }
  AppaTable table;
  table.grid_ = grid;
  table.offsets_.reserve(static_cast<std::size_t>(cells) + 1);
  table.offsets_.push_back(0);
  for (const auto& v : per) {
    for (int64_t e : v) {
      if (e < 0 || e > 0xFFFFFFFFll)
        throw InvalidArgument("APPA build: entry index " + std::to_string(e) + " out of range");
      table.entries_.push_back(static_cast<uint32_t>(e));
    }
    table.offsets_.push_back(static_cast<uint32_t>(table.entries_.size()));
  }
  return table;
}

std::pair<const uint32_t*, const uint32_t*> AppaTable::lookup(const Pose& pose) const {
  if (offsets_.size() < 2) return {nullptr, nullptr};
  const int c = grid_.cellOf(pose);
  const uint32_t* base = entries_.data();
  return {base + offsets_[static_cast<std::size_t>(c)],
          base + offsets_[static_cast<std::size_t>(c) + 1]};
}

std::vector<int64_t> AppaTable::blocks(const Pose& pose) const {
  auto [b, e] = lookup(pose);
  return std::vector<int64_t>(b, e);
}

void AppaTable::save(const std::string& path) const {
  std::vector<unsigned char> b;
  b.reserve(64 + 4 * (offsets_.size() + entries_.size()));
  b.insert(b.end(), {'A', 'F', 'A', 'P', 'P', 'A', 0, 0});
  put(b, kVersion);
  put(b, key_);
  put(b, grid_.dMin);
  put(b, grid_.dStep);
  put(b, grid_.angleStep);
  put(b, static_cast<uint32_t>(grid_.sample));
  put(b, static_cast<uint32_t>(grid_.distanceCells()));
  put(b, static_cast<uint32_t>(grid_.thetaCells()));
  put(b, static_cast<uint32_t>(grid_.phiCells()));
  for (uint32_t o : offsets_) put(b, o);
  for (uint32_t e : entries_) put(b, e);
  put(b, fnv1a32(b.data(), b.size()));
  writeFileAtomically(path, b.data(), b.size(), "APPA table");
}

AppaTable AppaTable::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open APPA table '" + path + "'");
  std::vector<unsigned char> b((std::istreambuf_iterator<char>(in)),
                               std::istreambuf_iterator<char>());
  if (b.size() < 12 || std::memcmp(b.data(), "AFAPPA\0\0", 8) != 0)
    throw FormatError("APPA table '" + path + "': bad magic (not an APPA table)");
  const std::size_t body = b.size() - 4;
  uint32_t stored;
  std::memcpy(&stored, b.data() + body, 4);
  if (fnv1a32(b.data(), body) != stored)
    throw FormatError("APPA table '" + path + "': checksum mismatch (corrupt or truncated)");
  In r{b, 8, path};
  const auto version = r.get<uint32_t>("version");
  if (version != kVersion)
    throw FormatError("APPA table '" + path + "': version " + std::to_string(version) +
                      ", this build reads " + std::to_string(kVersion));
  AppaTable t;
  t.key_ = r.get<uint64_t>("key");
  t.grid_.dMin = r.get<double>("dMin");
  t.grid_.dStep = r.get<double>("dStep");
  t.grid_.angleStep = r.get<double>("angle step");
  const auto sample = r.get<uint32_t>("sampling");
  const auto nd = r.get<uint32_t>("distance cells"), nt = r.get<uint32_t>("theta cells"),
             np = r.get<uint32_t>("phi cells");
  if (!(t.grid_.dStep > 0) || !(t.grid_.angleStep > 0) || sample > 1 || nd == 0 || nd > 100000)
    throw FormatError("APPA table '" + path + "': invalid grid");
  t.grid_.sample = static_cast<AppaGrid::Sample>(sample);
  t.grid_.dMax = t.grid_.dMin + nd * t.grid_.dStep;
  if (static_cast<uint32_t>(t.grid_.distanceCells()) != nd ||
      static_cast<uint32_t>(t.grid_.thetaCells()) != nt ||
      static_cast<uint32_t>(t.grid_.phiCells()) != np)
    throw FormatError("APPA table '" + path + "': cell counts do not match the steps");
  const std::size_t cells = std::size_t(nd) * nt * np;
  if ((body - r.pos) / 4 < cells + 1)
    throw FormatError("APPA table '" + path + "': truncated offsets");
  t.offsets_.resize(cells + 1);
  for (auto& o : t.offsets_) o = r.get<uint32_t>("offsets");
  if (t.offsets_[0] != 0) throw FormatError("APPA table '" + path + "': first offset not 0");
  for (std::size_t i = 1; i <= cells; ++i)
    if (t.offsets_[i] < t.offsets_[i - 1])
      throw FormatError("APPA table '" + path + "': offsets decrease at cell " + std::to_string(i));
  if ((body - r.pos) != std::size_t(t.offsets_.back()) * 4)
    throw FormatError("APPA table '" + path + "': entry count does not match the file size");
  t.entries_.resize(t.offsets_.back());
  if (!t.entries_.empty()) std::memcpy(t.entries_.data(), b.data() + r.pos, t.entries_.size() * 4);
  return t;
}

AppaTable AppaTable::loadOrBuild(const std::string& tablePath, uint64_t key, const AppaGrid& grid,
                                 const VisibleFn& visible, AppaBuildReport* report, int threads) {
  const auto t0 = std::chrono::steady_clock::now();
  AppaBuildReport rep;
  rep.path = tablePath;
  auto finish = [&](const AppaTable& t) {
    rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    rep.cells = t.grid().cellCount();
    rep.entries = t.entryCount();
    struct stat st {};
    rep.bytes = ::stat(tablePath.c_str(), &st) == 0 ? static_cast<uint64_t>(st.st_size) : 0;
    if (report) *report = rep;
  };
  try {
    AppaTable t = load(tablePath);
    if (t.key() != key) {
      rep.rebuiltBecause = "stale (the .afam file or the view settings changed)";
    } else if (t.grid().dMin != grid.dMin || t.grid().dStep != grid.dStep ||
               t.grid().angleStep != grid.angleStep || t.grid().sample != grid.sample ||
               t.grid().distanceCells() != grid.distanceCells()) {
      rep.rebuiltBecause = "different quantisation";
    } else {
      rep.loadedFromCache = true;
      finish(t);
      return t;
    }
  } catch (const Error& e) {
    rep.rebuiltBecause = e.what();
  }
  AppaTable t = build(grid, visible, threads);
  t.setKey(key);
  try {
    t.save(tablePath);
  } catch (const Error& e) {
    rep.rebuiltBecause += std::string("; not cached: ") + e.what();
  }
  finish(t);
  return t;
}

uint64_t appaSourceKey(const AfamFile& file, const std::string& context) {
  uint64_t h = fnv1a64(context.data(), context.size());
  struct stat st {};
  if (::stat(file.path().c_str(), &st) == 0) {
    const int64_t sz = st.st_size, sec = st.st_mtim.tv_sec, ns = st.st_mtim.tv_nsec;
    h = fnv1a64(&sz, sizeof sz, h);
    h = fnv1a64(&sec, sizeof sec, h);
    h = fnv1a64(&ns, sizeof ns, h);
  }
  for (const ModelEntry& e : file.entries()) {
    h = fnv1a64(&e.offset, sizeof e.offset, h);
    h = fnv1a64(&e.size, sizeof e.size, h);
    h = fnv1a64(&e.checksum, sizeof e.checksum, h);
  }
  return h;
}

AppaTable::VisibleFn makeLodVisibleFn(std::shared_ptr<const AfamFile> file,
                                      const LodSelector& selector, int width, int height,
                                      std::vector<float> tfTable, double tfLo, double tfHi) {
  return [file, selector, width, height, tf = std::move(tfTable), tfLo, tfHi](const Pose& pose) {
    const Camera cam = Camera::fromPose(pose, width, height);
    const Selection sel = selector.select(*file, cam, tf, tfLo, tfHi);
    std::vector<std::pair<double, int64_t>> scored;
    scored.reserve(sel.visible.size());
    for (const BlockRef& b : sel.visible) {
      double lo[3], hi[3];
      blockBox(file->partition(), b.level, b.ijk, lo, hi);
      double d2 = 0;
      for (int k = 0; k < 3; ++k) {
        const double c = 0.5 * (lo[k] + hi[k]) - cam.eye[k];
        d2 += c * c;
      }
      scored.emplace_back(d2, b.entry);
    }
    std::stable_sort(scored.begin(), scored.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<int64_t> out;
    out.reserve(scored.size());
    for (const auto& s : scored)
      if (s.second >= 0) out.push_back(s.second);
    return out;
  };
}

}  // namespace afam
