// SPDX-License-Identifier: BSD-3-Clause
// afam_eval: the measurement programs behind scripts/evaluate.sh that the `afam`
// command line does not cover. Every sub-command writes one CSV.
//
//   afam_eval quality  --trajectory T --view I|auto --size N --sd a,b,.. --csv OUT
//                      [--device cpu|gpu] LABEL=FILE...
//       image MSE/PSNR/SSIM against the analytic Marschner-Lobb ray cast, and frame time, per
//       file and sample distance, at one view (auto: the first view whose visible cut holds
//       blocks of every level: the paper's cross-level view). --device gpu times the CUDA ray
//       caster (the ground truth stays the CPU's analytic cast); the CSV's last column says which
//       device rendered each row.
//   afam_eval compress --codec zfp|fpzip --param X DS.afam OUT.afam
//       ZFP (fixed rate, bits/value) or fpzip (precision bits) over the DS file's micro-blocks
//       without their ghost layer; decompressed on load into a DS file (ghost layer re-made by
//       clamping the decompressed block) that `afam render`/quality render trilinearly.
//   afam_eval stability --csv OUT [--chi RAW]   BlockFitter stiff and extreme cases
//   afam_eval seams --csv OUT LABEL=FILE...     largest value jump across shared block faces
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/eval/ground_truth.hpp"
#include "afam/eval/image_metrics.hpp"
#include "afam/eval/png_io.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/render/cpu_raycaster.hpp"
#include "afam/render/renderer.hpp"
#include "afam/scene/camera.hpp"
#include "afam/spline/evaluate.hpp"
#include "afam/spline/fit.hpp"
#include "afam/volume/marschner_lobb.hpp"
#include "device_option.hpp"
#include "zfp_codec.hpp"

#ifdef AFAM_EVAL_HAVE_FPZIP
#include <fpzip.h>
#endif

using namespace afam;
using Clock = std::chrono::steady_clock;

