// SPDX-License-Identifier: BSD-3-Clause
// Opening an input volume: a raw file from --dims/--type or from its name (name_XxYxZ_type.raw),
// or a NRRD / MetaImage file from its header (volume_formats.hpp).
#pragma once

#include <memory>
#include <string>

#include "afam/encode/encoder.hpp"
#include "afam/volume/volume_formats.hpp"
#include "cli.hpp"

namespace afam::cli {

inline std::array<double, 3> parseSpacing(const std::string& s) {
  std::array<double, 3> spacing{1, 1, 1};
  size_t start = 0;
  for (int a = 0; a < 3; ++a) {
    const size_t c = s.find(',', start);
    try {
      spacing[a] =
          std::stod(s.substr(start, c == std::string::npos ? std::string::npos : c - start));
    } catch (...) {
      throw InvalidArgument("--spacing: '" + s + "' is not SX,SY,SZ");
    }
    if (c == std::string::npos && a < 2)
      throw InvalidArgument("--spacing: '" + s + "' is not SX,SY,SZ");
    start = c + 1;
  }
  return spacing;
}

inline std::unique_ptr<RawFileSource> openRaw(const std::string& path, const Args& args) {
  Index3 dims{};
  SampleType type = SampleType::Float32;
  const bool named = parseRawName(path, dims, type);
  if (args.has("dims"))
    dims = Args::parseDims(args.str("dims"));
  else if (!named)
    throw InvalidArgument(path +
                          ": give --dims X,Y,Z (the name does not follow name_XxYxZ_type.raw)");
  if (args.has("type")) type = parseSampleType(args.str("type"));
  std::array<double, 3> spacing{1, 1, 1}, origin{0, 0, 0};
  if (args.has("spacing")) spacing = parseSpacing(args.str("spacing"));
  return std::make_unique<RawFileSource>(path, dims, type, origin, spacing);
}

/// An opened input and the name of its sample type (for the summary line).
struct InputVolume {
  std::unique_ptr<VolumeSource> source;
  std::string typeName;
};

/// .nrrd/.nhdr/.mha/.mhd through their headers (--spacing overrides the header's; --dims and
/// --type are refused: the header gives them), anything else as raw (openRaw).
inline InputVolume openInput(const std::string& path, const Args& args) {
  if (!hasVolumeHeaderExtension(path)) {
    auto raw = openRaw(path, args);
    const std::string type = sampleTypeName(raw->type());
    return {std::move(raw), type};
  }
  if (args.has("dims") || args.has("type"))
    throw InvalidArgument(path + ": --dims and --type are for raw files; the header gives them");
  VolumeFileHeader header = readVolumeHeader(path);
  if (args.has("spacing")) header.spacing = parseSpacing(args.str("spacing"));
  const std::string type = sampleTypeName(header.type);
  return {std::make_unique<HeaderVolumeSource>(std::move(header)), type};
}

}  // namespace afam::cli
