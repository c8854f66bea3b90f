// SPDX-License-Identifier: BSD-3-Clause
#include "level_error.hpp"

#include <memory>
#include <string>
#include <vector>

#include "afam/volume/missing_value_source.hpp"

namespace afam::cli {

namespace {

// Compares the samples that block (i, j, kz) owns on the level grid (a shared boundary sample
// belongs to the later block, as in decodeLevelBox) with the original's samples of that block.
void addBlock(const AfamFile& file, const LevelGrid& grid, int level, Int3 ijk, const Int3& samples,
              const std::vector<float>& original, std::vector<float>& decoded,
              std::vector<float>& reference, ErrorAccumulator& acc) {
  Index3 lo{}, hi{};
  for (int a = 0; a < 3; ++a) {
    const auto& start = grid.start[size_t(a)];
    lo[a] = start[size_t(ijk[a])];
    hi[a] = size_t(ijk[a]) + 1 < start.size() ? start[size_t(ijk[a]) + 1] - 1 : grid.dims[a] - 1;
  }
  const int64_t nx = hi[0] - lo[0] + 1, ny = hi[1] - lo[1] + 1, nz = hi[2] - lo[2] + 1;
  decoded.resize(size_t(nx * ny * nz));
  decodeLevelBox(file, level, lo, hi, decoded.data());
  reference.resize(decoded.size());
  for (int64_t z = 0; z < nz; ++z)
    for (int64_t y = 0; y < ny; ++y)
      for (int64_t x = 0; x < nx; ++x)
        reference[size_t((z * ny + y) * nx + x)] =
            original[size_t((z * samples[1] + y) * samples[0] + x)];
  acc.add(decoded.data(), reference.data(), int64_t(decoded.size()));
}

}  // namespace

ErrorAccumulator measureLevelError(const AfamFile& file, VolumeSource& original, int level,
                                   const std::function<void(double)>& progress) {
  const Partition& part = file.partition();
  if (original.dims() != file.header().dims)
    throw InvalidArgument("the original volume's dims differ from the .afam file's");
  if (level < 0 || level >= part.levels())
    throw InvalidArgument("level " + std::to_string(level) + " outside [0, " +
                          std::to_string(part.levels() - 1) + "]");
  const LevelGrid grid = levelGrid(part, level);
  const Int3 nb = part.blocksPerAxis(level);
  // The file's fill value marks missing samples of the original as it did for the encoder.
  std::unique_ptr<MissingValueSource> filled;
  if (file.header().missing == MissingKind::Value)
    filled = std::make_unique<MissingValueSource>(original, file.header().missingValue);
  BlockRowReader reader(filled ? *filled : original, part);
  std::vector<std::vector<float>> row;
  std::vector<float> decoded, reference;
  ErrorAccumulator acc;
  for (int kz = 0; kz < nb[2]; ++kz) {
    reader.readRow(level, kz, false, file.header().sampling, row);
    for (int j = 0; j < nb[1]; ++j)
      for (int i = 0; i < nb[0]; ++i) {
        const Int3 ijk{i, j, kz};
        addBlock(file, grid, level, ijk, part.extent(level, ijk).samples,
                 row[size_t(j) * size_t(nb[0]) + size_t(i)], decoded, reference, acc);
      }
    if (progress) progress(double(kz + 1) / double(nb[2]));
  }
  return acc;
}

}  // namespace afam::cli
