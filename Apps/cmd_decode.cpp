// SPDX-License-Identifier: BSD-3-Clause
// afam decode FILE.afam --level K OUT.raw
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/render/level_decode.hpp"
#include "cli.hpp"
#include "commands.hpp"

namespace afam::cli {

int runDecode(int argc, char** argv) {
  Args args(argc, argv, {"level"}, {"progress"});
  const char* usage = "afam decode FILE.afam --level K OUT.raw";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "Evaluates every micro-model of level K (0 = coarsest; default the finest) on its sample\n"
        "grid and writes the level's grid as little-endian float32, x fastest, blocks joined on\n"
        "their shared boundary samples. Streams one row of blocks at a time. Prints the dims.\n",
        usage);
    return 0;
  }
  args.expectPositional(2, usage);
  auto f = AfamFile::open(args.positional()[0]);
  const VolumeHeader& h = f->header();
  const Partition& part = f->partition();
  const int level = int(args.integer("level", h.levels - 1));
  if (level < 0 || level >= h.levels)
    throw InvalidArgument("--level " + std::to_string(level) + " outside [0, " +
                          std::to_string(h.levels - 1) + "]");
  const Int3 nb = part.blocksPerAxis(level);
  // Output grid: per axis the blocks' samples joined on shared boundaries.
  const LevelGrid grid = levelGrid(part, level);
  const Index3 od = grid.dims;
  const auto& start = grid.start;
  const std::string out = args.positional()[1], tmp = out + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw IoError(tmp + ": cannot create: " + std::strerror(errno));
  ProgressBar bar("decode", args.has("progress"));
  try {
    std::vector<float> slab;
    for (int kz = 0; kz < nb[2]; ++kz) {
      const int nz = part.extent(level, {0, 0, kz}).samples[2];
      const int64_t z0 = start[2][size_t(kz)];
      const int64_t planes =
          kz + 1 < nb[2] ? nz - 1 : nz;  // the shared plane goes with the next row
      slab.resize(size_t(od[0] * od[1] * planes));
      decodeLevelBox(*f, level, {0, 0, z0}, {od[0] - 1, od[1] - 1, z0 + planes - 1}, slab.data());
      const size_t bytes = size_t(planes * od[0] * od[1]) * sizeof(float);
      const off_t off = off_t(size_t(z0 * od[0] * od[1]) * sizeof(float));
      const char* p = reinterpret_cast<const char*>(slab.data());
      size_t done = 0;
      while (done < bytes) {
        const ssize_t w = ::pwrite(fd, p + done, bytes - done, off + off_t(done));
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) throw IoError(tmp + ": write failed: " + std::strerror(errno));
        done += size_t(w);
      }
      bar(double(kz + 1) / double(nb[2]));
    }
    if (::fsync(fd) != 0 || ::close(fd) != 0)
      throw IoError(tmp + ": cannot flush: " + std::strerror(errno));
    if (::rename(tmp.c_str(), out.c_str()) != 0)
      throw IoError(out + ": cannot rename: " + std::strerror(errno));
  } catch (...) {
    ::close(fd);
    ::unlink(tmp.c_str());
    throw;
  }
  bar.finish();
  std::printf("wrote %s: level %d, %lldx%lldx%lld float32\n", out.c_str(), level, (long long)od[0],
              (long long)od[1], (long long)od[2]);
  return 0;
}

}  // namespace afam::cli
