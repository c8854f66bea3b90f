// SPDX-License-Identifier: BSD-3-Clause
// A real scan made large: a small volume resampled to any size, with noise at the new resolution,
// so that micro-blocks of the large volume cost what a real scan's blocks cost (smooth anatomy
// plus sample-to-sample noise), unlike an analytic field that compresses a thousandfold.
//
// Values: separable Catmull-Rom interpolation of the source (its samples span the same box as the
// new ones; clamped at the edges), plus Gaussian noise of standard deviation `noiseSigma`, drawn
// from a counter-based generator keyed by the voxel's index and the seed: any slab is generated
// on its own, the same bytes however the volume is cut into slabs. estimateScanNoise() gives the
// source's own noise level, the default.
//
// Optional detail at every scale (setDetail): a sum of octaves of value noise, lattice spacings
// 2, 4, 8, ... voxels up to a quarter of the largest axis (at most 128), each lattice value a
// hash of its integer coordinates, octave and seed, interpolated with a quintic fade; octave
// amplitudes in proportion to spacing^beta (amplitude ~ 1/f^beta), scaled so that the field's
// standard deviation is `sd`. A real scan has structure at every scale (tissue texture, vessels,
// folds); white noise on a smooth interpolation has none between the source's samples and the
// voxel, so that its coarse levels and its recorded paths' working sets are far smaller. The
// detail is added where the source shows tissue only: in full above 15% of the source's value
// range (from its lowest value), none below 5% (a scan's air keeps its noise alone, as a real
// scan's does: air made textured made nearly every block of a head complex, 93% against a real
// T1 MRI's 51%), a smooth step between. The noise may differ there too (setTissueNoise).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "afam/volume/volume_source.hpp"

namespace afam {

/// Noise standard deviation of a volume from its finest differences along x: the median absolute
/// difference of neighbouring samples / (0.6745 * sqrt(2)), robust to edges and smooth trends.
double estimateScanNoise(const std::vector<float>& samples, const Index3& dims);

class EnlargedScanSource : public VolumeSource {
 public:
  /// `samples` (dims, x fastest) are copied. `target`: samples per axis of the large volume, each
  /// >= 2. Values are clamped to [clampLo, clampHi] (the source type's range, say). Throws
  /// InvalidArgument for empty sources, target dims < 2, or a negative or non-finite sigma.
  EnlargedScanSource(std::vector<float> samples, Index3 dims, Index3 target, double noiseSigma,
                     uint64_t seed, double clampLo, double clampHi);
  Index3 dims() const override { return target_; }
  void readSlab(int64_t z0, int64_t zCount, float* out) override;
  /// Adds detail of standard deviation `sd` (the source's units; 0: none, the bytes of a source
  /// without it) with octave amplitudes ~ spacing^beta. Throws InvalidArgument for a negative or
  /// non-finite sd, or beta outside [0, 3].
  void setDetail(double sd, double beta = 0.5);
  /// Noise of standard deviation `sd` in tissue instead of the constructor's (which air keeps),
  /// blended as the detail is (tissueWeight): a real scan whose air is quiet and whose tissue's
  /// texture is above the bound. Throws InvalidArgument for a negative or non-finite sd.
  void setTissueNoise(double sd);

 private:
  struct Octave {
    int64_t spacing;
    float amplitude;
  };
  /// Where the detail ends and where it is whole, as shares of the source's value range.
  static constexpr float kAirShare[2] = {0.05f, 0.15f};
  /// The share of the detail a voxel of interpolated value v takes (0 in air, 1 in tissue).
  float tissueWeight(float v) const;
  /// Adds every detail octave's value at target plane z to `dst` (target_[0] * target_[1]).
  void addDetail(int64_t z, float* dst) const;
  void addOctave(const Octave& o, uint64_t key, int64_t z, float* dst) const;

  struct Taps {  // Catmull-Rom weights of 4 source samples starting at `first` (clamped)
    int64_t first[4];
    float weight[4];
  };
  static std::vector<Taps> taps(int64_t from, int64_t to);
  /// Source plane z resampled to the target's x and y (target_[0] * target_[1] floats).
  const std::vector<float>& plane(int64_t z);

  std::vector<float> source_;
  Index3 dims_, target_;
  double sigma_;
  uint64_t seed_;
  double lo_, hi_;
  std::vector<Taps> tx_, ty_, tz_;
  float airEnd_ = 0, tissueStart_ = 0;
  double tissueSigma_;
  std::vector<float> detail_;                                   ///< one plane's detail
  std::vector<float> weight_;                                   ///< one plane's tissueWeight
  std::vector<std::pair<int64_t, std::vector<float>>> planes_;  // a few resampled source planes
  std::vector<Octave> octaves_;                                 // empty: no detail
};

}  // namespace afam
