// SPDX-License-Identifier: BSD-3-Clause
// Payload decoding throughput, one thread: every stored payload of each .afam file given is read
// into memory once, then decoded (decodeStoredPayload: zstd, residuals, predictors, interpolant
// solves) ROUNDS times; prints, per file and per block kind, the median of the rounds in GB/s of
// decoded output (float32 bytes of the models) and in M values/s. With --codec the coded payloads
// only go through the block codec (decodeValues: zstd, residuals, predictors, the floats), without
// what follows it (an interpolant's spline solve), rows named "<kind> codec".
//   bench_decode [--rounds R] [--codec] FILE.afam [FILE.afam ...]
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/format/block_codec.hpp"

namespace {

struct Stored {
  afam::ModelEntry entry;
  std::vector<uint8_t> bytes;
};

std::vector<Stored> readStored(const afam::AfamFile& file) {
  std::vector<Stored> out;
  for (const afam::ModelEntry& e : file.entries()) {
    Stored s{e, std::vector<uint8_t>(e.storedSize)};
    if (pread(file.nativeHandle(), s.bytes.data(), e.storedSize, off_t(e.offset)) !=
        ssize_t(e.storedSize))
      throw afam::IoError(file.path() + ": short read");
    out.push_back(std::move(s));
  }
  return out;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

const char* kindName(const afam::ModelEntry& e) {
  if (e.kind == afam::BlockKind::Spline && !e.coded) return "spline(float)";
  if (e.kind == afam::BlockKind::Samples && !e.coded) return "samples(float)";
  return afam::blockKindName(e.kind);
}

/// Seconds per round for the payloads of one kind (all kinds when kind is empty).
std::vector<double> time(const std::vector<Stored>& stored, const std::string& kind, int rounds,
                         bool codecOnly, uint64_t& bytes) {
  std::vector<float> out;
  std::vector<double> seconds;
  for (int r = 0; r < rounds; ++r) {
    bytes = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (const Stored& s : stored) {
      if (!kind.empty() && kind != kindName(s.entry)) continue;
      if (codecOnly && !s.entry.coded) continue;
      out.resize(s.entry.size / sizeof(float));
      if (codecOnly)
        afam::decodeValues(s.bytes.data(), s.entry.storedSize, s.entry.ncp, out.data(), "bench");
      else
        afam::decodeStoredPayload(s.entry, s.bytes.data(), out.data(), "bench");
      bytes += s.entry.size;
    }
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return seconds;
}

}  // namespace

int main(int argc, char** argv) {
  int rounds = 9;
  bool codec = false;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--rounds") == 0 && i + 1 < argc)
      rounds = std::max(1, std::atoi(argv[++i]));
    else if (std::strcmp(argv[i], "--codec") == 0)
      codec = true;
    else
      files.push_back(argv[i]);
  }
  if (files.empty()) {
    std::fprintf(stderr, "usage: bench_decode [--rounds R] [--codec] FILE.afam [FILE.afam ...]\n");
    return 2;
  }
  std::printf(
      "| file | kind | models | decoded MB | stored MB | median s | GB/s decoded | M values/s |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  try {
    for (const std::string& path : files) {
      const auto file = afam::AfamFile::open(path);
      const std::vector<Stored> stored = readStored(*file);
      std::map<std::string, std::pair<int, uint64_t>> kinds;  // models, stored bytes
      for (const Stored& s : stored) {
        auto& k = kinds[kindName(s.entry)];
        ++k.first;
        k.second += s.entry.storedSize;
      }
      uint64_t storedAll = 0;
      for (const auto& k : kinds) storedAll += k.second.second;
      kinds[""] = {int(stored.size()), storedAll};
      const std::string name = path.substr(path.find_last_of('/') + 1);
      for (const bool codecOnly : {false, true}) {
        if (codecOnly && !codec) break;
        for (const auto& [kind, count] : kinds) {
          uint64_t bytes = 0;
          const double s = median(time(stored, kind, rounds, codecOnly, bytes));
          if (bytes == 0) continue;
          const std::string label = (kind.empty() ? "all" : kind) + (codecOnly ? " codec" : "");
          std::printf("| %s | %s | %d | %.2f | %.3f | %.5f | %.3f | %.1f |\n", name.c_str(),
                      label.c_str(), count.first, bytes / 1e6, count.second / 1e6, s,
                      bytes / s / 1e9, bytes / 4.0 / s / 1e6);
        }
      }
    }
  } catch (const afam::Error& e) {
    std::fprintf(stderr, "bench_decode: %s\n", e.what());
    return 1;
  }
  return 0;
}
