// SPDX-License-Identifier: BSD-3-Clause
#include "afam/volume/sample_type.hpp"

#include <algorithm>
#include <cstring>
#include <iterator>

#include "afam/base/errors.hpp"

namespace afam {

namespace {

constexpr SampleType kAllTypes[] = {SampleType::Int8,   SampleType::UInt8,  SampleType::Int16,   SampleType::UInt16,
                                    SampleType::Int32,  SampleType::UInt32, SampleType::Int64,   SampleType::UInt64,
                                    SampleType::Float32, SampleType::Float64};

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
  if (swap && sizeof(T) > 1) toFloat<T, true>(src, count, out);
  else toFloat<T, false>(src, count, out);
}

}  // namespace

int sampleTypeSize(SampleType type) {
  switch (type) {
    case SampleType::Int8:
    case SampleType::UInt8: return 1;
    case SampleType::Int16:
    case SampleType::UInt16: return 2;
    case SampleType::Int32:
    case SampleType::UInt32:
    case SampleType::Float32: return 4;
    case SampleType::Int64:
    case SampleType::UInt64:
    case SampleType::Float64: return 8;
  }
  return 1;
}

const char* sampleTypeName(SampleType type) {
  switch (type) {
    case SampleType::Int8: return "int8";
    case SampleType::UInt8: return "uint8";
    case SampleType::Int16: return "int16";
    case SampleType::UInt16: return "uint16";
    case SampleType::Int32: return "int32";
    case SampleType::UInt32: return "uint32";
    case SampleType::Int64: return "int64";
    case SampleType::UInt64: return "uint64";
    case SampleType::Float32: return "float32";
    case SampleType::Float64: return "float64";
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
    throw InvalidArgument("unknown sample type '" + name + "' (expected " + sampleTypeNames() + ")");
  return type;
}

void samplesToFloat(SampleType type, const void* samples, uint64_t count, float* out, bool swapBytes) {
  const auto* src = static_cast<const unsigned char*>(samples);
  switch (type) {
    case SampleType::Int8: return toFloat<int8_t>(src, count, out, false);
    case SampleType::UInt8: return toFloat<uint8_t>(src, count, out, false);
    case SampleType::Int16: return toFloat<int16_t>(src, count, out, swapBytes);
    case SampleType::UInt16: return toFloat<uint16_t>(src, count, out, swapBytes);
    case SampleType::Int32: return toFloat<int32_t>(src, count, out, swapBytes);
    case SampleType::UInt32: return toFloat<uint32_t>(src, count, out, swapBytes);
    case SampleType::Int64: return toFloat<int64_t>(src, count, out, swapBytes);
    case SampleType::UInt64: return toFloat<uint64_t>(src, count, out, swapBytes);
    case SampleType::Float32:
      if (!swapBytes) {
        std::memmove(out, src, size_t(count) * sizeof(float));  // the same bits: a copy
        return;
      }
      return toFloat<float>(src, count, out, true);
    case SampleType::Float64: return toFloat<double>(src, count, out, swapBytes);
  }
}

}  // namespace afam