namespace {

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

struct Opts {
  std::map<std::string, std::string> kv;
  std::vector<std::string> pos;
  Opts(int argc, char** argv, int first) {
    for (int i = first; i < argc; ++i) {
      std::string a = argv[i];
      if (a.rfind("--", 0) == 0) {
        if (i + 1 >= argc) throw std::runtime_error(a + " needs a value");
        kv[a.substr(2)] = argv[++i];
      } else {
        pos.push_back(a);
      }
    }
  }
  std::string str(const std::string& k, const std::string& d = "") const {
    auto it = kv.find(k);
    return it == kv.end() ? d : it->second;
  }
  bool has(const std::string& k) const { return kv.count(k) != 0; }
};

std::vector<std::string> split(const std::string& s, char c) {
  std::vector<std::string> out;
  size_t b = 0;
  while (b <= s.size()) {
    size_t e = s.find(c, b);
    if (e == std::string::npos) e = s.size();
    if (e > b) out.push_back(s.substr(b, e - b));
    b = e + 1;
  }
  return out;
}

std::pair<std::string, std::string> labelled(const std::string& s) {
  const size_t eq = s.find('=');
  if (eq == std::string::npos) return {s, s};
  return {s.substr(0, eq), s.substr(eq + 1)};
}

int levelsVisible(const Selection& s, int levels) {
  std::set<int> seen;
  for (const auto& b : s.visible) seen.insert(b.level);
  (void)levels;
  return int(seen.size());
}

// ------------------------------------------------------------------------------------- quality
int runQuality(const Opts& o) {
  const auto poses = loadTrajectory(o.str("trajectory"));
  const int size = std::atoi(o.str("size", "128").c_str());
  const int threads = std::atoi(o.str("threads", "0").c_str());
  const int repeats = std::max(1, std::atoi(o.str("repeats", "2").c_str()));
  const std::string device = o.str("device", "cpu");
  std::vector<double> sds;
  for (const auto& s : split(o.str("sd", "0.005"), ',')) sds.push_back(std::atof(s.c_str()));
  if (o.pos.empty()) throw std::runtime_error("quality: no LABEL=FILE given");
  auto first = AfamFile::open(labelled(o.pos[0]).second);
  const int L = first->header().levels;
  int view = -1;
  const std::string vs = o.str("view", "auto");
  if (vs == "auto") {
    RenderOptions ro;
    Renderer r(first, ro);
    for (size_t i = 0; i < poses.size(); ++i) {
      if (levelsVisible(r.select(Camera::fromPose(poses[i], size, size)), L) == L) {
        view = int(i);
        break;
      }
    }
    if (view < 0) view = 0;
  } else {
    view = std::atoi(vs.c_str());
  }
  const Camera cam = Camera::fromPose(poses.at(size_t(view)), size, size);
  std::FILE* csv = std::fopen(o.str("csv").c_str(), "w");
  if (!csv) throw std::runtime_error("cannot write " + o.str("csv"));
  std::fprintf(csv,
               "label,file,mode,view,levels_visible,sample_distance,blocks,payload_bytes,file_"
               "payload_bytes,raw_block_bytes,ratio,"
               "caching_ms,render_ms,mse,psnr,ssim,device\n");
  const std::string imgDir = o.str("images");
  for (double sd : sds) {
    RenderOptions ro;
    ro.sampleDistance = float(sd);
    ro.threads = threads;
    ro.cache = CacheBudget{0, 0};  // unlimited: quality runs measure the representation
    ImageRGB8 gtRgb;
    {
      Renderer r(first, ro);
      PreparedFrame fr;
      r.prepareEmpty(cam, fr);
      ImageRGBA gt;
      renderCpuWith(fr.view, MarschnerLobbSampler{}, gt, threads);
      gtRgb = toRGB8(gt);
      if (!imgDir.empty()) writePng(imgDir + "/gt_sd" + std::to_string(sd) + ".png", gtRgb);
    }
    for (const auto& arg : o.pos) {
      const auto lf = labelled(arg);
      auto file = AfamFile::open(lf.second);
      uint64_t filePayload = 0, rawBlocks = 0;
      for (const auto& e : file->entries()) {
        filePayload += e.size;
        rawBlocks += uint64_t(e.samples[0]) * uint64_t(e.samples[1]) * uint64_t(e.samples[2]) * 4u;
      }
      Renderer r(file, ro);
      const cli::DeviceChoice dev = cli::useDevice(r, device, 4096);
      FrameStats st;
      ImageRGBA img = r.renderFrame(cam, st);  // cold: loads the models
      cli::printDeviceMessages(st);
      const double caching = st.cachingMs;
      double best = std::numeric_limits<double>::infinity();
      for (int k = 0; k < repeats; ++k) {
        FrameStats s2;
        img = r.renderFrame(cam, s2);
        cli::printDeviceMessages(s2);
        best = std::min(best, s2.renderMs);
      }
      const ImageRGB8 rgb = toRGB8(img);
      if (!imgDir.empty())
        writePng(imgDir + "/" + lf.first + "_sd" + std::to_string(sd) + ".png", rgb);
      const ImageErrors e = compare(rgb, gtRgb);
      const int lv = levelsVisible(r.select(cam), file->header().levels);
      std::fprintf(csv,
                   "%s,%s,%s,%d,%d,%.8g,%lld,%llu,%llu,%llu,%.4f,%.4f,%.4f,%.8g,%.6f,%.6f,%s\n",
                   lf.first.c_str(), lf.second.c_str(), modeName(file->header().mode), view, lv, sd,
                   (long long)st.slots, (unsigned long long)st.poolBytes,
                   (unsigned long long)filePayload, (unsigned long long)rawBlocks,
                   double(rawBlocks) / double(std::max<uint64_t>(filePayload, 1)), caching, best,
                   e.mse, e.psnr, e.ssim, dev.used.c_str());
      std::fflush(csv);
      std::printf("%s sd=%g view=%d levels=%d render_ms=%.2f psnr=%.3f ssim=%.4f\n",
                  lf.first.c_str(), sd, view, lv, best, e.psnr, e.ssim);
    }
  }
  std::fclose(csv);
  return 0;
}

// ------------------------------------------------------------------------------------ compress
// Interior (no ghost) samples of a DS payload: payload dims s+2 per axis.
void interiorOf(const ModelEntry& m, const std::vector<float>& payload, std::vector<float>& out) {
  const int nx = m.samples[0], ny = m.samples[1], nz = m.samples[2];
  const int px = m.ncp[0], py = m.ncp[1];
  out.resize(size_t(nx) * ny * nz);
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x)
        out[(size_t(z) * ny + y) * nx + x] = payload[(size_t(z + 1) * py + (y + 1)) * px + (x + 1)];
}

