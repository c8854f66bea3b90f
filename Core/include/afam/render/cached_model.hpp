// SPDX-License-Identifier: BSD-3-Clause
// What the RAM cache holds of one micro-model (cache.hpp): its float32 control points, or, in the
// stored form (for a caster that decodes payloads itself, a GPU's), its payload as stored.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "afam/format/compact_form.hpp"

namespace afam {

/// A cached model: its float32 control points (the vector itself); or its compact form
/// (compact.width > 0: block_codec.hpp's CompactForm, a table of values and a 1- or 2-byte code a
/// control point, in the vector's floats); or, in the stored form, no floats and the payload's
/// stored bytes. (A vector with more members, so that code reading floats reads them as from any
/// vector; the shared_ptr deletes it as what it is.)
struct CachedModel : std::vector<float> {
  using std::vector<float>::vector;
  std::vector<uint8_t> stored;  ///< the stored form's bytes (empty: the floats are the model)
  CompactForm compact;          ///< width 0: the vector holds float32 control points
  bool isStored() const { return !stored.empty(); }
  /// Whether the vector holds the model's control points as float32, one a point.
  bool hasFloats() const { return !isStored() && compact.width == 0; }
  /// Bytes the model holds in RAM (what the cache's budget counts).
  uint64_t bytes() const { return isStored() ? stored.size() : size() * sizeof(float); }
};
using Payload = std::shared_ptr<const CachedModel>;

struct ModelEntry;
/// Which entries a cache keeps in the stored form (null: none).
using StoredForm = bool (*)(const ModelEntry& entry);

}  // namespace afam
