// SPDX-License-Identifier: BSD-3-Clause
// Which entropy stage an encoder gives its coded payloads (format/block_codec.hpp): zstd frames,
// lanes frames (lanes_coder.hpp, which a GPU decodes), or per payload the lanes frame unless zstd's
// is clearly smaller.
#pragma once

#include <string>

#include "afam/base/errors.hpp"

namespace afam {

/// Auto (the default): each payload's lanes frame, unless its zstd frame is more than
/// kLanesMargin smaller (small and smooth payloads, where zstd's matches code runs of zeros);
/// or one of them for every payload (Lanes: a file whose coded payloads a GPU decodes, at some
/// cost on smooth data).
enum class EntropyStage : unsigned char { Auto = 0, Zstd = 1, Lanes = 2 };

/// How much smaller a zstd frame must be for Auto to keep it over the lanes frame (which a GPU
/// decodes; on a scan's payloads the lanes frame is the smaller one anyway).
constexpr double kLanesMargin = 0.02;

/// Whether Auto keeps a lanes frame of `lanesBytes` over a zstd frame of `zstdBytes`.
inline bool keepsLanes(double lanesBytes, double zstdBytes) {
  return lanesBytes <= (1 + kLanesMargin) * zstdBytes;
}

struct EntropyCoding {
  int zstdLevel = 15;
  EntropyStage stage = EntropyStage::Auto;
};

/// "auto", "zstd", "lanes".
inline const char* entropyStageName(EntropyStage stage) {
  switch (stage) {
    case EntropyStage::Auto:
      return "auto";
    case EntropyStage::Zstd:
      return "zstd";
    case EntropyStage::Lanes:
      return "lanes";
  }
  return "?";
}

/// The stage a name gives; throws InvalidArgument naming the choices.
inline EntropyStage parseEntropyStage(const std::string& name) {
  for (const EntropyStage s : {EntropyStage::Auto, EntropyStage::Zstd, EntropyStage::Lanes})
    if (name == entropyStageName(s)) return s;
  throw InvalidArgument("unknown entropy stage '" + name + "' (auto, zstd or lanes)");
}

}  // namespace afam
