// SPDX-License-Identifier: BSD-3-Clause
// One sample type: its names and sizes, its one conversion to float (static_cast, as VTK converts),
// and the array source over samples of any type, whose planes and rows are those of a float array
// of the same values and whose .afam file is byte-identical to the one encoded from such an array.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/volume/sample_type.hpp"
#include "afam/volume/volume_source.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

const SampleType kTypes[] = {SampleType::Int8,   SampleType::UInt8,  SampleType::Int16,
                             SampleType::UInt16, SampleType::Int32,  SampleType::UInt32,
                             SampleType::Int64,  SampleType::UInt64, SampleType::Float32,
                             SampleType::Float64};

/// Values of T on a dims grid: the type's extremes first, then a ramp that wraps within its range
/// (negative values in signed types, fractions in floating ones).
template <class T>
std::vector<T> samplesOf(size_t count) {
  std::vector<T> v(count);
  const T special[] = {std::numeric_limits<T>::lowest(), std::numeric_limits<T>::max(), T(0), T(1)};
  for (size_t i = 0; i < count; ++i) {
    if (i < std::size(special)) {
      v[i] = special[i];
      continue;
    }
    const long long ramp =
        (long long)(i * 37 % 251) - (std::numeric_limits<T>::is_signed ? 125 : 0);
    v[i] = std::numeric_limits<T>::is_integer ? T(ramp) : T(double(ramp) * 0.3125);
  }
  return v;
}

template <class T>
std::vector<float> staticCast(const std::vector<T>& v) {
  std::vector<float> f(v.size());
  for (size_t i = 0; i < v.size(); ++i) f[i] = static_cast<float>(v[i]);
  return f;
}

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

/// For each SampleType: the typed source's slabs and rows against the float source's.
template <class T>
void checkTypedSource() {
  const Index3 dims{5, 4, 3};
  const size_t count = size_t(dims[0] * dims[1] * dims[2]);
  const std::vector<T> samples = samplesOf<T>(count);
  const std::vector<float> floats = staticCast(samples);
  ArraySource typed(samples.data(), sampleTypeOf<T>(), dims, "v");
  ArraySource reference(floats.data(), dims, "v");
  SCOPED_TRACE(sampleTypeName(typed.type()));
  EXPECT_EQ(typed.bytesPerVoxel(), int(sizeof(T)));
  std::vector<float> a(count), b(count);
  typed.readSlab(0, dims[2], a.data());
  EXPECT_TRUE(sameBits(a, floats)) << "every sample converts as static_cast<float>";
  for (int64_t z0 = 0; z0 < dims[2]; ++z0)
    for (int64_t nz = 1; z0 + nz <= dims[2]; ++nz) {
      const size_t n = size_t(dims[0] * dims[1] * nz);
      a.assign(n, -1.0f);
      b.assign(n, -2.0f);
      typed.readSlab(z0, nz, a.data());
      reference.readSlab(z0, nz, b.data());
      EXPECT_TRUE(sameBits(a, b)) << "planes " << z0 << " + " << nz;
      for (int64_t y0 = 0; y0 < dims[1]; ++y0)
        for (int64_t ny = 1; y0 + ny <= dims[1]; ++ny) {
          const size_t m = size_t(dims[0] * ny * nz);
          a.assign(m, -1.0f);
          b.assign(m, -2.0f);
          typed.readRows(z0, nz, y0, ny, a.data());
          reference.readRows(z0, nz, y0, ny, b.data());
          EXPECT_TRUE(sameBits(a, b))
              << "planes " << z0 << " + " << nz << ", rows " << y0 << " + " << ny;
        }
    }
  EXPECT_THROW(typed.readRows(0, 1, 3, 2, a.data()), InvalidArgument);
  EXPECT_THROW(typed.readSlab(2, 2, a.data()), InvalidArgument);
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// The encoder filter's former path: the samples copied to float, the ratio from the original size.
class FloatCopySource : public ArraySource {
 public:
  FloatCopySource(const float* data, Index3 dims, std::string name, int originalBytes)
      : ArraySource(data, dims, std::move(name)), bytes_(originalBytes) {}
  int bytesPerVoxel() const override { return bytes_; }

 private:
  int bytes_;
};

}  // namespace

