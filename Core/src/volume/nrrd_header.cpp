// SPDX-License-Identifier: BSD-3-Clause
// NRRD headers (teem's format, versions NRRD0001-NRRD0005): the fields a 3-D scalar volume needs.
#include <cmath>
#include <map>

#include "afam/base/errors.hpp"
#include "afam/volume/volume_formats.hpp"
#include "header_text.hpp"

namespace afam {

using namespace header_text;

namespace {

SampleType nrrdType(const std::string& path, const std::string& value) {
  static const std::map<std::string, SampleType> kTypes = {
      {"signed char", SampleType::Int8},
      {"int8", SampleType::Int8},
      {"int8_t", SampleType::Int8},
      {"uchar", SampleType::UInt8},
      {"unsigned char", SampleType::UInt8},
      {"uint8", SampleType::UInt8},
      {"uint8_t", SampleType::UInt8},
      {"short", SampleType::Int16},
      {"short int", SampleType::Int16},
      {"signed short", SampleType::Int16},
      {"signed short int", SampleType::Int16},
      {"int16", SampleType::Int16},
      {"int16_t", SampleType::Int16},
      {"ushort", SampleType::UInt16},
      {"unsigned short", SampleType::UInt16},
      {"unsigned short int", SampleType::UInt16},
      {"uint16", SampleType::UInt16},
      {"uint16_t", SampleType::UInt16},
      {"int", SampleType::Int32},
      {"signed int", SampleType::Int32},
      {"int32", SampleType::Int32},
      {"int32_t", SampleType::Int32},
      {"uint", SampleType::UInt32},
      {"unsigned int", SampleType::UInt32},
      {"uint32", SampleType::UInt32},
      {"uint32_t", SampleType::UInt32},
      {"longlong", SampleType::Int64},
      {"long long", SampleType::Int64},
      {"long long int", SampleType::Int64},
      {"signed long long", SampleType::Int64},
      {"signed long long int", SampleType::Int64},
      {"int64", SampleType::Int64},
      {"int64_t", SampleType::Int64},
      {"ulonglong", SampleType::UInt64},
      {"unsigned long long", SampleType::UInt64},
      {"unsigned long long int", SampleType::UInt64},
      {"uint64", SampleType::UInt64},
      {"uint64_t", SampleType::UInt64},
      {"float", SampleType::Float32},
      {"double", SampleType::Float64},
  };
  const auto it = kTypes.find(lowercase(value));
  if (it == kTypes.end())
    fieldError(path, "type",
               "unknown or unsupported type '" + value +
                   "' (8- to 64-bit integers, float and double are read)");
  return it->second;
}

bool nrrdCompressed(const std::string& path, const std::string& value) {
  const std::string v = lowercase(value);
  if (v == "raw") return false;
  if (v == "gzip" || v == "gz") return true;
  fieldError(path, "encoding", "'" + value + "' is not supported (raw or gzip)");
}

/// "(a,b,c)" -> its three numbers.
std::array<double, 3> nrrdVector(const std::string& path, const std::string& field,
                                 const std::string& token) {
  if (token.size() < 2 || token.front() != '(' || token.back() != ')')
    fieldError(path, field, "'" + token + "' is not a vector (x,y,z)");
  std::string inner = token.substr(1, token.size() - 2);
  for (char& c : inner)
    if (c == ',') c = ' ';
  const std::vector<std::string> w = words(inner);
  if (w.size() != 3) fieldError(path, field, "'" + token + "' does not have 3 components");
  return {parseReal(path, field, w[0]), parseReal(path, field, w[1]), parseReal(path, field, w[2])};
}

/// Space directions: one vector per axis; the spacing is its length.
std::array<double, 3> spacingFromDirections(const std::string& path, const std::string& value) {
  std::string compact;  // vectors may hold spaces after commas: "(1, 0, 0)"
  int depth = 0;
  for (char c : value) {
    if (c == '(') ++depth;
    if (c == ')') --depth;
    if (depth > 0 && (c == ' ' || c == '\t')) continue;
    compact.push_back(c);
  }
  const std::vector<std::string> w = threeWords(path, "space directions", compact);
  std::array<double, 3> s{};
  for (int a = 0; a < 3; ++a) {
    const auto d = nrrdVector(path, "space directions", w[size_t(a)]);
    s[size_t(a)] = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(s[size_t(a)] > 0))
      fieldError(path, "space directions", "axis " + std::to_string(a) + " has length 0");
  }
  return s;
}

std::string canonicalKey(const std::string& key) {
  if (key == "datafile") return "data file";
  if (key == "byteskip") return "byte skip";
  if (key == "lineskip") return "line skip";
  return key;
}

void applyField(VolumeFileHeader& h, const std::string& key, const std::string& value,
                std::map<std::string, bool>& seen) {
  const std::string& p = h.headerPath;
  seen[key] = true;
  if (key == "dimension") {
    if (parseInteger(p, key, value) != 3)
      fieldError(p, key, value + " axes; a 3-D scalar volume (dimension: 3) is needed");
  } else if (key == "type") {
    h.type = nrrdType(p, value);
  } else if (key == "sizes") {
    const auto w = threeWords(p, key, value);
    for (int a = 0; a < 3; ++a) {
      h.dims[size_t(a)] = parseInteger(p, key, w[size_t(a)]);
      if (h.dims[size_t(a)] < 1) fieldError(p, key, "'" + value + "': sizes must be >= 1");
    }
  } else if (key == "encoding") {
    h.compressed = nrrdCompressed(p, value);
  } else if (key == "endian") {
    const std::string v = lowercase(value);
    if (v != "little" && v != "big")
      fieldError(p, key, "'" + value + "' is neither little nor big");
    h.bigEndian = v == "big";
  } else if (key == "spacings") {
    const auto w = threeWords(p, key, value);
    for (int a = 0; a < 3; ++a) {
      const double s = parseReal(p, key, w[size_t(a)], true);
      if (!std::isnan(s) && !(s > 0))
        fieldError(p, key, "'" + value + "': spacings must be positive");
      h.spacing[size_t(a)] = std::isnan(s) ? 1.0 : s;
    }
  } else if (key == "space directions") {
    h.spacing = spacingFromDirections(p, value);
  } else if (key == "space origin") {
    h.origin = nrrdVector(p, key, trim(value));
  } else if (key == "data file") {
    if (words(value).size() != 1 || value.find('%') != std::string::npos ||
        lowercase(words(value)[0]) == "list")
      fieldError(p, key, "'" + value + "': several data files are not supported (one file is)");
    h.dataPath = siblingPath(p, trim(value));
  } else if (key == "byte skip") {
    h.byteSkip = parseInteger(p, key, value);
    if (h.byteSkip < -1) fieldError(p, key, "'" + value + "' must be -1 or >= 0");
  } else if (key == "line skip") {
    h.lineSkip = parseInteger(p, key, value);
    if (h.lineSkip < 0) fieldError(p, key, "'" + value + "' must be >= 0");
  }
  // Other fields (kinds, centerings, space, content, min/max, ...) do not change the samples.
}

}  // namespace