void withClampedGhost(const ModelEntry& m, const std::vector<float>& in,
                      std::vector<float>& payload) {
  const int nx = m.samples[0], ny = m.samples[1], nz = m.samples[2];
  const int px = m.ncp[0], py = m.ncp[1], pz = m.ncp[2];
  payload.resize(size_t(px) * py * pz);
  for (int z = 0; z < pz; ++z)
    for (int y = 0; y < py; ++y)
      for (int x = 0; x < px; ++x) {
        const int cx = std::clamp(x - 1, 0, nx - 1), cy = std::clamp(y - 1, 0, ny - 1),
                  cz = std::clamp(z - 1, 0, nz - 1);
        payload[(size_t(z) * py + y) * px + x] = in[(size_t(cz) * ny + cy) * nx + cx];
      }
}

// Compresses `in` (nx*ny*nz floats), returns compressed bytes; `out` gets the decompressed data,
// decompression time is added to decMs.
size_t codecRoundTrip(const std::string& codec, double param, const std::vector<float>& in, int nx,
                      int ny, int nz, std::vector<float>& out, double& decMs) {
  out.assign(in.size(), 0.f);
  if (codec == "zfp") {
    const ZfpRoundTrip z = zfpRoundTrip(ZfpMode::FixedRate, param, in.data(), size_t(nx),
                                        size_t(ny), size_t(nz), out.data());
    decMs += 1000.0 * z.decompressSeconds;
    return z.bytes;
  }
#ifdef AFAM_EVAL_HAVE_FPZIP
  if (codec == "fpzip") {
    std::vector<unsigned char> buf(in.size() * sizeof(float) * 2 + 1024);
    FPZ* fpz = fpzip_write_to_buffer(buf.data(), buf.size());
    fpz->type = FPZIP_TYPE_FLOAT;
    fpz->prec = int(param);
    fpz->nx = nx;
    fpz->ny = ny;
    fpz->nz = nz;
    fpz->nf = 1;
    if (!fpzip_write_header(fpz)) throw std::runtime_error("fpzip header failed");
    const size_t bytes = fpzip_write(fpz, in.data());
    fpzip_write_close(fpz);
    if (!bytes) throw std::runtime_error("fpzip_write failed");
    const auto t0 = Clock::now();
    FPZ* rd = fpzip_read_from_buffer(buf.data());
    if (!fpzip_read_header(rd)) throw std::runtime_error("fpzip read header failed");
    if (!fpzip_read(rd, out.data())) throw std::runtime_error("fpzip_read failed");
    fpzip_read_close(rd);
    decMs += msSince(t0);
    return bytes;
  }
#endif
  (void)param;
  (void)nx;
  (void)ny;
  (void)nz;
  (void)decMs;
  throw std::runtime_error("codec '" + codec +
                           "' not built in (zfp/fpzip need libzfp-dev/libfpzip-dev)");
}

