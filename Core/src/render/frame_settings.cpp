// SPDX-License-Identifier: BSD-3-Clause
#include "afam/render/frame_settings.hpp"

#include <cmath>
#include <sstream>

#include "afam/render/raycast.hpp"

namespace afam {

namespace {

std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string points(const TransferFunction& tf) {
  return std::to_string(tf.colors.size()) + " colour and " + std::to_string(tf.opacities.size()) +
         " opacity points";
}

const char* blendName(int mode) {
  switch (mode) {
    case kBlendComposite:
      return "composite";
    case kBlendMaximum:
      return "maximum intensity";
    case kBlendMinimum:
      return "minimum intensity";
    case kBlendAverage:
      return "average intensity";
    default:
      return "unknown";
  }
}

}  // namespace

namespace {

/// The NaN colour and opacity's problem, or empty.
std::string nanColorProblem(const TransferFunction& tf) {
  const auto& nan = tf.nanColor;
  if (std::isfinite(nan[0]) && std::isfinite(nan[1]) && std::isfinite(nan[2]) &&
      tf.nanOpacity >= 0 && tf.nanOpacity <= 1)
    return {};
  return "the NaN colour (rgb " + number(nan[0]) + " " + number(nan[1]) + " " + number(nan[2]) +
         ", opacity " + number(tf.nanOpacity) +
         ") is not a finite colour with an opacity in [0, 1]";
}

/// The sampled table's problem (an entry that is not finite), or empty.
std::string sampledTableProblem(const TransferFunction& tf) {
  if (tf.sampled.size() % 4 != 0)
    return "the sampled transfer-function table has " + std::to_string(tf.sampled.size()) +
           " floats, not RGBA entries";
  for (size_t i = 0; i < tf.sampled.size(); ++i)
    if (!std::isfinite(tf.sampled[i]))
      return "entry " + std::to_string(i / 4) +
             " of the sampled transfer-function table is not finite";
  if (!std::isfinite(tf.sampledLo) || !(tf.sampledHi >= tf.sampledLo))
    return "the sampled transfer-function table's range " + number(tf.sampledLo) + " .. " +
           number(tf.sampledHi) + " is not a finite range";
  return {};
}

}  // namespace

std::string transferFunctionProblem(const TransferFunction& tf) {
  if (tf.colors.empty()) return "the colour transfer function has no points";
  if (tf.opacities.empty()) return "the opacity transfer function has no points";
  for (size_t i = 0; i < tf.colors.size(); ++i) {
    const ColorPoint& p = tf.colors[i];
    if (!std::isfinite(p.value) || !std::isfinite(p.r) || !std::isfinite(p.g) ||
        !std::isfinite(p.b))
      return "colour point " + std::to_string(i) + " (value " + number(p.value) + ", rgb " +
             number(p.r) + " " + number(p.g) + " " + number(p.b) + ") is not finite";
  }
  for (size_t i = 0; i < tf.opacities.size(); ++i) {
    const OpacityPoint& p = tf.opacities[i];
    if (!std::isfinite(p.value) || !(p.alpha >= 0 && p.alpha <= 1))
      return "opacity point " + std::to_string(i) + " (value " + number(p.value) + ", opacity " +
             number(p.alpha) + ") is not a finite value with an opacity in [0, 1]";
  }
  const std::string nan = nanColorProblem(tf);
  if (!nan.empty()) return nan;
  const std::string table = sampledTableProblem(tf);
  if (!table.empty()) return table;
  if (!(tf.referenceDistance > 0) || !std::isfinite(tf.referenceDistance))
    return "the opacity unit distance " + number(tf.referenceDistance) +
           " is not a finite number > 0";
  return {};
}

namespace {

std::string sampleDistanceProblem(const FrameSettings& s) {
  if (s.sampleDistance > 0 && std::isfinite(s.sampleDistance)) return {};
  return "sample distance " + number(s.sampleDistance) + " is not a finite number > 0";
}

std::string blendModeProblem(const FrameSettings& s) {
  if (s.blendMode >= kBlendComposite && s.blendMode <= kBlendAverage) return {};
  return "blend mode " + std::to_string(s.blendMode) +
         " is not 0 (composite), 1 (maximum), 2 (minimum) or 3 (average)";
}

std::string lodProblem(const FrameSettings& s) {
  if (!(s.lod.pixelBudget > 0) || !std::isfinite(s.lod.pixelBudget))
    return "LOD pixel budget " + number(s.lod.pixelBudget) + " is not a finite number > 0";
  if (!(s.lod.bandWidth > 0) || !std::isfinite(s.lod.bandWidth))
    return "LOD band width " + number(s.lod.bandWidth) + " is not a finite number > 0";
  return {};
}

std::string tableProblem(const FrameSettings& s) {
  if (s.tfTableSize >= 2 && s.tfTableSize <= (1 << 20)) return {};
  return "transfer-function table size " + std::to_string(s.tfTableSize) + " is not in [2, 2^20]";
}

std::string terminationProblem(const FrameSettings& s) {
  if (s.terminationOpacity > 0 && s.terminationOpacity <= 1) return {};
  return "termination opacity " + number(s.terminationOpacity) + " is not in (0, 1]";
}

std::string missBudgetProblem(const FrameSettings& s) {
  if (s.missBudgetMs <= kMaxMissBudgetMs) return {};  // negative: no budget
  return "miss budget " + number(s.missBudgetMs) + " ms is not a number of milliseconds up to " +
         number(kMaxMissBudgetMs) + " (an hour; negative: wait for every block)";
}

}  // namespace

std::string frameSettingsProblem(const FrameSettings& s) {
  for (const std::string& p : {sampleDistanceProblem(s), blendModeProblem(s), lodProblem(s),
                               tableProblem(s), terminationProblem(s), missBudgetProblem(s)})
    if (!p.empty()) return p;
  if (s.hasTransferFunction) return transferFunctionProblem(s.transferFunction);
  return nanColorProblem(s.transferFunction);  // kept over the preset
}

FrameSettings acceptFrameSettings(const FrameSettings& wanted, const FrameSettings& kept,
                                  std::vector<std::string>& warnings) {
  FrameSettings s = wanted;
  if (const std::string p = sampleDistanceProblem(wanted); !p.empty()) {
    s.sampleDistance = kept.sampleDistance;
    warnings.push_back(p + "; keeping " + number(kept.sampleDistance));
  }
  if (const std::string p = blendModeProblem(wanted); !p.empty()) {
    s.blendMode = kept.blendMode;
    warnings.push_back(p + "; keeping " + std::to_string(kept.blendMode) + " (" +
                       blendName(kept.blendMode) + ")");
  }
  if (const std::string p = lodProblem(wanted); !p.empty()) {
    s.lod = kept.lod;
    warnings.push_back(p + "; keeping pixel budget " + number(kept.lod.pixelBudget) +
                       " and band width " + number(kept.lod.bandWidth));
  }
  if (const std::string p = tableProblem(wanted); !p.empty()) {
    s.tfTableSize = kept.tfTableSize;
    warnings.push_back(p + "; keeping " + std::to_string(kept.tfTableSize));
  }
  if (const std::string p = terminationProblem(wanted); !p.empty()) {
    s.terminationOpacity = kept.terminationOpacity;
    warnings.push_back(p + "; keeping " + number(kept.terminationOpacity));
  }
  if (const std::string p = missBudgetProblem(wanted); !p.empty()) {
    s.missBudgetMs = kept.missBudgetMs;
    warnings.push_back(p + "; keeping " + number(kept.missBudgetMs) + " ms");
  }
  if (wanted.hasTransferFunction) {
    if (const std::string p = transferFunctionProblem(wanted.transferFunction); !p.empty()) {
      s.hasTransferFunction = kept.hasTransferFunction;
      s.transferFunction = kept.transferFunction;
      warnings.push_back(p + "; keeping the last transfer function that could be drawn (" +
                         (kept.hasTransferFunction ? points(kept.transferFunction)
                                                   : std::string("the file's default")) +
                         ")");
    }
  }
  return s;
}

}  // namespace afam
