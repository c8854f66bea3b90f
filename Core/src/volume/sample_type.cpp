// SPDX-License-Identifier: BSD-3-Clause
#include "afam/volume/sample_type.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <type_traits>

#include "afam/base/errors.hpp"

namespace afam {

namespace {

constexpr SampleType kAllTypes[] = {SampleType::Int8,   SampleType::UInt8,  SampleType::Int16,
                                    SampleType::UInt16, SampleType::Int32,  SampleType::UInt32,
                                    SampleType::Int64,  SampleType::UInt64, SampleType::Float32,
                                    SampleType::Float64};

/// Bytes copied out one sample at a time: the samples may sit at any alignment (a slab of a file,
/// a piece of an MPI window); the compiler turns each copy into one load.
template <class T, bool Swap>
void toFloat(const unsigned char* src, uint64_t count, float* out) {
  for (uint64_t i = 0; i < count; ++i) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, src + i * sizeof(T), sizeof(T));
    if constexpr (Swap) std::reverse(b, b + sizeof(T));
    T v;
    std::memcpy(&v, b, sizeof(T));
    out[i] = static_cast<float>(v);
  }
}

template <class T>
void toFloat(const unsigned char* src, uint64_t count, float* out, bool swap) {
  if (swap && sizeof(T) > 1)
    toFloat<T, true>(src, count, out);
  else
    toFloat<T, false>(src, count, out);
}

template <class T>
void fromFloat(const float* values, uint64_t count, unsigned char* dst) {
  for (uint64_t i = 0; i < count; ++i) {
    T v;
    if constexpr (std::is_floating_point_v<T>) {
      v = static_cast<T>(values[i]);
    } else {
      const double r = std::nearbyint(double(values[i]));
      const double lo = double(std::numeric_limits<T>::lowest()),
                   hi = double(std::numeric_limits<T>::max());
      v = r <= lo   ? std::numeric_limits<T>::lowest()
          : r >= hi ? std::numeric_limits<T>::max()
                    : static_cast<T>(r);
    }
    std::memcpy(dst + i * sizeof(T), &v, sizeof(T));
  }
}

template <class T>
void rangeOf(double& lo, double& hi) {
  lo = double(std::numeric_limits<T>::lowest());
  hi = double(std::numeric_limits<T>::max());
}

}  // namespace

int sampleTypeSize(SampleType type) {
  switch (type) {
    case SampleType::Int8:
    case SampleType::UInt8:
      return 1;
    case SampleType::Int16:
    case SampleType::UInt16:
      return 2;
    case SampleType::Int32:
    case SampleType::UInt32:
    case SampleType::Float32:
      return 4;
    case SampleType::Int64:
    case SampleType::UInt64:
    case SampleType::Float64:
      return 8;
  }
  return 1;
}

const char* sampleTypeName(SampleType type) {
  switch (type) {
    case SampleType::Int8:
      return "int8";
    case SampleType::UInt8:
      return "uint8";
    case SampleType::Int16:
      return "int16";
    case SampleType::UInt16:
      return "uint16";
    case SampleType::Int32:
      return "int32";
    case SampleType::UInt32:
      return "uint32";
    case SampleType::Int64:
      return "int64";
    case SampleType::UInt64:
      return "uint64";
    case SampleType::Float32:
      return "float32";
    case SampleType::Float64:
      return "float64";
  }
  return "unknown";
}

const std::string& sampleTypeNames() {
  static const std::string names = [] {
    std::string s;
    const size_t n = std::size(kAllTypes);
    for (size_t i = 0; i < n; ++i)
      s += std::string(i == 0 ? "" : i + 1 == n ? " or " : ", ") + sampleTypeName(kAllTypes[i]);
    return s;
  }();
  return names;
}

bool tryParseSampleType(const std::string& name, SampleType& type) {
  for (SampleType t : kAllTypes)
    if (name == sampleTypeName(t)) {
      type = t;
      return true;
    }
  if (name == "float" || name == "double") {
    type = name == "float" ? SampleType::Float32 : SampleType::Float64;
    return true;
  }
  return false;
}

SampleType parseSampleType(const std::string& name) {
  SampleType type{};
  if (!tryParseSampleType(name, type))
    throw InvalidArgument("unknown sample type '" + name + "' (expected " + sampleTypeNames() +
                          ")");
  return type;
}

void samplesToFloat(SampleType type, const void* samples, uint64_t count, float* out,
                    bool swapBytes) {
  const auto* src = static_cast<const unsigned char*>(samples);
  switch (type) {
    case SampleType::Int8:
      return toFloat<int8_t>(src, count, out, false);
    case SampleType::UInt8:
      return toFloat<uint8_t>(src, count, out, false);
    case SampleType::Int16:
      return toFloat<int16_t>(src, count, out, swapBytes);
    case SampleType::UInt16:
      return toFloat<uint16_t>(src, count, out, swapBytes);
    case SampleType::Int32:
      return toFloat<int32_t>(src, count, out, swapBytes);
    case SampleType::UInt32:
      return toFloat<uint32_t>(src, count, out, swapBytes);
    case SampleType::Int64:
      return toFloat<int64_t>(src, count, out, swapBytes);
    case SampleType::UInt64:
      return toFloat<uint64_t>(src, count, out, swapBytes);
    case SampleType::Float32:
      if (!swapBytes) {
        std::memmove(out, src, size_t(count) * sizeof(float));  // the same bits: a copy
        return;
      }
      return toFloat<float>(src, count, out, true);
    case SampleType::Float64:
      return toFloat<double>(src, count, out, swapBytes);
  }
}

namespace {

/// One switch over the types, calling fn with a value of the type (its tag).
template <class Fn>
void withType(SampleType type, Fn&& fn) {
  switch (type) {
    case SampleType::Int8:
      return fn(int8_t{});
    case SampleType::UInt8:
      return fn(uint8_t{});
    case SampleType::Int16:
      return fn(int16_t{});
    case SampleType::UInt16:
      return fn(uint16_t{});
    case SampleType::Int32:
      return fn(int32_t{});
    case SampleType::UInt32:
      return fn(uint32_t{});
    case SampleType::Int64:
      return fn(int64_t{});
    case SampleType::UInt64:
      return fn(uint64_t{});
    case SampleType::Float32:
      return fn(float{});
    case SampleType::Float64:
      return fn(double{});
  }
}

}  // namespace

void sampleTypeRange(SampleType type, double& lo, double& hi) {
  withType(type, [&](auto tag) { rangeOf<decltype(tag)>(lo, hi); });
}

void floatToSamples(SampleType type, const float* values, uint64_t count, void* samples) {
  withType(type, [&](auto tag) {
    fromFloat<decltype(tag)>(values, count, static_cast<unsigned char*>(samples));
  });
}

}  // namespace afam