int runCompress(const Opts& o) {
  if (o.pos.size() != 2) throw std::runtime_error("compress: DS.afam OUT.afam");
  const std::string codec = o.str("codec", "zfp");
  const double param = std::atof(o.str("param", "1.6").c_str());
  auto f = AfamFile::open(o.pos[0]);
  if (f->header().mode != EncodingMode::Downsampled)
    throw std::runtime_error("compress: input must be a ds file");
  AfamWriter w(o.pos[1], f->header());
  size_t rawBytes = 0, compBytes = 0;
  double decMs = 0, sumSq = 0;
  size_t count = 0;
  std::vector<float> interior, dec, payload;
  for (int64_t i = 0; i < int64_t(f->entries().size()); ++i) {
    ModelEntry m = f->entries()[size_t(i)];
    const std::vector<float> p = f->readPayload(i);
    interiorOf(m, p, interior);
    compBytes += codecRoundTrip(codec, param, interior, m.samples[0], m.samples[1], m.samples[2],
                                dec, decMs);
    rawBytes += interior.size() * sizeof(float);
    float mn = std::numeric_limits<float>::infinity(), mx = -mn;
    double bs = 0, be = 0;
    for (size_t k = 0; k < dec.size(); ++k) {
      const double d = double(dec[k]) - double(interior[k]);
      bs += d * d;
      be = std::max(be, std::fabs(d));
      mn = std::min(mn, dec[k]);
      mx = std::max(mx, dec[k]);
    }
    sumSq += bs;
    count += dec.size();
    withClampedGhost(m, dec, payload);
    m.minValue = mn;
    m.maxValue = mx;
    m.rmse = float(std::sqrt(bs / double(std::max<size_t>(dec.size(), 1))));
    m.maxError = float(be);
    w.add(m, payload.data());
  }
  w.commit();
  const size_t blocks = f->entries().size();
  std::printf(
      "codec=%s param=%g blocks=%zu raw_bytes=%zu compressed_bytes=%zu ratio=%.4f rmse=%.6g "
      "decompress_ms_total=%.4f decompress_us_per_block=%.4f\n",
      codec.c_str(), param, blocks, rawBytes, compBytes, double(rawBytes) / double(compBytes),
      std::sqrt(sumSq / double(std::max<size_t>(count, 1))), decMs,
      1000.0 * decMs / double(blocks));
  return 0;
}

// ----------------------------------------------------------------------------------- stability
struct Case {
  std::string name;
  std::array<int, 3> n;
  int ncp, degree;
  std::vector<float> data;
};

void stabilityRow(std::FILE* csv, BlockFitter& fitter, const Case& c) {
  double dmin = std::numeric_limits<double>::infinity(), dmax = -dmin, amax = 0;
  for (float v : c.data) {
    dmin = std::min(dmin, double(v));
    dmax = std::max(dmax, double(v));
    amax = std::max(amax, std::fabs(double(v)));
  }
  std::array<int, 3> ncp{}, deg{};
  for (int a = 0; a < 3; ++a) deg[a] = effectiveDegree(c.degree, c.n[a]);
  ncp = clampNcp(c.ncp, c.n, deg);
  std::string status = "ok";
  double maxErr = NAN, rmse = NAN, overshoot = NAN;
  long long nans = 0;
  try {
    FitResult r = fitter.fit(c.data.data(), c.n, ncp, c.degree, true);
    maxErr = r.error.maxError;
    rmse = r.error.rmse;
    for (float v : r.control) nans += !std::isfinite(v);
    // Overshoot: model beyond the data's range, evaluated at samples and midpoints (2n-1 per axis).
    const ModelView mv = r.view();
    double omax = 0;
    const int mx = 2 * c.n[0] - 1, my = 2 * c.n[1] - 1, mz = 2 * c.n[2] - 1;
    const int step = std::max(1, (mx * my * mz) / 400000);
    long long idx = 0;
    for (int z = 0; z < mz; ++z)
      for (int y = 0; y < my; ++y)
        for (int x = 0; x < mx; ++x, ++idx) {
          if (idx % step) continue;
          const float u = mx > 1 ? float(x) / float(mx - 1) : 0.f,
                      v = my > 1 ? float(y) / float(my - 1) : 0.f,
                      w = mz > 1 ? float(z) / float(mz - 1) : 0.f;
          const float val = evaluateModel<false>(mv, u, v, w, nullptr);
          if (!std::isfinite(val)) {
            ++nans;
            continue;
          }
          omax = std::max(omax, std::max(double(val) - dmax, dmin - double(val)));
        }
    overshoot = omax;
  } catch (const std::exception& e) {
    status = std::string("refused: ") + e.what();
    for (char& ch : status)
      if (ch == ',' || ch == '\n') ch = ';';
  }
  double cond = 0;
  for (int a = 0; a < 3; ++a)
    cond = std::max(cond, axisConditioning(c.n[a], ncp[a], c.degree).normal);
  const double scale = amax > 0 ? amax : 1;
  std::fprintf(csv, "%s,%dx%dx%d,%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%lld,%s\n", c.name.c_str(),
               c.n[0], c.n[1], c.n[2], ncp[0], c.degree, amax, maxErr, maxErr / scale, rmse,
               overshoot, cond, nans, status.c_str());
  std::printf("%-28s max_err=%.3g rel=%.3g overshoot=%.3g cond=%.3g nan=%lld %s\n", c.name.c_str(),
              maxErr, maxErr / scale, overshoot, cond, nans, status.c_str());
}