VolumeFileHeader readNrrdHeader(const std::string& path) {
  VolumeFileHeader h;
  h.format = "NRRD";
  h.headerPath = path;
  HeaderLines lines(path, "NRRD");
  std::string line;
  lines.next(line);
  if (line.compare(0, 7, "NRRD000") != 0)
    fieldError(path, "magic", "the first line is not NRRD0001..NRRD0005: not a NRRD file");
  std::map<std::string, bool> seen;
  bool blank = false;
  while (lines.next(line)) {
    if (line.empty()) {
      blank = true;
      break;
    }
    if (line[0] == '#') continue;
    const size_t first = line.find(':');
    if (first != std::string::npos && first + 1 < line.size() && line[first + 1] == '=')
      continue;  // key:=value
    const size_t colon = line.find(": ");
    if (colon == std::string::npos || colon != first)
      fieldError(path, trim(line), "a header line is not 'field: value'");
    applyField(h, canonicalKey(lowercase(trim(line.substr(0, colon)))),
               trim(line.substr(colon + 2)), seen);
  }
  for (const char* required : {"dimension", "type", "sizes", "encoding"})
    if (!seen[required]) fieldError(path, required, "missing");
  if (sampleTypeSize(h.type) > 1 && !seen["endian"])
    fieldError(path, "endian", "missing (needed for multi-byte types)");
  if (h.dataPath.empty()) {
    if (!blank) fieldError(path, "data file", "missing, and no data follow the header");
    h.dataPath = path;
    h.dataOffset = lines.offset();
    if (seen["byte skip"] || seen["line skip"])
      fieldError(path, seen["byte skip"] ? "byte skip" : "line skip",
                 "only for a detached data file");
  }
  if (h.compressed && h.byteSkip == -1)
    fieldError(path, "byte skip", "-1 is only for raw encoding");
  return h;
}

}  // namespace afam
