// SPDX-License-Identifier: BSD-3-Clause
// MetaImage headers (ITK's MetaIO, .mha / .mhd): the fields a 3-D scalar volume needs.
#include <cmath>
#include <map>

#include "afam/base/errors.hpp"
#include "afam/volume/volume_formats.hpp"
#include "header_text.hpp"

namespace afam {

using namespace header_text;

namespace {

SampleType metaType(const std::string& path, const std::string& value) {
  static const std::map<std::string, SampleType> kTypes = {
      {"MET_CHAR", SampleType::Int8},       {"MET_UCHAR", SampleType::UInt8},
      {"MET_SHORT", SampleType::Int16},     {"MET_USHORT", SampleType::UInt16},
      {"MET_INT", SampleType::Int32},       {"MET_UINT", SampleType::UInt32},
      {"MET_LONG", SampleType::Int32},      {"MET_ULONG", SampleType::UInt32},
      {"MET_LONG_LONG", SampleType::Int64}, {"MET_ULONG_LONG", SampleType::UInt64},
      {"MET_FLOAT", SampleType::Float32},   {"MET_DOUBLE", SampleType::Float64},
  };
  const auto it = kTypes.find(value);
  if (it == kTypes.end())
    fieldError(path, "ElementType",
               "unknown or unsupported type '" + value +
                   "' (MET_CHAR, MET_UCHAR, MET_SHORT, MET_USHORT, MET_INT, MET_UINT, "
                   "MET_LONG_LONG, MET_ULONG_LONG, MET_FLOAT, MET_DOUBLE are read)");
  return it->second;
}

bool metaBool(const std::string& path, const std::string& field, const std::string& value) {
  const std::string v = lowercase(value);
  if (v == "true" || v == "1") return true;
  if (v == "false" || v == "0") return false;
  fieldError(path, field, "'" + value + "' is neither True nor False");
}

std::array<double, 3> metaTriple(const std::string& path, const std::string& field,
                                 const std::string& value, bool positive) {
  const auto w = threeWords(path, field, value);
  std::array<double, 3> r{};
  for (int a = 0; a < 3; ++a) {
    r[size_t(a)] = parseReal(path, field, w[size_t(a)]);
    if (positive && !(r[size_t(a)] > 0))
      fieldError(path, field, "'" + value + "': values must be positive");
  }
  return r;
}

struct MetaFields {
  std::map<std::string, std::string> values;  ///< by lower-case key
  bool has(const char* key) const { return values.count(key) != 0; }
  const std::string& at(const char* key) const { return values.at(key); }
};

void applyFields(VolumeFileHeader& h, const MetaFields& f) {
  const std::string& p = h.headerPath;
  if (f.has("objecttype") && lowercase(f.at("objecttype")) != "image")
    fieldError(p, "ObjectType", "'" + f.at("objecttype") + "' is not Image");
  if (!f.has("ndims")) fieldError(p, "NDims", "missing");
  if (parseInteger(p, "NDims", f.at("ndims")) != 3)
    fieldError(p, "NDims",
               f.at("ndims") + " dimensions; a 3-D scalar volume (NDims = 3) is needed");
  if (!f.has("dimsize")) fieldError(p, "DimSize", "missing");
  const auto w = threeWords(p, "DimSize", f.at("dimsize"));
  for (int a = 0; a < 3; ++a) {
    h.dims[size_t(a)] = parseInteger(p, "DimSize", w[size_t(a)]);
    if (h.dims[size_t(a)] < 1)
      fieldError(p, "DimSize", "'" + f.at("dimsize") + "': sizes must be >= 1");
  }
  if (!f.has("elementtype")) fieldError(p, "ElementType", "missing");
  h.type = metaType(p, f.at("elementtype"));
  if (f.has("elementnumberofchannels") &&
      parseInteger(p, "ElementNumberOfChannels", f.at("elementnumberofchannels")) != 1)
    fieldError(p, "ElementNumberOfChannels",
               f.at("elementnumberofchannels") + " channels; one (scalars) is read");
  if (f.has("binarydata") && !metaBool(p, "BinaryData", f.at("binarydata")))
    fieldError(p, "BinaryData", "ASCII data are not supported");
  for (const char* k : {"binarydatabyteordermsb", "elementbyteordermsb", "byteordermsb"})
    if (f.has(k)) h.bigEndian = metaBool(p, "BinaryDataByteOrderMSB", f.at(k));
  if (f.has("compresseddata")) h.compressed = metaBool(p, "CompressedData", f.at("compresseddata"));
  if (f.has("elementspacing"))
    h.spacing = metaTriple(p, "ElementSpacing", f.at("elementspacing"), true);
  else if (f.has("elementsize"))
    h.spacing = metaTriple(p, "ElementSize", f.at("elementsize"), true);
  const std::pair<const char*, const char*> kOrigins[] = {
      {"offset", "Offset"}, {"origin", "Origin"}, {"position", "Position"}};
  for (const auto& [key, name] : kOrigins)
    if (f.has(key)) h.origin = metaTriple(p, name, f.at(key), false);
  if (f.has("headersize")) {
    h.byteSkip = parseInteger(p, "HeaderSize", f.at("headersize"));
    if (h.byteSkip < -1)
      fieldError(p, "HeaderSize", "'" + f.at("headersize") + "' must be -1 or >= 0");
  }
}

}  // namespace

VolumeFileHeader readMetaImageHeader(const std::string& path) {
  VolumeFileHeader h;
  h.format = "MetaImage";
  h.headerPath = path;
  h.sizesField = "DimSize";
  h.typeField = "ElementType";
  h.dataField = "ElementDataFile";
  HeaderLines lines(path, "MetaImage");
  MetaFields fields;
  std::string line, dataFile;
  while (lines.next(line)) {
    if (trim(line).empty()) continue;
    const size_t eq = line.find('=');
    if (eq == std::string::npos)
      fieldError(path, trim(line), "a header line is not 'Field = value'");
    const std::string key = lowercase(trim(line.substr(0, eq))), value = trim(line.substr(eq + 1));
    if (key == "elementdatafile") {  // always the last field; the data may follow it
      dataFile = value;
      break;
    }
    fields.values[key] = value;
  }
  if (dataFile.empty()) fieldError(path, "ElementDataFile", "missing");
  applyFields(h, fields);
  if (lowercase(dataFile) == "local") {
    h.dataPath = path;
    h.dataOffset = lines.offset();
    if (fields.has("headersize")) fieldError(path, "HeaderSize", "only for a detached data file");
  } else {
    if (words(dataFile).size() != 1 || dataFile.find('%') != std::string::npos ||
        lowercase(dataFile) == "list")
      fieldError(path, "ElementDataFile",
                 "'" + dataFile + "': several data files are not supported (one file is)");
    h.dataPath = siblingPath(path, dataFile);
  }
  if (h.compressed && h.byteSkip == -1)
    fieldError(path, "HeaderSize", "-1 is only for uncompressed data");
  return h;
}

}  // namespace afam