std::vector<float> mlBlock(std::array<int, 3> n, double scale, double offset) {
  MarschnerLobb ml;
  std::vector<float> d(static_cast<size_t>(n[0]) * n[1] * n[2]);
  for (int z = 0; z < n[2]; ++z)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x) {
        const double px = -1 + 2.0 * x / std::max(1, n[0] - 1),
                     py = -1 + 2.0 * y / std::max(1, n[1] - 1),
                     pz = -1 + 2.0 * z / std::max(1, n[2] - 1);
        d[(size_t(z) * n[1] + y) * n[0] + x] =
            float(offset + scale * ml.valueT<double>(px, py, pz));
      }
  return d;
}

int runStability(const Opts& o) {
  std::FILE* csv = std::fopen(o.str("csv").c_str(), "w");
  if (!csv) throw std::runtime_error("cannot write " + o.str("csv"));
  std::fprintf(csv,
               "case,n,ncp,degree,max_abs_value,max_error,rel_max_error,rmse,overshoot,cond_normal,"
               "nan_count,status\n");
  BlockFitter fitter;
  std::vector<Case> cases;
  const std::array<int, 3> line{128, 8, 8};
  for (int p = 1; p <= 3; ++p)
    cases.push_back({"ncp_eq_n_n128_p" + std::to_string(p), line, 128, p, mlBlock(line, 1, 0)});
  const std::array<int, 3> b{32, 32, 32};
  const size_t nb = size_t(32) * 32 * 32;
  {
    std::vector<float> d(nb);
    for (size_t i = 0; i < nb; ++i) d[i] = (i % 32) < 16 ? 0.f : 1.f;
    cases.push_back({"step_ncp16", b, 16, 2, d});
    cases.push_back({"step_ncp_eq_n", b, 32, 2, d});
  }
  {
    std::vector<float> d(nb, 0.f);
    d[(size_t(16) * 32 + 16) * 32 + 16] = 1.f;
    cases.push_back({"spike_ncp16", b, 16, 2, d});
    cases.push_back({"spike_ncp_eq_n", b, 32, 2, d});
  }
  cases.push_back({"ml_scaled_1e30", b, 16, 2, mlBlock(b, 1e30, 0)});
  cases.push_back({"ml_scaled_1e-30", b, 16, 2, mlBlock(b, 1e-30, 0)});
  cases.push_back({"ml_denormal_1e-40", b, 16, 2, mlBlock(b, 1e-40, 0)});
  {
    std::vector<float> d(nb);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    for (auto& v : d) v = u(rng) * 1e20f;
    cases.push_back({"random_mixed_signs_1e20", b, 16, 2, d});
    cases.push_back({"ml_mixed_signs", b, 16, 2, mlBlock(b, 2, -1)});
  }
  {
    std::vector<float> d(nb, 1.f);
    d[5] = std::numeric_limits<float>::quiet_NaN();
    cases.push_back({"nan_sample", b, 16, 2, d});
  }
  const std::string chi = o.str("chi");
  if (!chi.empty()) {
    std::ifstream in(chi, std::ios::binary);
    std::vector<float> d(size_t(50) * 50 * 50);
    if (!in) throw std::runtime_error("stability: cannot open --chi file " + chi);
    in.read(reinterpret_cast<char*>(d.data()), std::streamsize(d.size() * 4));
    if (!in)
      throw std::runtime_error("stability: --chi file " + chi +
                               " holds fewer than 50^3 float32 values");
    cases.push_back({"chi_field_ncp25", {50, 50, 50}, 25, 2, d});
    cases.push_back({"chi_field_ncp_eq_n", {50, 50, 50}, 50, 2, d});
    cases.push_back({"chi_field_ncp_eq_n_p3", {50, 50, 50}, 50, 3, d});
  }
  for (const auto& c : cases) stabilityRow(csv, fitter, c);
  std::fclose(csv);
  return 0;
}

