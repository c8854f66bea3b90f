// SPDX-License-Identifier: BSD-3-Clause
// The type of a volume's samples as they are stored (in a raw file, behind a NRRD or MetaImage
// header, in a caller's array, in an MPI rank's piece), and their one conversion to the float32
// the encoder fits: static_cast, as VTK converts an array's values.
#pragma once

#include <cstdint>
#include <string>
#include <type_traits>

namespace afam {

enum class SampleType : uint8_t {
  Int8,
  UInt8,
  Int16,
  UInt16,
  Int32,
  UInt32,
  Int64,
  UInt64,
  Float32,
  Float64
};

/// Bytes per sample: 1, 2, 4 or 8.
int sampleTypeSize(SampleType type);
/// "int8", "uint8", ..., "float32", "float64" (the names of raw files, name_XxYxZ_type.raw).
const char* sampleTypeName(SampleType type);
/// Every name, for messages: "int8, uint8, int16, uint16, int32, uint32, int64, uint64, float32 or
/// float64".
const std::string& sampleTypeNames();
/// A sampleTypeName, or "float" (float32) or "double" (float64); throws InvalidArgument naming the
/// accepted names for another.
SampleType parseSampleType(const std::string& name);
/// The same without throwing: false for a name parseSampleType refuses.
bool tryParseSampleType(const std::string& name, SampleType& type);

/// The SampleType of a C++ arithmetic type of 1 to 8 bytes (char and long included: by size and
/// signedness, whose conversion to float is the same).
template <class T>
constexpr SampleType sampleTypeOf() {
  static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>, "samples are numbers");
  if constexpr (std::is_floating_point_v<T>) {
    static_assert(sizeof(T) == 4 || sizeof(T) == 8, "float or double");
    return sizeof(T) == 4 ? SampleType::Float32 : SampleType::Float64;
  } else {
    static_assert(sizeof(T) == 1 || sizeof(T) == 2 || sizeof(T) == 4 || sizeof(T) == 8,
                  "1 to 8 bytes");
    constexpr bool s = std::is_signed_v<T>;
    switch (sizeof(T)) {
      case 1:
        return s ? SampleType::Int8 : SampleType::UInt8;
      case 2:
        return s ? SampleType::Int16 : SampleType::UInt16;
      case 4:
        return s ? SampleType::Int32 : SampleType::UInt32;
      default:
        return s ? SampleType::Int64 : SampleType::UInt64;
    }
  }
}

/// Whether `type` is one that withCopyType names: a 1- or 2-byte integer, or float32.
constexpr bool isCopyType(SampleType type) {
  return type == SampleType::Int8 || type == SampleType::UInt8 || type == SampleType::Int16 ||
         type == SampleType::UInt16 || type == SampleType::Float32;
}

/// f(p) with p a null `const T*` of the C++ type of samples stored as `type` where it is a 1- or
/// 2-byte integer, else float32's (the types a copy of a volume holds: level_sampler.hpp; the
/// planes the sampling reads): one switch for the code templated on them.
template <typename F>
decltype(auto) withCopyType(SampleType type, F&& f) {
  switch (type) {
    case SampleType::Int8:
      return f(static_cast<const int8_t*>(nullptr));
    case SampleType::UInt8:
      return f(static_cast<const uint8_t*>(nullptr));
    case SampleType::Int16:
      return f(static_cast<const int16_t*>(nullptr));
    case SampleType::UInt16:
      return f(static_cast<const uint16_t*>(nullptr));
    default:
      return f(static_cast<const float*>(nullptr));
  }
}

/// out[i] = static_cast<float>(sample i), for `count` samples of `type` at `samples` (any
/// alignment); `swapBytes` reverses each sample's bytes first (big-endian data on this host).
void samplesToFloat(SampleType type, const void* samples, uint64_t count, float* out,
                    bool swapBytes = false);

/// The values a sample of `type` can hold (integers: exactly; floats: +-their largest finite
/// value).
void sampleTypeRange(SampleType type, double& lo, double& hi);

/// The inverse, for volumes written in a type (generated scans): each value rounded to the
/// nearest integer and clamped to the type's range for integer types, converted for float types,
/// stored little-endian at `samples`.
void floatToSamples(SampleType type, const float* values, uint64_t count, void* samples);

}  // namespace afam
