// SPDX-License-Identifier: BSD-3-Clause
// Opening a raw input from --dims/--type or from its name (name_XxYxZ_type.raw).
#pragma once

#include <memory>
#include <string>

#include "afam/encoder.hpp"
#include "cli.hpp"

namespace afam::cli {

inline std::unique_ptr<RawFileSource> openRaw(const std::string& path, const Args& args) {
  Index3 dims{};
  ScalarType type = ScalarType::Float32;
  const bool named = parseRawName(path, dims, type);
  if (args.has("dims")) dims = Args::parseDims(args.str("dims"));
  else if (!named)
    throw InvalidArgument(path + ": give --dims X,Y,Z (the name does not follow name_XxYxZ_type.raw)");
  if (args.has("type")) type = parseScalarType(args.str("type"));
  std::array<double, 3> spacing{1, 1, 1}, origin{0, 0, 0};
  if (args.has("spacing")) {
    const std::string s = args.str("spacing");
    size_t start = 0;
    for (int a = 0; a < 3; ++a) {
      const size_t c = s.find(',', start);
      try {
        spacing[a] = std::stod(s.substr(start, c == std::string::npos ? std::string::npos : c - start));
      } catch (...) {
        throw InvalidArgument("--spacing: '" + s + "' is not SX,SY,SZ");
      }
      if (c == std::string::npos && a < 2) throw InvalidArgument("--spacing: '" + s + "' is not SX,SY,SZ");
      start = c + 1;
    }
  }
  return std::make_unique<RawFileSource>(path, dims, type, origin, spacing);
}

}  // namespace afam::cli
