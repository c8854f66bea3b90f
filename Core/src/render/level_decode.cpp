// SPDX-License-Identifier: BSD-3-Clause
#include "afam/render/level_decode.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <memory>

#include "afam/base/errors.hpp"
#include "afam/render/damage.hpp"
#include "afam/render/prepared_frame.hpp"
#include "afam/render/raycast.hpp"
#include "afam/spline/fit.hpp"

namespace afam {

namespace {

/// What stands in for a damaged block (replaceDamaged: its nearest intact coarser model, else its
/// intact children), each model over its region, ready to be evaluated at voxel positions.
class StandIns {
 public:
  StandIns(const AfamFile& f, const BlockRef& damaged) {
    const IntactLoader load = [&f](int64_t entry) -> Payload {
      try {
        auto model = std::make_shared<CachedModel>(f.entries()[size_t(entry)].size / sizeof(float));
        f.readPayload(entry, model->data());
        return Payload(std::move(model));
      } catch (const FormatError&) {
        return nullptr;  // damaged too: replaceDamaged looks further
      }
    };
    replaceDamaged(f, damaged, load, placed_);
    for (const Placement& p : placed_) {
      slots_.push_back(modelSlot(f, p.model, 0));
      regions_.push_back(f.partition().extent(p.region.level, p.region.ijk));
    }
  }

  /// The value at voxel coordinates x of the model whose region holds x; NaN when none does.
  float valueAt(const float* x) const {
    for (size_t k = 0; k < slots_.size(); ++k) {
      if (!covers(regions_[k], x)) continue;
      return sampleSlot<false>(slots_[k], placed_[k].data->data(), x, nullptr);
    }
    return std::numeric_limits<float>::quiet_NaN();
  }

 private:
  static bool covers(const BlockExtent& r, const float* x) {
    for (int a = 0; a < 3; ++a)
      if (x[a] < float(r.lo[a]) || x[a] > float(r.hi[a])) return false;
    return true;
  }
  std::vector<Placement> placed_;
  std::vector<FrameSlot> slots_;
  std::vector<BlockExtent> regions_;
};

/// Level-grid samples [b0, b1] of a damaged block, written into the box `out` (origin lo, n
/// samples per axis) from its stand-ins.
void fillFromStandIns(const AfamFile& f, const LevelGrid& g, const BlockRef& damaged,
                      const int64_t b0[3], const int64_t b1[3], const Index3& lo, const Index3& n,
                      float* out) {
  const StandIns standIns(f, damaged);
  const BlockExtent e = f.partition().extent(damaged.level, damaged.ijk);
  for (int64_t z = b0[2]; z <= b1[2]; ++z)
    for (int64_t y = b0[1]; y <= b1[1]; ++y)
      for (int64_t xi = b0[0]; xi <= b1[0]; ++xi) {
        const int64_t at[3] = {xi, y, z};
        float x[3];  // voxel coordinates of the sample
        for (int a = 0; a < 3; ++a)
          x[a] = float(f.partition().samplePosition(
              e, a, int(at[a] - g.start[size_t(a)][size_t(damaged.ijk[a])])));
        out[((z - lo[2]) * n[1] + (y - lo[1])) * n[0] + (xi - lo[0])] = standIns.valueAt(x);
      }
}

}  // namespace

void decodeLevelBox(const AfamFile& f, int level, const Index3& lo, const Index3& hi, float* out,
                    const std::function<void(double)>& progress,
                    std::vector<std::string>* damaged) {
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
  const double total =
      double(last[0] - first[0] + 1) * (last[1] - first[1] + 1) * (last[2] - first[2] + 1);
  double done = 0;
  std::vector<float> payload, dec;
  for (int k = first[2]; k <= last[2]; ++k)
    for (int j = first[1]; j <= last[1]; ++j)
      for (int i = first[0]; i <= last[0]; ++i) {
        const int64_t ei = f.entryIndex(level, {i, j, k});
        const ModelEntry& m = f.entries()[size_t(ei)];
        const int ijk[3] = {i, j, k};
        int64_t b0[3], b1[3];  // owned samples of the block inside the box, level-grid indices
        for (int a = 0; a < 3; ++a) {
          const auto& st = g.start[size_t(a)];
          const int64_t s0 = st[size_t(ijk[a])];
          const int64_t ownedEnd = ijk[a] + 1 < nb[a] ? st[size_t(ijk[a]) + 1] - 1 : g.dims[a] - 1;
          b0[a] = std::max(s0, lo[a]);
          b1[a] = std::min(ownedEnd, hi[a]);
        }
        payload.resize(m.size / 4);
        try {
          f.readPayload(ei, payload.data());
          decodeBlockSamples(m, payload.data(), f.header().mode, dec);
        } catch (const FormatError& e) {
          if (!damaged) throw;
          damaged->push_back(e.what());
          fillFromStandIns(f, g, BlockRef{level, Int3{i, j, k}, ei}, b0, b1, lo, n, out);
          if (progress) progress(++done / total);
          continue;
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

void clampToSourceRange(const AfamFile& file, float* values, size_t count) {
  const float lo = float(file.header().valueMin), hi = float(file.header().valueMax);
  if (!(lo <= hi)) return;
  for (size_t i = 0; i < count; ++i) values[i] = rc::clampf(values[i], lo, hi);  // NaN stays
}

}  // namespace afam
