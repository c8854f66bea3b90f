// SPDX-License-Identifier: BSD-3-Clause
// afam compare-codecs IN.raw... [--bounds E,...] [--csv OUT] [--levels L] [--blocks B] [--degree P]
//                     [--threads T] [--work DIR] [--device auto|gpu|cpu]
// Adaptive-FAM (all levels stored) next to ZFP in fixed-accuracy mode tuned to the RMSE that
// Adaptive-FAM reached, per raw volume and relative RMSE bound: compression ratio against the raw
// file, RMSE and max error on the finest level (the measure of `afam verify --against`), time.
// The tolerance search runs on every thread (the volume in slabs of whole ZFP blocks); the rows
// are ZFP's own runs at the tolerance found, on one thread and with its OpenMP.
#include <stdlib.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "encode_device.hpp"
#include "level_error.hpp"
#include "zfp_codec.hpp"

using namespace afam;
using namespace afam::cli;
namespace fs = std::filesystem;

namespace {

/// One row of the table and the CSV.
struct CodecRow {
  std::string volume, type, codec, setting;
  Index3 dims{};
  double bound = 0;  ///< relative RMSE bound asked for
  uint64_t rawBytes = 0, compressedBytes = 0;
  double rmse = 0, maxError = 0, valueRange = 0;
  double targetRmse = 0;  ///< Adaptive-FAM: its absolute bound; ZFP: Adaptive-FAM's achieved RMSE
  double seconds = 0;     ///< encode (Adaptive-FAM) or compress at the chosen tolerance (ZFP)
  int threads = 1;
  double ratio() const { return double(rawBytes) / double(compressedBytes); }
};

const char* kCsvHeader =
    "volume,dims,type,bound,codec,raw_bytes,compressed_bytes,ratio,rmse,rmse_relative,max_error,"
    "target_rmse,"
    "seconds,threads,setting";

/// A folder made with mkdtemp under `parent`, removed with everything in it when it goes out of
/// scope.
class TemporaryFolder {
 public:
  explicit TemporaryFolder(const fs::path& parent) {
    std::string pattern = (parent / "afam-compare-codecs-XXXXXX").string();
    if (!::mkdtemp(pattern.data()))
      throw IoError(parent.string() + ": cannot create a temporary folder there");
    path_ = pattern;
  }
  ~TemporaryFolder() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::vector<double> parseBounds(const std::string& list) {
  std::vector<double> bounds;
  size_t start = 0;
  while (start <= list.size()) {
    const size_t comma = std::min(list.find(',', start), list.size());
    const std::string s = list.substr(start, comma - start);
    double v = 0;
    try {
      size_t pos = 0;
      v = std::stod(s, &pos);
      if (pos != s.size()) throw 0;
    } catch (...) {
      throw InvalidArgument("--bounds: '" + s + "' is not a number");
    }
    if (!(v > 0) || !std::isfinite(v))
      throw InvalidArgument("--bounds: every bound must be > 0, got " + s);
    bounds.push_back(v);
    start = comma + 1;
  }
  return bounds;
}

std::unique_ptr<RawFileSource> openNamedRaw(const std::string& path) {
  Index3 dims{};
  SampleType type = SampleType::Float32;
  if (!parseRawName(path, dims, type))
    throw InvalidArgument(path + ": not a raw volume named name_XxYxZ_type.raw (type " +
                          sampleTypeNames() + ")");
  return std::make_unique<RawFileSource>(path, dims, type);
}

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

CodecRow baseRow(const RawFileSource& src, double bound, const char* codec) {
  CodecRow r;
  r.volume = fs::path(src.path()).stem().string();
  r.type = sampleTypeName(src.type());
  r.codec = codec;
  r.dims = src.dims();
  r.bound = bound;
  r.rawBytes = fs::file_size(src.path());
  return r;
}

CodecRow runAdaptiveFam(RawFileSource& src, EncoderOptions options, double bound,
                        const std::string& device, const fs::path& folder) {
  options.errorBound = bound;
  options.relativeBound = true;  // the bound kind (RMSE or pointwise) is the caller's
  const fs::path out = folder / (fs::path(src.path()).stem().string() + ".afam");
  const EncodeStats s = encodeVolume(src, options, out.string());
  auto file = AfamFile::open(out.string());
  const ErrorAccumulator e = measureLevelError(*file, src, file->header().levels - 1);
  CodecRow r = baseRow(src, bound, "adaptive-fam");
  r.compressedBytes = fs::file_size(out);
  r.rmse = e.rmse();
  r.maxError = e.maxError;
  r.valueRange = s.valueMax - s.valueMin;
  r.targetRmse = s.bound;
  r.seconds = s.seconds;
  r.threads = s.threads;
  r.setting = "levels=" + std::to_string(options.levels) +
              " blocks=" + std::to_string(options.blocksPerAxis) +
              " degree=" + std::to_string(options.degree) + " device=" + device;
  fs::remove(out);
  return r;
}

/// ZFP at tolerance 2^exponent on the volume, with its error against the volume.
struct ZfpTrial {
  int exponent = 0;
  ZfpRoundTrip trip;
  ErrorAccumulator error;
};

ZfpTrial zfpTrial(const std::vector<float>& volume, Index3 dims, int exponent,
                  std::vector<float>& decoded, int threads = 1) {
  ZfpTrial t;
  t.exponent = exponent;
  decoded.resize(volume.size());
  t.trip = zfpRoundTrip(ZfpMode::FixedAccuracy, std::ldexp(1.0, exponent), volume.data(),
                        size_t(dims[0]), size_t(dims[1]), size_t(dims[2]), decoded.data(), threads);
  t.error.add(decoded.data(), volume.data(), int64_t(volume.size()));
  return t;
}

/// The error ZFP at tolerance 2^exponent leaves on the volume, the volume cut into `threads` slabs
/// of whole ZFP blocks (4 planes) along z, each compressed and decompressed serially on a thread of
/// its own: ZFP codes each 4x4x4 block alone, so every sample decodes as in one stream of the
/// whole volume (ZFP's OpenMP compresses that way, and its variable-rate streams decompress on one
/// thread only). For the tolerance search on volumes of billions of samples.
ErrorAccumulator zfpSlabsError(const std::vector<float>& volume, Index3 dims, int exponent,
                               int threads) {
  const int64_t plane = dims[0] * dims[1];
  const int64_t blocks = (dims[2] + 3) / 4;
  const int64_t slabs = std::max<int64_t>(1, std::min<int64_t>(threads, blocks));
  std::vector<ErrorAccumulator> errors(static_cast<size_t>(slabs));
  std::vector<std::string> failures(static_cast<size_t>(slabs));
  std::vector<std::thread> workers;
  for (int64_t k = 0; k < slabs; ++k)
    workers.emplace_back([&, k] {
      const int64_t z0 = 4 * (blocks * k / slabs),
                    z1 = std::min(dims[2], 4 * (blocks * (k + 1) / slabs));
      try {
        std::vector<float> decoded(size_t((z1 - z0) * plane));
        const float* in = volume.data() + z0 * plane;
        zfpRoundTrip(ZfpMode::FixedAccuracy, std::ldexp(1.0, exponent), in, size_t(dims[0]),
                     size_t(dims[1]), size_t(z1 - z0), decoded.data());
        errors[size_t(k)].add(decoded.data(), in, (z1 - z0) * plane);
      } catch (const std::exception& e) {
        failures[size_t(k)] = e.what();
      }
    });
  for (std::thread& w : workers) w.join();
  ErrorAccumulator all;
  for (int64_t k = 0; k < slabs; ++k) {
    if (!failures[size_t(k)].empty()) throw Error(failures[size_t(k)]);
    all.sumSquares += errors[size_t(k)].sumSquares;
    all.maxError = std::max(all.maxError, errors[size_t(k)].maxError);
    all.count += errors[size_t(k)].count;
  }
  return all;
}

/// Bisection on the tolerance for the largest one whose RMSE (or, `pointwise`, largest error) is
/// <= target. ZFP's fixed-accuracy mode applies the power of two at or below the tolerance asked
/// for, so the search runs over that exponent: from a passing exponent (2^e <= target bounds every
/// error by target) and a failing one found by doubling steps upwards, down to two neighbours; the
/// passing one is returned.
int tuneZfp(const std::vector<float>& volume, Index3 dims, double target, double valueRange,
            bool pointwise, int threads, int& trials) {
  if (!(target > 0))
    throw Error("Adaptive-FAM reached an error of 0: there is no ZFP tolerance to tune to it");
  const auto within = [&](int exponent) {
    ++trials;
    const ErrorAccumulator e = zfpSlabsError(volume, dims, exponent, threads);
    return (pointwise ? e.maxError : e.rmse()) <= target;  // ZFP's bound is on the max error
  };
  trials = 0;
  int lo = int(std::floor(std::log2(target)));
  for (int k = 0; !within(lo); ++k) {
    if (k == 64)
      throw Error("ZFP does not reach RMSE " + std::to_string(target) + " at tolerance 2^" +
                  std::to_string(lo));
    --lo;
  }
  // Above 2^(top) every tolerance is larger than the whole value range: ZFP keeps next to nothing.
  const int top = int(std::ceil(std::log2(std::max(valueRange, target)))) + 2;
  int hi = lo, step = 1;
  while (hi < top) {
    hi = std::min(lo + step, top);
    if (!within(hi)) break;
    lo = hi;
    step *= 2;
  }
  if (lo == hi) return lo;  // passes up to `top`
  while (hi - lo > 1) {
    const int mid = lo + (hi - lo) / 2;
    (within(mid) ? lo : hi) = mid;
  }
  return lo;
}

/// ZFP tuned to `target` (Adaptive-FAM's reached RMSE, or its bound; `pointwise`: the largest
/// error), on the same float32 volume: compressed on one thread ("zfp"), and, where Adaptive-FAM
/// ran on several, again at the same tolerance with ZFP's OpenMP on as many ("zfp-omp").
std::vector<CodecRow> runZfp(RawFileSource& src, const CodecRow& afam, double target,
                             bool pointwise) {
  const Index3 d = src.dims();
  std::vector<float> volume(size_t(d[0] * d[1] * d[2]));
  src.readSlab(0, d[2], volume.data());
  int trials = 0;
  const auto t0 = std::chrono::steady_clock::now();
  const int exponent = tuneZfp(volume, d, target, afam.valueRange, pointwise, afam.threads, trials);
  const double tuning = secondsSince(t0);
  std::vector<float> decoded;
  const ZfpTrial t = zfpTrial(volume, d, exponent, decoded);
  CodecRow r = baseRow(src, afam.bound, "zfp");
  r.compressedBytes = t.trip.bytes;
  r.rmse = t.error.rmse();
  r.maxError = t.error.maxError;
  r.valueRange = afam.valueRange;
  r.targetRmse = target;
  r.seconds = t.trip.compressSeconds;
  char setting[160];
  std::snprintf(setting, sizeof setting,
                "accuracy tolerance=2^%d=%.6g tuning_trials=%d tuning_s=%.3f", t.exponent,
                t.trip.effectiveParameter, trials, tuning);
  r.setting = setting;
  std::vector<CodecRow> rows{r};
  if (afam.threads > 1) {
    const ZfpTrial omp = zfpTrial(volume, d, t.exponent, decoded, afam.threads);
    CodecRow o = r;
    o.codec = "zfp-omp";
    o.threads = afam.threads;
    o.compressedBytes = omp.trip.bytes;
    o.rmse = omp.error.rmse();
    o.maxError = omp.error.maxError;
    o.seconds = omp.trip.compressSeconds;
    std::snprintf(setting, sizeof setting, "accuracy tolerance=2^%d=%.6g openmp_threads=%d",
                  t.exponent, omp.trip.effectiveParameter, afam.threads);
    o.setting = setting;
    rows.push_back(o);
  }
  return rows;
}

std::string dimsText(const Index3& d) {
  return std::to_string(d[0]) + "x" + std::to_string(d[1]) + "x" + std::to_string(d[2]);
}

void printTable(const std::vector<CodecRow>& rows) {
  std::printf("%-28s %-8s %-13s %9s %12s %11s %12s %12s %9s  %s\n", "volume", "bound", "codec",
              "ratio", "rmse", "rmse/range", "max_error", "target_rmse", "seconds", "setting");
  for (const CodecRow& r : rows)
    std::printf("%-28s %-8g %-13s %9.3f %12.6g %11.4g %12.6g %12.6g %9.3f  %s\n", r.volume.c_str(),
                r.bound, r.codec.c_str(), r.ratio(), r.rmse, r.rmse / r.valueRange, r.maxError,
                r.targetRmse, r.seconds, r.setting.c_str());
}

/// Writes the CSV next to `path` and renames it into place, so a failed run leaves no partial file.
void writeCsv(const std::string& path, const std::vector<CodecRow>& rows) {
  const std::string tmp = path + ".part";
  std::FILE* f = std::fopen(tmp.c_str(), "w");
  if (!f) throw IoError(path + ": cannot write");
  std::fprintf(f, "%s\n", kCsvHeader);
  for (const CodecRow& r : rows)
    std::fprintf(f, "%s,%s,%s,%g,%s,%llu,%llu,%.6g,%.9g,%.9g,%.9g,%.9g,%.6g,%d,%s\n",
                 r.volume.c_str(), dimsText(r.dims).c_str(), r.type.c_str(), r.bound,
                 r.codec.c_str(), (unsigned long long)r.rawBytes,
                 (unsigned long long)r.compressedBytes, r.ratio(), r.rmse, r.rmse / r.valueRange,
                 r.maxError, r.targetRmse, r.seconds, r.threads, r.setting.c_str());
  const bool ok = std::fflush(f) == 0 && !std::ferror(f);
  std::fclose(f);
  std::error_code ec;
  if (ok) fs::rename(tmp, path, ec);
  if (!ok || ec) {
    fs::remove(tmp, ec);
    throw IoError(path + ": cannot write");
  }
}

EncoderOptions encoderOptions(const Args& args) {
  EncoderOptions opt;  // the encoder's defaults unless asked otherwise
  opt.levels = int(args.integer("levels", opt.levels));
  opt.blocksPerAxis = int(args.integer("blocks", opt.blocksPerAxis));
  opt.degree = int(args.integer("degree", opt.degree));
  opt.threads = int(args.integer("threads", opt.threads));
  return opt;
}

}  // namespace

int runCompareCodecs(int argc, char** argv) {
  Args args(
      argc, argv,
      {"bounds", "csv", "levels", "blocks", "degree", "threads", "work", "zfp-target", "device"},
      {"max-error"});
  const char* usage =
      "afam compare-codecs IN.raw... [--bounds E1,E2,...] [--csv OUT.csv] [--levels L] [--blocks "
      "B]\n"
      "       [--degree P] [--threads T] [--work DIR] [--zfp-target reached|bound] [--max-error]\n"
      "       [--device auto|gpu|cpu]";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "For each raw volume (name_XxYxZ_type.raw) and each relative RMSE bound E:\n"
        "  adaptive-fam  `afam encode IN OUT --error-bound E --relative --device D` (all levels\n"
        "                stored; the setting says where it asked) into a"
        "\n"
        "                temporary folder, removed afterwards; ratio = raw file bytes / .afam "
        "bytes;\n"
        "                rmse and max_error of the finest level against IN, as `afam verify "
        "--against`;\n"
        "                seconds = encode wall time.\n"
        "  zfp           ZFP fixed-accuracy mode on the same float32 volume, its tolerance "
        "bisected so\n"
        "                that its RMSE is <= the RMSE adaptive-fam reached, as close below as "
        "ZFP's\n"
        "                power-of-two tolerances allow; ratio = raw file bytes / ZFP stream "
        "bytes;\n"
        "                seconds = compression time at that tolerance (serial).\n"
        "  zfp-omp       where adaptive-fam ran on several threads: ZFP at the same tolerance\n"
        "                compressed with its OpenMP execution on as many threads (seconds).\n"
        "Prints a table; --csv writes one row per (volume, bound, codec).\n\n"
        "  --bounds E,...  relative RMSE bounds, each > 0 (default 1e-2)\n"
        "  --levels, --blocks, --degree, --threads  passed to the encoder (default: its defaults)\n"
        "%s"
        "  --work DIR      where the temporary folder goes (default: the system's temporary "
        "folder)\n"
        "  --zfp-target T  reached (default): ZFP's RMSE <= the RMSE adaptive-fam reached; bound: "
        "<= the\n"
        "                  bound E * (max - min) itself (looser for ZFP when adaptive-fam lands "
        "below it)\n"
        "  --max-error     the bounds are pointwise: adaptive-fam encodes with --max-error E "
        "--relative,\n"
        "                  ZFP's tolerance is the largest whose largest error is <= E * (max - "
        "min)\n"
        "                  (--zfp-target bound is then the default; target_rmse is that largest "
        "error)\n",
        usage, encodeDeviceHelp());
    return 0;
  }
  if (args.positional().empty())
    throw InvalidArgument("no raw volume given (afam compare-codecs --help)");
  const std::vector<double> bounds = parseBounds(args.str("bounds", "1e-2"));
  EncoderOptions options = encoderOptions(args);
  std::string device = useEncodeDevice(options, args.str("device", "auto"));
  std::replace(device.begin(), device.end(), ',', ';');  // the CSV's setting is one cell
  const bool pointwise = args.has("max-error");
  if (pointwise) options.boundKind = BoundKind::MaxError;
  // Pointwise: both codecs held to the same largest error E * (max - min), as a user asks for it.
  const std::string zfpTarget = args.str("zfp-target", pointwise ? "bound" : "reached");
  if (zfpTarget != "reached" && zfpTarget != "bound")
    throw InvalidArgument("--zfp-target must be reached or bound, not '" + zfpTarget + "'");
  if (!zfpAvailable())
    throw Error("this afam was built without ZFP (install libzfp-dev and configure again)");
  const fs::path csvFolder = fs::path(args.str("csv")).parent_path();
  if (args.has("csv") && !csvFolder.empty() && !fs::is_directory(csvFolder))
    throw IoError(args.str("csv") + ": its folder does not exist");
  std::vector<std::unique_ptr<RawFileSource>> sources;
  for (const std::string& path : args.positional()) sources.push_back(openNamedRaw(path));
  const TemporaryFolder folder(args.has("work") ? fs::path(args.str("work"))
                                                : fs::temp_directory_path());
  std::vector<CodecRow> rows;
  for (auto& src : sources)
    for (double bound : bounds) {
      const CodecRow afam = runAdaptiveFam(*src, options, bound, device, folder.path());
      rows.push_back(afam);
      const double reached = pointwise ? afam.maxError : afam.rmse;
      for (CodecRow& z :
           runZfp(*src, afam, zfpTarget == "reached" ? reached : afam.targetRmse, pointwise))
        rows.push_back(std::move(z));
    }
  printTable(rows);
  if (args.has("csv")) {
    writeCsv(args.str("csv"), rows);
    std::printf("csv: %s\n", args.str("csv").c_str());
  }
  return 0;
}
