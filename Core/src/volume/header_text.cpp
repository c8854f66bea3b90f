// SPDX-License-Identifier: BSD-3-Clause
#include "header_text.hpp"

#include <sys/stat.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <sstream>

#include "afam/base/errors.hpp"

namespace afam::header_text {

namespace {
constexpr size_t kMaxLine = 64 * 1024;
constexpr uint64_t kMaxHeader = 1024 * 1024;
}  // namespace

HeaderLines::HeaderLines(const std::string& path, const char* format)
    : path_(path), format_(format) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw IoError(path + ": cannot open " + format + " header: " + std::strerror(errno));
  if (!S_ISREG(st.st_mode))
    throw IoError(path + ": cannot read " + format + " header: not a regular file");
  if (st.st_size == 0) throw IoError(path + ": empty file, no " + std::string(format) + " header");
  file_ = std::fopen(path.c_str(), "rb");
  if (!file_) throw IoError(path + ": cannot open " + format + " header: " + std::strerror(errno));
}

HeaderLines::~HeaderLines() {
  if (file_) std::fclose(file_);
}

bool HeaderLines::next(std::string& line) {
  line.clear();
  int c = 0;
  bool any = false;
  while ((c = std::fgetc(file_)) != EOF) {
    any = true;
    ++offset_;
    if (c == '\n') break;
    line.push_back(char(c));
    if (line.size() > kMaxLine)
      throw FormatError(path_ + ": line longer than 64 KiB in the " + format_ +
                        " header (binary data?)");
  }
  if (std::ferror(file_))
    throw IoError(path_ + ": cannot read " + format_ + " header: " + std::strerror(errno));
  if (offset_ > kMaxHeader)
    throw FormatError(path_ + ": " + format_ +
                      " header longer than 1 MiB (no end of header found)");
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return any;
}

void fieldError(const std::string& path, const std::string& field, const std::string& what) {
  throw FormatError(path + ": field '" + field + "': " + what);
}

std::string trim(const std::string& s) {
  size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

std::string lowercase(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::vector<std::string> words(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

int64_t parseInteger(const std::string& path, const std::string& field, const std::string& token) {
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(token.c_str(), &end, 10);
  if (token.empty() || *end != '\0' || errno == ERANGE)
    fieldError(path, field, "'" + token + "' is not an integer");
  return int64_t(v);
}

double parseReal(const std::string& path, const std::string& field, const std::string& token,
                 bool allowNan) {
  if (allowNan && lowercase(token) == "nan") return std::nan("");
  char* end = nullptr;
  const double v = std::strtod(token.c_str(), &end);
  if (token.empty() || *end != '\0' || !std::isfinite(v))
    fieldError(path, field, "'" + token + "' is not a finite number");
  return v;
}

std::vector<std::string> threeWords(const std::string& path, const std::string& field,
                                    const std::string& value) {
  std::vector<std::string> w = words(value);
  if (w.size() != 3)
    fieldError(path, field,
               "'" + value + "' has " + std::to_string(w.size()) + " values; a 3-D volume needs 3");
  return w;
}

std::string siblingPath(const std::string& headerPath, const std::string& name) {
  if (!name.empty() && name[0] == '/') return name;
  const size_t slash = headerPath.find_last_of('/');
  return slash == std::string::npos ? name : headerPath.substr(0, slash + 1) + name;
}

}  // namespace afam::header_text