// --------------------------------------------------------------------------------------- seams
// Largest jump between two decoded models at the same points: (a) same level, neighbours share
// their boundary samples; (b) across levels, a coarse block against the children of its coarse
// neighbour along the shared face (the situation at an LOD transition of the cut).
struct Decoded {
  std::vector<float> control;
  ModelView view;
  ModelEntry entry;
  BlockExtent ext;
};

float evalAt(const Decoded& d, const Partition& p, const double pos[3], EncodingMode mode) {
  float uvw[3];
  for (int a = 0; a < 3; ++a) {
    const double lo = double(d.ext.lo[a]), hi = double(d.ext.hi[a]);
    uvw[a] = hi > lo ? float((pos[a] - lo) / (hi - lo)) : 0.f;
    uvw[a] = std::clamp(uvw[a], 0.f, 1.f);
  }
  (void)p;
  if (mode != EncodingMode::Downsampled)
    return evaluateModel<false>(d.view, uvw[0], uvw[1], uvw[2], nullptr);
  // DS: trilinear on the interior samples (payload has a ghost layer).
  const ModelEntry& m = d.entry;
  float g[3];
  int i0[3];
  float t[3];
  for (int a = 0; a < 3; ++a) {
    g[a] = uvw[a] * float(std::max(m.samples[a] - 1, 0));
    i0[a] = std::min(int(g[a]), std::max(m.samples[a] - 2, 0));
    t[a] = m.samples[a] > 1 ? g[a] - float(i0[a]) : 0.f;
  }
  auto at = [&](int x, int y, int z) {
    x = std::min(x, m.samples[0] - 1);
    y = std::min(y, m.samples[1] - 1);
    z = std::min(z, m.samples[2] - 1);
    return d.control[(size_t(z + 1) * m.ncp[1] + (y + 1)) * m.ncp[0] + (x + 1)];
  };
  float v = 0;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const float w = (dx ? t[0] : 1 - t[0]) * (dy ? t[1] : 1 - t[1]) * (dz ? t[2] : 1 - t[2]);
    v += w * at(i0[0] + dx, i0[1] + dy, i0[2] + dz);
  }
  return v;
}

