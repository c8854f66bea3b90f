// SPDX-License-Identifier: BSD-3-Clause
#include "afam/base/atomic_write.hpp"

#include <cstdio>
#include <fstream>

#include "afam/base/errors.hpp"

namespace afam {

void writeFileAtomically(const std::string& path, const void* data, std::size_t bytes,
                         const std::string& what) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError("cannot open '" + tmp + "' for writing the " + what);
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw IoError("writing the " + what + " '" + tmp + "' failed (disk full?)");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw IoError("cannot rename '" + tmp + "' to '" + path + "'");
  }
}

}  // namespace afam
