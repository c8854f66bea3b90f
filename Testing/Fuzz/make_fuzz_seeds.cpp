// SPDX-License-Identifier: BSD-3-Clause
// Writes the seed corpus of the fuzz targets: small valid inputs of every kind, made by the same
// code that makes real files (the encoder, the writer), so a format change changes the seeds too.
//   make_fuzz_seeds OUT_DIR
// creates OUT_DIR/{afam_file,raw_file,volume_header,trajectory,lstm_weights}/seed-* (control bytes
// as each fuzz target expects them).
#include <sys/stat.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "afam/base/hash.hpp"
#include "afam/encode/encode_run.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/volume/marschner_lobb.hpp"

namespace {

using Bytes = std::vector<uint8_t>;

Bytes readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void writeSeed(const std::string& dir, const std::string& name, uint8_t control, const Bytes& body,
               bool withControl = true) {
  ::mkdir(dir.c_str(), 0755);
  std::ofstream out(dir + "/seed-" + name, std::ios::binary | std::ios::trunc);
  if (withControl) out.put(static_cast<char>(control));
  out.write(reinterpret_cast<const char*>(body.data()), static_cast<std::streamsize>(body.size()));
  if (!out) throw std::runtime_error("cannot write seed " + dir + "/seed-" + name);
}

// An .afam file of Marschner-Lobb on dims, encoded in `mode`; returns its bytes.
Bytes encodedMl(const afam::Index3& dims, afam::EncodingMode mode, int levels, int blocks,
                const std::string& scratch, afam::EntropyStage entropy = afam::EntropyStage::Auto) {
  std::vector<float> v(static_cast<size_t>(dims[0] * dims[1] * dims[2]));
  afam::marschnerLobbSlab(afam::MarschnerLobb{}, dims, 0, dims[2], v.data());
  afam::ArraySource source(v.data(), dims);
  afam::EncoderOptions o;
  o.levels = levels;
  o.blocksPerAxis = blocks;
  o.errorBound = 1e-2;
  o.mode = mode;
  o.entropy = entropy;
  o.threads = 1;
  afam::encodeVolume(source, o, scratch);
  Bytes b = readFile(scratch);
  std::remove(scratch.c_str());
  return b;
}

Bytes readThenRemove(const std::string& scratch) {
  Bytes bytes = readFile(scratch);
  std::remove(scratch.c_str());
  return bytes;
}

// The steps as a run file (2 levels, 2 blocks a side, RMSE bound 1e-2, one thread); its bytes.
Bytes encodedRunOf(const std::vector<afam::VolumeSource*>& steps, int keyInterval,
                   const std::string& scratch) {
  afam::EncoderOptions o;
  o.levels = 2;
  o.blocksPerAxis = 2;
  o.errorBound = 1e-2;
  o.threads = 1;
  afam::RunOptions r;
  r.keyInterval = keyInterval;
  afam::encodeRun(steps, o, r, scratch);
  return readThenRemove(scratch);
}

// A run of three steps of Marschner-Lobb (the second the first again: references), as one file.
Bytes encodedRun(const std::string& scratch) {
  const afam::Index3 dims{7, 6, 5};
  std::vector<float> a(static_cast<size_t>(dims[0] * dims[1] * dims[2])), b;
  afam::marschnerLobbSlab(afam::MarschnerLobb{}, dims, 0, dims[2], a.data());
  b = a;
  for (float& v : b) v = 1.5f - v;
  afam::ArraySource sa(a.data(), dims), sb(b.data(), dims);
  return encodedRunOf({&sa, &sa, &sb}, 2, scratch);
}

// A run whose steps drift a little (residuals on the step before, chains of three payloads).
Bytes encodedResidualRun(const std::string& scratch) {
  const afam::Index3 dims{9, 8, 7};
  std::vector<std::vector<float>> steps(4);
  for (int k = 0; k < 4; ++k) {
    steps[size_t(k)].resize(static_cast<size_t>(dims[0] * dims[1] * dims[2]));
    size_t i = 0;
    for (int64_t z = 0; z < dims[2]; ++z)
      for (int64_t y = 0; y < dims[1]; ++y)
        for (int64_t x = 0; x < dims[0]; ++x, ++i)
          steps[size_t(k)][i] = float(std::sin(0.7 * double(x) + 0.05 * k) *
                                      std::cos(0.5 * double(y) - 0.3 * double(z))) +
                                0.05f * float((x * 7 + y * 13 + z * 29) % 11);
  }
  std::vector<afam::ArraySource> sources;
  for (const auto& v : steps) sources.emplace_back(v.data(), dims);
  return encodedRunOf({&sources[0], &sources[1], &sources[2], &sources[3]}, 3, scratch);
}

// Marschner-Lobb with holes: masked blocks (coded masks before their models) and an empty block.
Bytes encodedWithHoles(const std::string& scratch) {
  const afam::Index3 dims{12, 10, 9};
  std::vector<float> v(static_cast<size_t>(dims[0] * dims[1] * dims[2]));
  afam::marschnerLobbSlab(afam::MarschnerLobb{}, dims, 0, dims[2], v.data());
  size_t i = 0;
  for (int64_t z = 0; z < dims[2]; ++z)
    for (int64_t y = 0; y < dims[1]; ++y)
      for (int64_t x = 0; x < dims[0]; ++x, ++i)
        if (x < 5 || (x - 8) * (x - 8) + (y - 5) * (y - 5) + (z - 4) * (z - 4) < 6)
          v[i] = std::numeric_limits<float>::quiet_NaN();
  afam::ArraySource source(v.data(), dims);
  afam::EncoderOptions o;
  o.levels = 2;
  o.blocksPerAxis = 3;
  o.errorBound = 1e-2;
  o.threads = 1;
  afam::encodeVolume(source, o, scratch);
  return readThenRemove(scratch);
}

// A smooth field under noise above the bound: interpolants with rounded points (index flag bit
// 14, the step's shift as each payload's last byte). Throws if none comes out rounded.
Bytes encodedRounded(const std::string& scratch) {
  const afam::Index3 dims{12, 11, 10};
  std::vector<float> v(static_cast<size_t>(dims[0] * dims[1] * dims[2]));
  uint32_t state = 12345;
  for (size_t i = 0; i < v.size(); ++i) {
    state = state * 1664525u + 1013904223u;  // a fixed sequence: the same seed every time
    v[i] = float(std::sin(0.3 * double(i % 12)) + 0.2 * (double(state >> 8) / 16777216.0 - 0.5));
  }
  afam::ArraySource source(v.data(), dims);
  afam::EncoderOptions o;
  o.levels = 1;
  o.blocksPerAxis = 2;
  o.errorBound = 1e-2;
  o.relativeBound = true;
  o.threads = 1;
  afam::encodeVolume(source, o, scratch);
  int rounded = 0;
  const auto file = afam::AfamFile::open(scratch);
  for (const afam::ModelEntry& e : file->entries()) rounded += e.roundedPoints;
  if (rounded == 0) throw std::runtime_error("the rounded-points seed has no rounded interpolant");
  return readThenRemove(scratch);
}

// A 2x2x2 volume whose one block is an interpolant with rounded points coded into exactly the
// bytes of its float samples (a reader once took such a payload for floats); says so if not.
Bytes encodedAsLongAsItsFloats(const std::string& scratch) {
  std::vector<float> v{0.34558418f, 0.82161814f, 0.33043706f, -1.3031572f,
                       0.9053559f,  0.44637457f, -0.5369532f, 0.5811181f};
  afam::ArraySource source(v.data(), {2, 2, 2});
  afam::EncoderOptions o;
  o.errorBound = 1e-3;
  o.relativeBound = true;
  o.threads = 1;
  afam::encodeVolume(source, o, scratch);
  const afam::ModelEntry e = afam::AfamFile::open(scratch)->entries()[0];
  if (!e.roundedPoints || e.storedSize != e.size)  // still a tiny rounded file worth fuzzing
    std::cerr << "make_fuzz_seeds: the 2x2x2 seed's payload is no longer as long as its floats\n";
  return readThenRemove(scratch);
}

void afamSeeds(const std::string& out) {
  const std::string dir = out + "/afam_file", scratch = out + "/scratch.afam";
  using M = afam::EncodingMode;
  const struct {
    afam::Index3 dims;
    M mode;
    int levels, blocks;
    const char* name;
  } cases[] = {
      {{7, 6, 5}, M::Adaptive, 2, 2, "adaptive"},
      {{8, 5, 4}, M::InLevel, 2, 2, "inlevel"},
      {{5, 5, 5}, M::Fixed, 1, 1, "fixed"},
      {{6, 5, 4}, M::Downsampled, 2, 2, "ds"},
  };
  for (const auto& c : cases) {
    const Bytes b = encodedMl(c.dims, c.mode, c.levels, c.blocks, scratch);
    writeSeed(dir, std::string(c.name) + "-fixall", 7, b);  // checksums recomputed after mutation
    writeSeed(dir, std::string(c.name) + "-asis", 0, b);    // checksums left as mutated
  }
  // Coded payloads in lanes frames (interleaved rANS, entropy/lanes_coder.hpp).
  const Bytes lanes = encodedMl({11, 9, 8}, M::Adaptive, 2, 2, scratch, afam::EntropyStage::Lanes);
  writeSeed(dir, "lanes-fixall", 7, lanes);
  writeSeed(dir, "lanes-asis", 0, lanes);
  const Bytes run = encodedRun(scratch);  // format version 3, references included
  writeSeed(dir, "run-fixall", 7, run);
  writeSeed(dir, "run-asis", 0, run);
  const Bytes residuals = encodedResidualRun(scratch);  // residual chains
  writeSeed(dir, "residuals-fixall", 7, residuals);
  writeSeed(dir, "residuals-asis", 0, residuals);
  const Bytes holes = encodedWithHoles(scratch);  // missing samples: masks and an empty block
  writeSeed(dir, "holes-fixall", 7, holes);
  writeSeed(dir, "holes-asis", 0, holes);
  const Bytes rounded = encodedRounded(scratch);  // interpolants with rounded points
  writeSeed(dir, "rounded-fixall", 7, rounded);
  writeSeed(dir, "rounded-asis", 0, rounded);
  const Bytes tiny = encodedAsLongAsItsFloats(scratch);  // coded bytes the size of its floats
  writeSeed(dir, "tiny-rounded-fixall", 7, tiny);
  writeSeed(dir, "tiny-rounded-asis", 0, tiny);
}

Bytes floatBytes(const std::vector<float>& f) {
  Bytes b(f.size() * 4);
  std::memcpy(b.data(), f.data(), b.size());
  return b;
}

void rawSeeds(const std::string& out) {
  const std::string dir = out + "/raw_file";
  const struct {
    const char* name;
    int voxels, bytesPerVoxel;
  } cases[] = {
      {"ml_4x3x2_float32.raw", 24, 4},  {"vol_2x2x2_float64.raw", 8, 8},
      {"ct_5x1x3_uint8.raw", 15, 1},    {"mri_3x3x1_uint16.raw", 9, 2},
      {"a/b/c_2x3x4_int16.raw", 24, 2},
  };
  for (const auto& c : cases) {
    const std::string name = c.name;
    Bytes b(name.begin(), name.end());
    b.push_back(0);
    for (int i = 0; i < c.voxels * c.bytesPerVoxel; ++i)
      b.push_back(static_cast<uint8_t>(i * 37 + 11));
    std::string file = name;
    for (char& ch : file)
      if (ch == '/') ch = '-';
    writeSeed(dir, file, 0, b, false);
  }
}

// NRRD (control 0) and MetaImage (control 1) files with their samples attached: raw and compressed.
void volumeHeaderSeeds(const std::string& out) {
  const std::string dir = out + "/volume_header";
  Bytes samples;
  for (int i = 0; i < 24; ++i) samples.push_back(static_cast<uint8_t>(i * 11));
  auto withText = [&](const std::string& text, const Bytes& payload) {
    Bytes b(text.begin(), text.end());
    b.insert(b.end(), payload.begin(), payload.end());
    return b;
  };
  writeSeed(
      dir, "nrrd-raw", 0,
      withText(
          "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 3 2\nspacings: 1 2 3\nencoding: raw\n\n",
          samples));
  writeSeed(
      dir, "nrrd-int16", 0,
      withText(
          "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 3 2\nendian: little\nencoding: raw\n\n",
          samples));
  writeSeed(dir, "mha-raw", 1,
            withText("NDims = 3\nDimSize = 4 3 2\nElementType = MET_UCHAR\nElementSpacing = 1 1 2\n"
                     "ElementDataFile = LOCAL\n",
                     samples));
  // zlib stream of 24 zero bytes (stored block: header 78 01, then 01 18 00 e7 ff, data, adler32)
  Bytes zlib = {0x78, 0x01, 0x01, 0x18, 0x00, 0xe7, 0xff};
  zlib.insert(zlib.end(), 24, 0);
  for (uint8_t v : {0x00, 0x18, 0x00, 0x01}) zlib.push_back(v);
  writeSeed(dir, "mha-zlib", 1,
            withText("NDims = 3\nDimSize = 4 3 2\nElementType = MET_UCHAR\nCompressedData = True\n"
                     "ElementDataFile = LOCAL\n",
                     zlib));
}

void trajectorySeeds(const std::string& out) {
  const std::string dir = out + "/trajectory";
  // Stored as three planes: distances, then theta, then phi (camera.cpp).
  writeSeed(dir, "three-views", 0,
            floatBytes({1.2f, 1.5f, 1.7f, 10.f, 45.f, 170.f, -20.f, 0.f, 80.f}), false);
  writeSeed(dir, "one-view", 0, floatBytes({1.0f, 0.f, 0.f}), false);
}

void putU32(Bytes& b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
void putF32(Bytes& b, float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  putU32(b, u);
}

// A valid weights file with hidden size H (layout of Core/src/predict/lstm.cpp).
Bytes tinyLstm(uint32_t hidden, uint32_t steps) {
  Bytes b = {'A', 'F', 'L', 'S', 'T', 'M', 0, 0};
  putU32(b, 1);
  for (uint32_t v : {6u, hidden, 3u, 4u}) putU32(b, v);
  putF32(b, 0.05f);
  putU32(b, 1);
  const size_t floats = 4 * hidden * 6 + 4 * hidden * hidden + 4 * hidden + 3 * hidden + 3;
  for (size_t i = 0; i < floats; ++i) putF32(b, 0.01f * std::sin(float(i)));
  putU32(b, steps);
  for (size_t i = 0; i < steps * 6 + 3; ++i) putF32(b, 0.1f * float(i % 7));
  putU32(b, afam::fnv1a32(b.data(), b.size()));
  return b;
}

// Small shapes only: the shipped file (hidden 32) has the same layout and would slow every run.
void lstmSeeds(const std::string& out) {
  const std::string dir = out + "/lstm_weights";
  writeSeed(dir, "hidden2", 1, tinyLstm(2, 3));
  writeSeed(dir, "hidden5-asis", 0, tinyLstm(5, 1));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: make_fuzz_seeds OUT_DIR\n";
    return 2;
  }
  try {
    const std::string out = argv[1];
    ::mkdir(out.c_str(), 0755);
    afamSeeds(out);
    rawSeeds(out);
    volumeHeaderSeeds(out);
    trajectorySeeds(out);
    lstmSeeds(out);
  } catch (const std::exception& e) {
    std::cerr << "make_fuzz_seeds: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