TEST(SampleType, NamesSizesAndParsing) {
  for (SampleType t : kTypes) {
    EXPECT_EQ(parseSampleType(sampleTypeName(t)), t);
    EXPECT_NE(sampleTypeNames().find(sampleTypeName(t)), std::string::npos);
  }
  EXPECT_EQ(parseSampleType("float"), SampleType::Float32);
  EXPECT_EQ(parseSampleType("double"), SampleType::Float64);
  SampleType t{};
  EXPECT_FALSE(tryParseSampleType("complex64", t));
  EXPECT_FALSE(tryParseSampleType("Float32", t));
  try {
    parseSampleType("int128");
    ADD_FAILURE() << "int128 was parsed";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("'int128'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("uint64"), std::string::npos) << e.what();
  }
  EXPECT_EQ(sampleTypeSize(SampleType::Int8), 1);
  EXPECT_EQ(sampleTypeSize(SampleType::UInt16), 2);
  EXPECT_EQ(sampleTypeSize(SampleType::Float32), 4);
  EXPECT_EQ(sampleTypeSize(SampleType::UInt64), 8);
  static_assert(sampleTypeOf<signed char>() == SampleType::Int8);
  static_assert(sampleTypeOf<unsigned char>() == SampleType::UInt8);
  static_assert(sampleTypeOf<short>() == SampleType::Int16);
  static_assert(sampleTypeOf<unsigned int>() == SampleType::UInt32);
  static_assert(sampleTypeOf<long long>() == SampleType::Int64);
  static_assert(sampleTypeOf<unsigned long long>() == SampleType::UInt64);
  static_assert(sampleTypeOf<float>() == SampleType::Float32);
  static_assert(sampleTypeOf<double>() == SampleType::Float64);
  for (SampleType type : kTypes) {
    Index3 dims{};
    ASSERT_TRUE(parseRawName(std::string("v_2x3x4_") + sampleTypeName(type) + ".raw", dims, t));
    EXPECT_EQ(t, type);
  }
}

TEST(SampleType, SwappedBytesConvertAsTheirValue) {
  const std::vector<int16_t> i16 = {-2, 300, 32767};
  std::vector<unsigned char> swapped(i16.size() * 2);
  for (size_t i = 0; i < i16.size(); ++i) {
    unsigned char b[2];
    std::memcpy(b, &i16[i], 2);
    swapped[2 * i] = b[1];
    swapped[2 * i + 1] = b[0];
  }
  std::vector<float> out(i16.size());
  samplesToFloat(SampleType::Int16, swapped.data(), i16.size(), out.data(), true);
  EXPECT_TRUE(sameBits(out, staticCast(i16)));
  // Unaligned samples (a slab of a file at an odd offset).
  const std::vector<double> f64 = {1.5, -1e300, 0.1};
  std::vector<unsigned char> odd(1 + f64.size() * 8);
  std::memcpy(odd.data() + 1, f64.data(), f64.size() * 8);
  samplesToFloat(SampleType::Float64, odd.data() + 1, f64.size(), out.data());
  EXPECT_TRUE(sameBits(out, staticCast(f64)));
  EXPECT_TRUE(std::isinf(out[1]));
}

TEST(SampleType, ArraySourceOfEveryTypeReadsAsTheFloatArray) {
  checkTypedSource<int8_t>();
  checkTypedSource<uint8_t>();
  checkTypedSource<int16_t>();
  checkTypedSource<uint16_t>();
  checkTypedSource<int32_t>();
  checkTypedSource<uint32_t>();
  checkTypedSource<int64_t>();
  checkTypedSource<uint64_t>();
  checkTypedSource<float>();
  checkTypedSource<double>();
}

TEST(SampleType, TypedArrayEncodesTheFileOfItsFloatCopy) {
  const Index3 dims{23, 19, 17};
  const size_t count = size_t(dims[0] * dims[1] * dims[2]);
  std::vector<uint8_t> bytes(count);
  for (size_t i = 0; i < count; ++i) {
    const double x = double(i % 23), y = double(i / 23 % 19), z = double(i / (23 * 19));
    bytes[i] = uint8_t(127.5 + 120 * std::sin(0.3 * x) * std::cos(0.2 * y + 0.1 * z));
  }
  const std::vector<float> floats = staticCast(bytes);
  EncoderOptions o;
  o.levels = 2;
  o.blocksPerAxis = 2;
  o.errorBound = 1e-2;
  o.relativeBound = true;
  o.threads = 2;
  const std::string typedPath = afam_test::scratchPath("typed.afam");
  const std::string copyPath = afam_test::scratchPath("copy.afam");
  ArraySource typed(bytes.data(), SampleType::UInt8, dims, "density");
  FloatCopySource copy(floats.data(), dims, "density", 1);
  const EncodeStats a = encodeVolume(typed, o, typedPath);
  encodeVolume(copy, o, copyPath);
  const std::string typedBytes = slurp(typedPath), copyBytes = slurp(copyPath);
  ASSERT_FALSE(typedBytes.empty());
  EXPECT_TRUE(typedBytes == copyBytes) << "the uint8 array and its float copy give different files";
  EXPECT_EQ(a.bytesIn, uint64_t(count));
}