int runSeams(const Opts& o) {
  std::FILE* csv = std::fopen(o.str("csv").c_str(), "w");
  if (!csv) throw std::runtime_error("cannot write " + o.str("csv"));
  std::fprintf(csv,
               "label,mode,value_range,same_level_max_jump,same_level_rel,cross_level_max_jump,"
               "cross_level_rel,faces_same,faces_cross\n");
  for (const auto& arg : o.pos) {
    const auto lf = labelled(arg);
    auto f = AfamFile::open(lf.second);
    const Partition& p = f->partition();
    const EncodingMode mode = f->header().mode;
    std::vector<Decoded> dec(f->entries().size());
    for (size_t i = 0; i < dec.size(); ++i) {
      Decoded& d = dec[i];
      d.entry = f->entries()[i];
      d.control = f->readPayload(int64_t(i));
      for (int a = 0; a < 3; ++a) d.view.knots[a] = Knots::make(d.entry.ncp[a], d.entry.degree[a]);
      d.view.control = d.control.data();
      d.ext = p.extent(d.entry.level, d.entry.block);
    }
    double same = 0, cross = 0;
    long long nSame = 0, nCross = 0;
    for (int l = 0; l < p.levels(); ++l) {
      const Int3 nbl = p.blocksPerAxis(l);
      for (int64_t li = 0; li < p.blockCount(l); ++li) {
        const Int3 ijk = p.blockFromLinear(l, li);
        const Decoded& A = dec[size_t(f->entryIndex(l, ijk))];
        for (int a = 0; a < 3; ++a) {
          if (ijk[a] + 1 >= nbl[a]) continue;
          Int3 nj = ijk;
          nj[a] += 1;
          const Decoded& B = dec[size_t(f->entryIndex(l, nj))];
          // Same level: the shared face at A's last sample along a, sampled at A's samples.
          const int b1 = (a + 1) % 3, b2 = (a + 2) % 3;
          ++nSame;
          for (int s1 = 0; s1 < A.entry.samples[b1]; ++s1)
            for (int s2 = 0; s2 < A.entry.samples[b2]; ++s2) {
              double pos[3];
              pos[a] = double(A.ext.hi[a]);
              pos[b1] = p.samplePosition(A.ext, b1, s1);
              pos[b2] = p.samplePosition(A.ext, b2, s2);
              same = std::max(same,
                              double(std::fabs(evalAt(A, p, pos, mode) - evalAt(B, p, pos, mode))));
            }
          // Cross level: A against the finer children of B that touch the face.
          if (l + 1 < p.levels()) {
            for (const Int3& c : p.children(l, nj)) {
              const Decoded& F = dec[size_t(f->entryIndex(l + 1, c))];
              if (F.ext.lo[a] != A.ext.hi[a]) continue;
              ++nCross;
              for (int s1 = 0; s1 < F.entry.samples[b1]; ++s1)
                for (int s2 = 0; s2 < F.entry.samples[b2]; ++s2) {
                  double pos[3];
                  pos[a] = double(F.ext.lo[a]);
                  pos[b1] = p.samplePosition(F.ext, b1, s1);
                  pos[b2] = p.samplePosition(F.ext, b2, s2);
                  cross = std::max(
                      cross, double(std::fabs(evalAt(A, p, pos, mode) - evalAt(F, p, pos, mode))));
                }
            }
          }
        }
      }
    }
    const double range = std::max(1e-300, f->header().valueMax - f->header().valueMin);
    std::fprintf(csv, "%s,%s,%.8g,%.6g,%.6g,%.6g,%.6g,%lld,%lld\n", lf.first.c_str(),
                 modeName(mode), range, same, same / range, cross, cross / range, nSame, nCross);
    std::printf("%s same=%.4g (%.3g of range) cross=%.4g (%.3g of range)\n", lf.first.c_str(), same,
                same / range, cross, cross / range);
  }
  std::fclose(csv);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help") {
    std::printf(
        "usage: afam_eval quality|compress|stability|seams [options]  (see the header of "
        "Apps/evaluation/afam_eval.cpp)\ncodecs:%s%s\n",
        zfpAvailable() ? " zfp" : "",
#ifdef AFAM_EVAL_HAVE_FPZIP
        " fpzip"
#else
        ""
#endif
    );
    return argc < 2 ? 2 : 0;
  }
  try {
    const std::string cmd = argv[1];
    const Opts o(argc, argv, 2);
    if (cmd == "quality") return runQuality(o);
    if (cmd == "compress") return runCompress(o);
    if (cmd == "stability") return runStability(o);
    if (cmd == "seams") return runSeams(o);
    throw std::runtime_error("unknown sub-command " + cmd);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "afam_eval: %s\n", e.what());
    return 1;
  }
}
