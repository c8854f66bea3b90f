// SPDX-License-Identifier: BSD-3-Clause
#include "afam/render/renderer.hpp"

#include <algorithm>
#include <chrono>
#include <unordered_map>
#include <unordered_set>

#include "afam/base/errors.hpp"
#include "afam/predict/predictor_factory.hpp"

namespace afam {

using Clock = std::chrono::steady_clock;

static double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

namespace {

/// Floats of a placed model: its control points (a model in the stored form has none yet).
uint64_t modelFloats(const AfamFile& file, const Placement& m) {
  return m.data->isStored() ? uint64_t(controlCount(file.entries()[size_t(m.model.entry)]))
                            : m.data->size();
}

bool meetsBox(const Partition& p, const CellBox& box, int level, const Int3& ijk) {
  return !p.cells(level, ijk).intersection(box).empty();
}

/// Drops the blocks whose region lies outside a rank's `box` from `sel` (another rank's).
void keepInBox(const AfamFile& file, const CellBox& box, Selection& sel) {
  std::vector<BlockRef> kept;
  for (const BlockRef& b : sel.visible) {
    if (meetsBox(file.partition(), box, b.level, b.ijk)) {
      kept.push_back(b);
      continue;
    }
    const int64_t bytes = int64_t(file.entries()[size_t(b.entry)].size);
    sel.counts.otherRankBlocks++;
    sel.counts.otherRankBytes += bytes;
    sel.counts.visibleBlocks--;
    sel.counts.visibleBytes -= bytes;
  }
  sel.visible = std::move(kept);
}

}  // namespace

Renderer::Renderer(std::shared_ptr<const AfamFile> file, RendererResources resources,
                   FrameSettings settings, std::shared_ptr<DamageLog> damage)
    : file_(std::move(file)), resources_(std::move(resources)) {
  if (!file_) throw InvalidArgument("renderer: no file");
  if (resources_.threads < 0) throw InvalidArgument("renderer: threads must be >= 0");
  if (resources_.loadNice < 0 || resources_.loadNice > 19)
    throw InvalidArgument("renderer: the load threads' nice step must be 0..19");
  const VolumeHeader& h = file_->header();
  tfLo_ = h.valueMin;
  tfHi_ = h.valueMax > h.valueMin ? h.valueMax : h.valueMin + 1.0;
  setFrameSettings(settings);
  caster_ = std::make_unique<CpuCaster>(resources_.threads);
  cache_ = std::make_unique<LruCache>(file_, resources_.cache, std::move(damage));
  loader_ = std::make_unique<BlockLoader>(*cache_, resources_.loadThreads, resources_.loadNice);
  if (resources_.storageMBps > 0) cache_->setBandwidthCap(resources_.storageMBps * 1e6);
  prefetcher_ = std::make_unique<Prefetcher>(resources_.loadNice);
  // appa and forecache keep the transfer function and LOD settings they were built with (APPA's
  // table and ForeCache's visibility are computed for them): later edits change what is drawn,
  // not what they predict.
  PredictorContext ctx;
  ctx.file = file_;
  ctx.lod = settings_.lod;
  ctx.tfTable = tf_;
  ctx.tfLo = tfLo_;
  ctx.tfHi = tfHi_;
  predictor_ = makePrefetchPredictor(resources_.prefetch, ctx);
  // Finest boundaries per axis (voxel coordinates) from the partition's finest level.
  const Partition& p = file_->partition();
  const int finest = p.levels() - 1;
  const Int3 bf = p.blocksPerAxis(finest);
  for (int a = 0; a < 3; ++a) {
    bounds_[a].resize(size_t(bf[a]) + 1);
    for (int i = 0; i < bf[a]; ++i) {
      Int3 ijk{0, 0, 0};
      ijk[a] = i;
      const BlockExtent e = p.extent(finest, ijk);
      bounds_[a][size_t(i)] = float(e.lo[a]);
      bounds_[a][size_t(i) + 1] = float(e.hi[a]);
    }
  }
  if (resources_.box) box_ = resources_.box->intersection(CellBox{{0, 0, 0}, bf});
}

Renderer::~Renderer() {
  if (prefetcher_) prefetcher_->finish();
}

void Renderer::setFrameSettings(const FrameSettings& settings) {
  const std::string problem = frameSettingsProblem(settings);
  if (!problem.empty()) throw InvalidArgument("renderer: " + problem);
  FrameSettings next = settings;
  if (!next.hasTransferFunction) {  // the preset, with the NaN colour and opacity as given
    next.transferFunction = TransferFunction::preset(tfLo_, tfHi_);
    next.transferFunction.nanColor = settings.transferFunction.nanColor;
    next.transferFunction.nanOpacity = settings.transferFunction.nanOpacity;
  }
  tf_ = next.transferFunction.table(next.tfTableSize, tfLo_, tfHi_);
  lod_ = LodSelector(next.lod);
  settings_ = std::move(next);
}

Selection Renderer::select(const Camera& camera) const {
  static const std::vector<float> none;
  Selection sel = lod_.select(*file_, camera, settings_.blendMode == kBlendComposite ? tf_ : none,
                              tfLo_, tfHi_, settings_.transferFunction.nanOpacity > 0);
  if (box_) keepInBox(*file_, *box_, sel);
  return sel;
}

std::vector<int64_t> Renderer::inBox(const std::vector<int64_t>& entries) const {
  if (!box_) return entries;
  std::vector<int64_t> kept;
  for (int64_t e : entries) {
    const ModelEntry& m = file_->entries()[size_t(e)];
    if (meetsBox(file_->partition(), *box_, m.level, m.block)) kept.push_back(e);
  }
  return kept;
}

void Renderer::prepareEmpty(const Camera& camera, PreparedFrame& fr) const {
  const Partition& p = file_->partition();
  const Int3 bf = p.blocksPerAxis(p.levels() - 1);
  FrameView& v = fr.view;
  v = FrameView{};
  v.camera = camera.toRayCamera();
  for (int a = 0; a < 3; ++a) {
    const double n1 = double(p.dims()[a] - 1);
    v.boxLo[a] = -1.f;
    v.boxHi[a] = 1.f;
    v.voxelPerUnit[a] = float(n1 / 2.0);
    v.voxelMax[a] = float(n1);
    v.gridDims[a] = bf[a];
    v.cellPerVoxel[a] = n1 > 0 ? float(double(bf[a]) / n1) : 0.f;
    fr.cellBounds[a] = bounds_[a];
  }
  fr.cellSlot.assign(size_t(bf[0]) * bf[1] * bf[2], -1);
  fr.slots.clear();
  fr.pool.clear();
  fr.entries.clear();
  fr.keys.clear();
  fr.models.clear();
  fr.slotHost.clear();
  // Opacity corrected for the sample distance once per frame, not per sample.
  fr.tf = tf_;
  const float ratio =
      float(double(settings_.sampleDistance) / settings_.transferFunction.referenceDistance);
  // Compositing uses opacities per sample step; the projections use the table's own opacity.
  const TransferFunction& tf = settings_.transferFunction;
  v.nanOpacity = float(tf.nanOpacity);
  if (settings_.blendMode == kBlendComposite) {
    for (size_t i = 3; i < fr.tf.size(); i += 4) fr.tf[i] = correctOpacity(fr.tf[i], ratio);
    v.nanOpacity = correctOpacity(v.nanOpacity, ratio);
  }
  for (int a = 0; a < 3; ++a) v.nanColor[a] = float(tf.nanColor[size_t(a)]);
  v.blendMode = settings_.blendMode;
  v.tfMin = float(tfLo_);
  v.tfMax = float(tfHi_);
  v.tfReferenceDistance = settings_.sampleDistance;
  v.sampleDistance = settings_.sampleDistance;
  v.terminationOpacity = settings_.terminationOpacity;
  v.shading = settings_.shading ? 1 : 0;
  v.jitter = settings_.jitter ? 1 : 0;
  // Splines: one value+gradient evaluation per shaded sample is cheaper (H200, ae8b2c9). Raw DS
  // blocks: a gradient is six more trilinear fetches, so only visible samples pay for it.
  v.gradientWithValue = file_->header().mode == EncodingMode::Downsampled ? 0 : 1;
  v.ambient = settings_.ambient;
  v.diffuse = settings_.diffuse;
  v.specular = settings_.specular;
  v.specularPower = settings_.specularPower;
  fr.bind();
}

int32_t Renderer::addSlot(const BlockRef& model, PreparedFrame& fr, uint64_t offset) const {
  fr.slots.push_back(modelSlot(*file_, model, offset));
  fr.entries.push_back(model.entry);
  fr.keys.push_back(modelKey(file_->entries()[size_t(model.entry)]));
  return int32_t(fr.slots.size() - 1);
}

void Renderer::fillCells(const BlockRef& region, int32_t slot, PreparedFrame& fr) const {
  const Partition& p = file_->partition();
  const Int3 bf = p.blocksPerAxis(p.levels() - 1);
  const CellBox c = p.cells(region.level, region.ijk);
  for (int z = c.lo[2]; z < c.hi[2]; ++z)
    for (int y = c.lo[1]; y < c.hi[1]; ++y)
      for (int x = c.lo[0]; x < c.hi[0]; ++x)
        fr.cellSlot[(size_t(z) * bf[1] + y) * bf[0] + x] = slot;
}

void Renderer::prepare(const Camera& camera, PreparedFrame& fr, FrameStats& st, bool hostPool) {
  const auto t0 = Clock::now();
  // A file changed on disk ends this renderer's frames (FileChangedError): its cache holds blocks
  // of the old file, which must not be drawn beside blocks of the new one.
  file_->checkUnchanged();
  const CacheStats before = cache_->stats();
  const Selection sel = select(camera);
  st.selectMs = msSince(t0);
  st.culled = sel.counts;
  prepareEmpty(camera, fr);
  const Clock::time_point deadline =
      settings_.missBudgetMs < 0 ? Clock::time_point::max()
                                 : t0 + std::chrono::microseconds(int64_t(
                                            tailReserve_.waitMs(settings_.missBudgetMs) * 1e3));
  const std::vector<Placement> placed = loadModels(sel, camera, st, deadline);
  // One slot per model: a coarser model standing in for several damaged blocks is stored once
  // (the GPU pool keys its models by entry) and covers each of their regions.
  std::unordered_map<int64_t, int32_t> slotOf;
  uint64_t poolFloats = 0;
  for (const Placement& m : placed)
    if (slotOf.emplace(m.model.entry, -1).second) poolFloats += modelFloats(*file_, m);
  if (hostPool) fr.pool.resize(poolFloats);
  fr.slots.reserve(slotOf.size());
  uint64_t offset = 0;
  for (const Placement& m : placed) {
    int32_t& slot = slotOf[m.model.entry];
    if (slot < 0) {
      const ModelEntry& e = file_->entries()[size_t(m.model.entry)];
      const uint64_t floats = modelFloats(*file_, m);
      if (hostPool) writeModel(e, *m.data, fr.pool.data() + offset, floats);
      slot = addSlot(m.model, fr, offset);
      setCompactForm(m.data->compact, fr.slots.back());
      fr.models.push_back(m.data);
      fr.slotHost.push_back(m.data->isStored() ? nullptr : m.data->data());
      fr.slotEntries.push_back(&e);
      offset += floats;
    }
    fillCells(m.region, slot, fr);
  }
  fr.bind();
  if (box_) clipFrameToBox(fr, *box_);
  const CacheStats after = cache_->stats();
  st.hits = after.hits - before.hits;
  st.misses = after.misses - before.misses;
  st.slots = int64_t(fr.slots.size());
  st.poolBytes = poolFloats * sizeof(float);
  st.damageReports = cache_->damage().takeReports();
  st.loadErrors = loader_->takeErrors();
  st.knownDamagedBlocks = int64_t(cache_->damage().count());
  st.cachingMs = msSince(t0);
  if (settings_.missBudgetMs >= 0) tailReserve_.observe(msSince(waitEnd_));
}

void Renderer::setStep(std::shared_ptr<const AfamFile> step) {
  if (!step) throw InvalidArgument("renderer: no file");
  if (step == file_) return;
  cache_->setFile(step);  // checks that it is a step of the same run
  file_ = std::move(step);
  residentReady_ = false;  // the new step's resident levels, loaded by its first budgeted frame
}

void Renderer::setNextStep(std::shared_ptr<const AfamFile> next) {
  if (next && (next->path() != file_->path() || next->entries().size() != file_->entries().size()))
    throw InvalidArgument("renderer: the next step is not a step of " + file_->path());
  next_ = std::move(next);
}

void Renderer::setCaster(std::unique_ptr<FrameCaster> caster) {
  caster_ = caster ? std::move(caster) : std::make_unique<CpuCaster>(resources_.threads);
}

ImageRGBA Renderer::renderFrame(const Camera& camera, const FrameSettings& settings, FrameStats& st,
                                const FrameTargets& targets) {
  setFrameSettings(settings);
  return renderFrame(camera, st, targets);
}

ImageRGBA Renderer::renderFrame(const Camera& camera, const FrameSettings& settings, FrameStats& st,
                                const float* maxDistance) {
  setFrameSettings(settings);
  return renderFrame(camera, st, maxDistance);
}

ImageRGBA Renderer::renderFrame(const Camera& camera, FrameStats& st, const float* maxDistance) {
  FrameTargets targets;
  targets.maxDistance = maxDistance;
  return renderFrame(camera, st, targets);
}

ImageRGBA Renderer::renderFrame(const Camera& camera, FrameStats& st, const FrameTargets& targets) {
  st = FrameStats{};
  cache_->takePeakResidentBytes();  // the frame's peak starts here
  if (resources_.cold) cache_->dropOsCache();
  const CacheStats before = cache_->stats();
  PreparedFrame fr;
  cache_->setStoredForm(caster_->storedForm());  // null again once a GPU caster has failed
  cache_->setCompactForm(resources_.compactModels && caster_->readsCompactForm());
  prepare(camera, fr, st, caster_->readsHostPool());
  history_.push_back(camera);
  if (history_.size() > kPredictorHistory) history_.erase(history_.begin());
  // Prefetch the predicted next view while this one renders. The prediction runs in the prefetch
  // thread (off the frame's critical path); predictors that know the blocks directly (APPA's
  // table, ForeCache's signature ranking) hand them over without a view selection. The blocks
  // are loaded by the load threads, most important first, until the frame is done.
  if (resources_.prefetch != "none") {
    BlockLoader* loader = loader_.get();
    const Renderer* self = this;
    const Predictor* predictor = predictor_.get();
    prefetcher_->start(
        [loader, self, predictor, history = history_](const std::atomic<bool>& stop, uint64_t&) {
          std::vector<int64_t> entries;
          if (!predictor->predictEntries(history, entries)) {
            Camera next;
            if (!predictor->predict(history, next)) return;
            for (const BlockRef& b : self->select(next).visible) entries.push_back(b.entry);
          }
          entries = self->inBox(entries);  // a predictor's own blocks: the rank's only
          if (!stop.load(std::memory_order_acquire))
            loader->request(entries, LruCache::Purpose::Prefetch);
        });
  }
  // The next step's models of this view, loaded while this step is shown (after every load this
  // frame and its prefetching ask for; they go on after the frame).
  if (next_ && next_ != file_) loader_->requestStep(next_, fr.entries);
  const auto t0 = Clock::now();
  ImageRGBA image;
  st.cast = caster_->cast(fr, targets, image);
  st.renderMs = msSince(t0);
  prefetcher_->finish();      // the paper's rendering_done: prefetching stops with the frame
  loader_->cancelPrefetch();  // (a load under way completes)
  cache_->clearPinned();
  for (const auto& [entry, why] : st.cast.damaged) cache_->damage().record(*file_, entry, why);
  for (std::string& r : cache_->damage().takeReports()) st.damageReports.push_back(std::move(r));
  st.knownDamagedBlocks = int64_t(cache_->damage().count());
  const CacheStats after = cache_->stats();
  st.bytesRead = after.bytesRead - before.bytesRead;
  st.prefetchedBlocks = after.prefetchLoads - before.prefetchLoads;
  st.prefetchedBytes = after.prefetchBytes - before.prefetchBytes;
  st.latencyMs = st.cachingMs + st.renderMs;
  st.cachePeakBytes = cache_->takePeakResidentBytes();
  st.cacheBytes = cache_->residentBytes();
  return image;
}

}  // namespace afam
