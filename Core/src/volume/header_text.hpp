// SPDX-License-Identifier: BSD-3-Clause
// Reading the text headers of NRRD and MetaImage files: lines with their byte offsets, and numbers
// parsed with errors that name the file and the field. Private to Core/src/volume_formats.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace afam::header_text {

/// Reads a header line by line. The constructor throws IoError when the file cannot be opened or
/// read, is not a regular file, or is empty.
class HeaderLines {
 public:
  HeaderLines(const std::string& path, const char* format);
  ~HeaderLines();
  HeaderLines(const HeaderLines&) = delete;
  HeaderLines& operator=(const HeaderLines&) = delete;
  /// The next line without its "\n" or "\r\n"; false at the end of the file. Throws FormatError
  /// for a line longer than 64 KiB or a header longer than 1 MiB (binary data, not a header).
  bool next(std::string& line);
  /// Bytes consumed so far: after a line, the offset of the next one.
  uint64_t offset() const { return offset_; }

 private:
  std::string path_;
  const char* format_;
  std::FILE* file_ = nullptr;
  uint64_t offset_ = 0;
};

/// "PATH: field 'FIELD': WHAT" (FormatError).
[[noreturn]] void fieldError(const std::string& path, const std::string& field,
                             const std::string& what);

std::string trim(const std::string& s);
std::string lowercase(std::string s);
std::vector<std::string> words(const std::string& s);
int64_t parseInteger(const std::string& path, const std::string& field, const std::string& token);
/// A finite real; "nan" is accepted only when allowNan (NRRD's "no spacing") and gives NaN.
double parseReal(const std::string& path, const std::string& field, const std::string& token,
                 bool allowNan = false);
/// Exactly three values of a field.
std::vector<std::string> threeWords(const std::string& path, const std::string& field,
                                    const std::string& value);
/// `name` relative to the folder of `headerPath` (unchanged when absolute).
std::string siblingPath(const std::string& headerPath, const std::string& name);

}  // namespace afam::header_text
