// SPDX-License-Identifier: BSD-3-Clause
// NRRD and MetaImage inputs: every layout the readers take gives the samples of the raw corpus
// volume it was written from, and an .afam file byte-identical to the raw one's; each kind of bad
// header is refused with the file and the field named.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/volume/volume_formats.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

const std::string kVolumes = std::string(AFAM_TEST_DATA_DIR) + "/volumes/";
const std::string kHead = "headsq_quarter_64x64x93_int16.raw";  // multi-byte, anisotropic
const std::string kBucky = "bucky_32x32x32_uint8.raw";

std::string work(const std::string& name) { return afam_test::scratchPath(name); }

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void spit(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

std::string gzipped(const std::string& bytes, bool gzipWrapper) {
  z_stream z{};
  EXPECT_EQ(deflateInit2(&z, 6, Z_DEFLATED, gzipWrapper ? 15 + 16 : 15, 8, Z_DEFAULT_STRATEGY),
            Z_OK);
  std::string out(deflateBound(&z, uLong(bytes.size())), '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
  z.avail_in = uInt(bytes.size());
  z.next_out = reinterpret_cast<Bytef*>(&out[0]);
  z.avail_out = uInt(out.size());
  EXPECT_EQ(deflate(&z, Z_FINISH), Z_STREAM_END);
  out.resize(z.total_out);
  deflateEnd(&z);
  return out;
}

std::string swapped16(std::string bytes) {
  for (size_t i = 0; i + 1 < bytes.size(); i += 2) std::swap(bytes[i], bytes[i + 1]);
  return bytes;
}

std::vector<float> samples(VolumeSource& s) {
  const Index3 d = s.dims();
  std::vector<float> v(size_t(d[0] * d[1] * d[2]));
  s.readSlab(0, d[2], v.data());
  return v;
}

/// The same samples, each plane read by one of four threads at once (concurrentReads).
std::vector<float> samplesOnThreads(VolumeSource& s) {
  const Index3 d = s.dims();
  const size_t plane = size_t(d[0] * d[1]);
  std::vector<float> v(plane * size_t(d[2]));
  std::vector<std::thread> readers;
  for (int t = 0; t < 4; ++t)
    readers.emplace_back([&, t] {
      for (int64_t z = t; z < d[2]; z += 4) s.readSlab(z, 1, v.data() + size_t(z) * plane);
    });
  for (std::thread& r : readers) r.join();
  return v;
}

std::string encodeToBytes(VolumeSource& s, const std::string& out) {
  EncoderOptions o;
  o.levels = 2;
  o.blocksPerAxis = 4;
  o.errorBound = 1e-2;
  o.relativeBound = true;
  o.threads = 2;
  encodeVolume(s, o, out);
  return slurp(out);
}

std::string nrrdHeader(const std::string& type, const std::string& sizes,
                       const std::string& extra) {
  return "NRRD0004\n# written by the test\ntype: " + type + "\ndimension: 3\nsizes: " + sizes +
         "\n" + extra;
}

// The message of the exception `f` throws; empty (and a failure) when it throws none.
template <typename F>
std::string errorOf(F f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error";
  return "";
}

}  // namespace

namespace {

/// Rows 3..52 of planes 7..26 of a 64 x 64 x 93 int16 volume as the source stores them, then the
/// whole of planes 90..92.
std::vector<int16_t> storedPart(VolumeSource& src) {
  std::vector<int16_t> out(size_t(64) * 50 * 20 + size_t(64) * 64 * 3);
  src.readStoredRows(7, 20, 3, 50, out.data());
  src.readStoredRows(90, 3, 0, 64, out.data() + 64 * 50 * 20);
  return out;
}

/// The same samples picked from the volume's floats.
std::vector<int16_t> storedPartOf(const std::vector<float>& v) {
  std::vector<int16_t> out;
  for (int64_t z = 7; z < 27; ++z)
    for (int64_t y = 3; y < 53; ++y)
      for (int64_t x = 0; x < 64; ++x) out.push_back(int16_t(v[size_t((z * 64 + y) * 64 + x)]));
  for (size_t i = size_t(90 * 64 * 64); i < size_t(93 * 64 * 64); ++i) out.push_back(int16_t(v[i]));
  return out;
}

}  // namespace

TEST(VolumeFormats, EveryLayoutReadsTheRawSamples) {
  const std::string raw = slurp(kVolumes + kHead);
  RawFileSource reference(kVolumes + kHead, {64, 64, 93}, SampleType::Int16);
  const std::vector<float> want = samples(reference);
  const std::string sizes = "64 64 93";
  spit(work("head_attached.nrrd"),
       nrrdHeader("short", sizes,
                  "endian: little\nencoding: raw\nspacings: 3.2 3.2 1.5\nnote:=a: b\n"
                  "content: CT: head\n\n") +
           raw);
  spit(work("head_gzip.nrrd"),
       nrrdHeader("int16", sizes, "endian: little\nencoding: gzip\n\n") + gzipped(raw, true));
  spit(work("head_big.raw"), "skip me\nand me\n" + std::string(5, 'x') + swapped16(raw));
  spit(work("head_detached.nhdr"),
       nrrdHeader(
           "int16_t", sizes,
           "endian: big\nencoding: raw\ndata file: head_big.raw\nline skip: 2\nbyte skip: 5\n"));
  spit(work("head_tail.nhdr"),
       nrrdHeader("short", sizes,
                  "endian: big\nencoding: raw\ndata file: head_big.raw\nbyte skip: -1\n"));
  spit(work("head_zlib.mha"),
       "ObjectType = Image\nNDims = 3\nDimSize = 64 64 93\nElementType = MET_SHORT\n"
       "BinaryDataByteOrderMSB = False\nCompressedData = True\nElementSpacing = 3.2 3.2 1.5\n"
       "ElementDataFile = LOCAL\n" +
           gzipped(raw, false));
  spit(work("head.mhd"),
       "NDims = 3\nDimSize = 64 64 93\nElementType = MET_SHORT\nOffset = -10 5 2.5\n"
       "ElementDataFile = " +
           kVolumes + kHead + "\n");
  for (const char* name : {"head_attached.nrrd", "head_gzip.nrrd", "head_detached.nhdr",
                           "head_tail.nhdr", "head_zlib.mha", "head.mhd"}) {
    SCOPED_TRACE(name);
    auto src = openHeaderVolume(work(name));
    EXPECT_EQ(src->dims(), (Index3{64, 64, 93}));
    EXPECT_EQ(src->name(), "head");
    EXPECT_EQ(samples(*src), want);
    ASSERT_TRUE(src->concurrentReads());
    EXPECT_EQ(samplesOnThreads(*src), want);
    // As stored for the encoder where that is the samples' floats: not byte-swapped ones.
    if (std::string(name).find(".nhdr") != std::string::npos) {  // the big-endian layouts
      EXPECT_FALSE(src->storedType().has_value());
      EXPECT_THROW(storedPart(*src), Error);
      continue;
    }
    ASSERT_EQ(src->storedType(), SampleType::Int16);
    EXPECT_EQ(storedPart(*src), storedPartOf(want));
    EXPECT_THROW(src->readStoredRows(90, 4, 0, 64, nullptr), InvalidArgument);  // past the end
  }
  EXPECT_EQ(samplesOnThreads(reference), want);
  ASSERT_EQ(reference.storedType(), SampleType::Int16);
  EXPECT_EQ(storedPart(reference), storedPartOf(want));
  ArraySource inMemory(raw.data(), SampleType::Int16, {64, 64, 93});
  ASSERT_EQ(inMemory.storedType(), SampleType::Int16);
  EXPECT_EQ(storedPart(inMemory), storedPartOf(want));
  ArraySource floats(want.data(), {64, 64, 93});
  EXPECT_FALSE(floats.storedType().has_value());  // float32 planes are read as they are
  EXPECT_THROW(storedPart(floats), Error);
  EXPECT_EQ(openHeaderVolume(work("head_attached.nrrd"))->spacing(),
            (std::array<double, 3>{3.2, 3.2, 1.5}));
  EXPECT_EQ(openHeaderVolume(work("head_zlib.mha"))->spacing(),
            (std::array<double, 3>{3.2, 3.2, 1.5}));
  EXPECT_EQ(openHeaderVolume(work("head.mhd"))->origin(), (std::array<double, 3>{-10, 5, 2.5}));
  EXPECT_EQ(openHeaderVolume(work("head_gzip.nrrd"))->spacing(), (std::array<double, 3>{1, 1, 1}));
}

TEST(VolumeFormats, SpaceDirectionsAndOriginReachTheAfamHeader) {
  spit(work("bucky_dirs.nrrd"), nrrdHeader("uchar", "32 32 32",
                                           "encoding: raw\nspace: left-posterior-superior\n"
                                           "space directions: (-0.5,0,0) (0, 0.5, 0) (0,0,2)\n"
                                           "space origin: (1.5,-2,3)\n\n") +
                                    slurp(kVolumes + kBucky));
  auto src = openHeaderVolume(work("bucky_dirs.nrrd"));
  EXPECT_EQ(src->spacing(), (std::array<double, 3>{0.5, 0.5, 2}));
  EXPECT_EQ(src->origin(), (std::array<double, 3>{1.5, -2, 3}));
  encodeToBytes(*src, work("bucky_dirs.afam"));
  const auto file = AfamFile::open(work("bucky_dirs.afam"));
  EXPECT_EQ(file->header().spacing, (std::array<double, 3>{0.5, 0.5, 2}));
  EXPECT_EQ(file->header().origin, (std::array<double, 3>{1.5, -2, 3}));
}

// The bar: the same volume through NRRD and MetaImage encodes to the same bytes as from raw.
TEST(VolumeFormats, EncodingIsByteIdenticalToTheRawCopy) {
  const std::string raw = slurp(kVolumes + kBucky);
  spit(work("bucky.nrrd"),
       nrrdHeader("uint8", "32 32 32", "encoding: gzip\n\n") + gzipped(raw, true));
  spit(work("bucky.mha"),
       "NDims = 3\nDimSize = 32 32 32\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n" + raw);
  RawFileSource rawSource(kVolumes + kBucky, {32, 32, 32}, SampleType::UInt8);
  const std::string want = encodeToBytes(rawSource, work("bucky_raw.afam"));
  ASSERT_GT(want.size(), 1000u);
  for (const char* name : {"bucky.nrrd", "bucky.mha"}) {
    SCOPED_TRACE(name);
    auto src = openHeaderVolume(work(name));
    const std::string got = encodeToBytes(*src, work(std::string(name) + ".afam"));
    EXPECT_EQ(got.size(), want.size());
    EXPECT_TRUE(got == want);
  }
}

// 64-bit integers, little- and big-endian, read as raw files of the same type read them.
TEST(VolumeFormats, SixtyFourBitIntegersReadAsTheirRawFile) {
  std::vector<int64_t> values(2 * 3 * 4);
  for (size_t i = 0; i < values.size(); ++i) values[i] = (int64_t(1) << 40) * int64_t(i) - 7;
  std::string little(values.size() * 8, '\0');
  std::memcpy(&little[0], values.data(), little.size());
  std::string big = little;
  for (size_t i = 0; i < big.size(); i += 8)
    std::reverse(big.begin() + std::ptrdiff_t(i), big.begin() + std::ptrdiff_t(i + 8));
  spit(work("long_2x3x4_int64.raw"), little);
  spit(work("long.nrrd"), nrrdHeader("long long", "2 3 4", "encoding: raw\nendian: big\n\n") + big);
  spit(work("long.mha"),
       "NDims = 3\nDimSize = 2 3 4\nElementType = MET_LONG_LONG\nElementDataFile = LOCAL\n" +
           little);
  Index3 dims{};
  SampleType type{};
  ASSERT_TRUE(parseRawName(work("long_2x3x4_int64.raw"), dims, type));
  RawFileSource raw(work("long_2x3x4_int64.raw"), dims, type);
  const std::vector<float> want = samples(raw);
  for (size_t i = 0; i < values.size(); ++i) ASSERT_EQ(want[i], static_cast<float>(values[i]));
  for (const char* name : {"long.nrrd", "long.mha"}) {
    SCOPED_TRACE(name);
    auto src = openHeaderVolume(work(name));
    EXPECT_EQ(src->header().type, SampleType::Int64);
    EXPECT_EQ(src->bytesPerVoxel(), 8);
    EXPECT_TRUE(samples(*src) == want);
  }
}

TEST(VolumeFormats, HeadersThatLieAreRefusedNamingFileAndField) {
  const std::string raw = slurp(kVolumes + kBucky);
  struct Case {
    const char* file;
    std::string bytes;
    const char* mustName;
  };
  const std::vector<Case> cases = {
      {"short.nrrd", nrrdHeader("uchar", "32 32 33", "encoding: raw\n\n") + raw, "sizes"},
      {"long.nrrd", nrrdHeader("uchar", "32 32 31", "encoding: raw\n\n") + raw, "sizes"},
      {"wide.nrrd", nrrdHeader("ushort", "32 32 32", "endian: little\nencoding: raw\n\n") + raw,
       "type"},
      {"gzshort.nrrd", nrrdHeader("uchar", "32 32 40", "encoding: gzip\n\n") + gzipped(raw, true),
       "sizes"},
      {"gzlong.nrrd", nrrdHeader("uchar", "16 32 32", "encoding: gzip\n\n") + gzipped(raw, true),
       "sizes"},
      {"gztrunc.nrrd",
       nrrdHeader("uchar", "32 32 32", "encoding: gzip\n\n") + gzipped(raw, true).substr(0, 300),
       "truncated"},
      {"type.nrrd", nrrdHeader("quaternion", "32 32 32", "encoding: raw\n\n") + raw,
       "field 'type'"},
      {"enc.nrrd", nrrdHeader("uchar", "32 32 32", "encoding: bzip2\n\n") + raw,
       "field 'encoding'"},
      {"dim.nrrd", "NRRD0004\ntype: uchar\ndimension: 2\nsizes: 1024 32\nencoding: raw\n\n" + raw,
       "field 'dimension'"},
      {"noendian.nrrd", nrrdHeader("short", "32 32 16", "encoding: raw\n\n") + raw,
       "field 'endian'"},
      {"nosizes.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nencoding: raw\n\n" + raw,
       "field 'sizes'"},
      {"magic.nrrd", "PNRD0004\n" + raw, "field 'magic'"},
      {"missing.nhdr", nrrdHeader("uchar", "32 32 32", "encoding: raw\ndata file: nowhere.raw\n"),
       "field 'data file'"},
      {"short.mha",
       "NDims = 3\nDimSize = 32 32 33\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n" + raw,
       "DimSize"},
      {"type.mha",
       "NDims = 3\nDimSize = 32 32 32\nElementType = MET_COMPLEX\nElementDataFile = LOCAL\n" + raw,
       "field 'ElementType'"},
      {"zlib.mha",
       "NDims = 3\nDimSize = 32 32 32\nElementType = MET_UCHAR\nCompressedData = True\n"
       "ElementDataFile = LOCAL\n" +
           raw,
       "damaged"},
      {"missing.mhd",
       "NDims = 3\nDimSize = 32 32 32\nElementType = MET_UCHAR\nElementDataFile = gone.raw\n",
       "field 'ElementDataFile'"},
      {"nodata.mhd", "NDims = 3\nDimSize = 32 32 32\nElementType = MET_UCHAR\n",
       "field 'ElementDataFile'"},
      {"empty.nrrd", "", "empty"},
      {"empty.mhd", "", "empty"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    spit(work(c.file), c.bytes);
    const std::string msg = errorOf([&] { openHeaderVolume(work(c.file)); });
    EXPECT_NE(msg.find(work(c.file)), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.mustName), std::string::npos) << msg;
  }
  // A directory is not readable as a header.
  const std::string dir = work("folder.nrrd");
  ::mkdir(dir.c_str(), 0755);
  const std::string msg = errorOf([&] { openHeaderVolume(dir); });
  EXPECT_NE(msg.find("not a regular file"), std::string::npos) << msg;
  EXPECT_THROW(openHeaderVolume(work("absent.mha")), IoError);
  EXPECT_THROW(openHeaderVolume(work("x.vti")), InvalidArgument);
}
