// SPDX-License-Identifier: BSD-3-Clause
// The payload behind a NRRD or MetaImage header: checked against the header, streamed (raw) or
// inflated once (gzip / zlib), converted to float32 plane by plane.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "afam/base/errors.hpp"
#include "afam/volume/volume_formats.hpp"
#include "file_samples.hpp"
#include "header_text.hpp"

namespace afam {

namespace {

uint64_t expectedBytes(const VolumeFileHeader& h) {
  return uint64_t(h.dims[0]) * uint64_t(h.dims[1]) * uint64_t(h.dims[2]) *
         uint64_t(sampleTypeSize(h.type));
}

/// "the header's sizes 32 32 32 and type uint8 (fields 'sizes', 'type' of H) need N bytes"
std::string headerNeeds(const VolumeFileHeader& h) {
  return "the sizes " + std::to_string(h.dims[0]) + " " + std::to_string(h.dims[1]) + " " +
         std::to_string(h.dims[2]) + " and type " + sampleTypeName(h.type) + " (fields '" +
         h.sizesField + "', '" + h.typeField + "' of " + h.headerPath + ") need " +
         std::to_string(expectedBytes(h)) + " bytes";
}

[[noreturn]] void missingData(const VolumeFileHeader& h, const std::string& why) {
  throw IoError(h.dataPath + ": cannot open the data file named by field '" + h.dataField +
                "' of " + h.headerPath + ": " + why);
}

int openData(const VolumeFileHeader& h, uint64_t& size) {
  const int fd = ::open(h.dataPath.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) missingData(h, std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    missingData(h, "not a regular file");
  }
  size = uint64_t(st.st_size);
  return fd;
}

/// Where the payload starts: after the header (attached), or after `line skip` lines and
/// `byte skip` bytes of the data file (-1: the last `expected` bytes).
uint64_t payloadStart(const VolumeFileHeader& h, int fd, uint64_t fileSize) {
  if (h.dataPath == h.headerPath) return h.dataOffset;
  uint64_t offset = 0;
  for (int64_t line = 0; line < h.lineSkip; ++line) {
    unsigned char c = 0;
    do {
      if (offset >= fileSize)
        throw FormatError(h.dataPath + ": field 'line skip' of " + h.headerPath +
                          ": the file has fewer than " + std::to_string(h.lineSkip) + " lines");
      readFully(fd, h.dataPath, offset++, &c, 1);
    } while (c != '\n');
  }
  if (h.byteSkip == -1) {
    if (fileSize - offset < expectedBytes(h))
      throw FormatError(h.dataPath + ": holds " + std::to_string(fileSize - offset) +
                        " bytes, but " + headerNeeds(h));
    return fileSize - expectedBytes(h);
  }
  return offset + uint64_t(h.byteSkip);
}

// Big-endian payloads are swapped; little-endian ones are read as they are.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "the byte swapping assumes a little-endian host");

}  // namespace

HeaderVolumeSource::HeaderVolumeSource(VolumeFileHeader header) : header_(std::move(header)) {
  if (header_.compressed)
    inflateAll();
  else
    openRaw();
}

HeaderVolumeSource::~HeaderVolumeSource() {
  if (fd_ >= 0) ::close(fd_);
}

void HeaderVolumeSource::openRaw() {
  uint64_t size = 0;
  fd_ = openData(header_, size);
  try {
    rawOffset_ = payloadStart(header_, fd_, size);
    const uint64_t have = size >= rawOffset_ ? size - rawOffset_ : 0;
    if (have != expectedBytes(header_))
      throw FormatError(header_.dataPath + ": holds " + std::to_string(have) +
                        " bytes of data after byte " + std::to_string(rawOffset_) + ", but " +
                        headerNeeds(header_));
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
}

void HeaderVolumeSource::inflateAll() {
  uint64_t size = 0;
  const int fd = openData(header_, size);
  std::vector<unsigned char> packed;
  try {
    const uint64_t start = payloadStart(header_, fd, size);
    if (start >= size)
      throw FormatError(header_.dataPath + ": no compressed data after byte " +
                        std::to_string(start) + ", but " + headerNeeds(header_));
    packed.resize(size - start);
    readFully(fd, header_.dataPath, start, packed.data(), packed.size());
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  const uint64_t expected = expectedBytes(header_);
  inflated_.resize(expected + 1);  // one spare byte reveals a payload longer than the header says
  z_stream z{};
  if (inflateInit2(&z, 15 + 32) != Z_OK) throw IoError(header_.dataPath + ": zlib cannot start");
  z.next_in = packed.data();
  uint64_t in = 0, out = 0;
  int rc = Z_OK;
  while (true) {  // chunks of at most 1 GiB (zlib counts in unsigned int); gzip members one by one
    z.next_in = packed.data() + in;
    z.avail_in = unsigned(std::min<uint64_t>(packed.size() - in, 1u << 30));
    z.next_out = inflated_.data() + out;
    z.avail_out = unsigned(std::min<uint64_t>(inflated_.size() - out, 1u << 30));
    const unsigned availIn = z.avail_in, availOut = z.avail_out;
    rc = inflate(&z, Z_NO_FLUSH);
    in += availIn - z.avail_in;
    out += availOut - z.avail_out;
    if (rc == Z_STREAM_END && in < packed.size() && out < inflated_.size()) {
      inflateReset(&z);  // another gzip member follows
      continue;
    }
    if (rc != Z_OK || out == inflated_.size()) break;
    if (in == packed.size()) break;
  }
  const std::string msg = z.msg ? z.msg : "";
  inflateEnd(&z);
  if (rc != Z_OK && rc != Z_STREAM_END && rc != Z_BUF_ERROR)
    throw FormatError(header_.dataPath + ": compressed data are damaged (zlib: " +
                      (msg.empty() ? "error" : msg) + ")");
  if (out > expected)
    throw FormatError(header_.dataPath + ": the compressed data hold more than " +
                      std::to_string(expected) + " bytes, but " + headerNeeds(header_));
  if (rc != Z_STREAM_END)
    throw FormatError(header_.dataPath + ": the compressed data end after " + std::to_string(out) +
                      " bytes without their trailer (truncated file?); " + headerNeeds(header_));
  if (out != expected)
    throw FormatError(header_.dataPath + ": the compressed data hold " + std::to_string(out) +
                      " bytes, but " + headerNeeds(header_));
  inflated_.resize(expected);
}

std::string HeaderVolumeSource::name() const {
  const std::string& p = header_.headerPath;
  const size_t slash = p.find_last_of('/');
  const std::string base = slash == std::string::npos ? p : p.substr(slash + 1);
  const size_t stop = base.find_first_of("_.");
  return stop == std::string::npos || stop == 0 ? base : base.substr(0, stop);
}

void HeaderVolumeSource::readSlab(int64_t z0, int64_t zCount, float* out) {
  if (z0 < 0 || zCount < 0 || z0 + zCount > header_.dims[2])
    throw InvalidArgument(header_.headerPath + ": planes outside the volume");
  const uint64_t es = uint64_t(sampleTypeSize(header_.type));
  const uint64_t count = uint64_t(header_.dims[0]) * uint64_t(header_.dims[1]) * uint64_t(zCount);
  const uint64_t offset = uint64_t(z0) * uint64_t(header_.dims[0]) * uint64_t(header_.dims[1]) * es;
  const bool swap = header_.bigEndian;
  if (!inflated_.empty())
    return samplesToFloat(header_.type, inflated_.data() + offset, count, out, swap);
  readFileSamples(fd_, header_.dataPath, rawOffset_ + offset, header_.type, count, out, swap);
}

std::optional<SampleType> HeaderVolumeSource::storedType() const {
  if (header_.bigEndian && sampleTypeSize(header_.type) > 1) return std::nullopt;  // swapped
  return storedAs(header_.type);
}

void HeaderVolumeSource::readStoredRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount,
                                        void* out) {
  if (!storedType()) return VolumeSource::readStoredRows(z0, zCount, y0, yCount, out);  // throws
  const StoredRows rows = storedRows(header_.dims, sampleTypeSize(header_.type), z0, zCount, y0,
                                     yCount, header_.headerPath);
  if (!inflated_.empty()) return copyStoredRows(inflated_.data(), rows, out);
  readStoredFileRows(fd_, header_.dataPath, rawOffset_, rows, out);
}

bool hasVolumeHeaderExtension(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos) return false;
  const std::string ext = header_text::lowercase(path.substr(dot + 1));
  return ext == "nrrd" || ext == "nhdr" || ext == "mha" || ext == "mhd";
}

VolumeFileHeader readVolumeHeader(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  const std::string ext =
      dot == std::string::npos ? "" : header_text::lowercase(path.substr(dot + 1));
  if (ext == "nrrd" || ext == "nhdr") return readNrrdHeader(path);
  if (ext == "mha" || ext == "mhd") return readMetaImageHeader(path);
  throw InvalidArgument(path + ": not a .nrrd, .nhdr, .mha or .mhd file");
}

std::unique_ptr<HeaderVolumeSource> openHeaderVolume(const std::string& path) {
  return std::make_unique<HeaderVolumeSource>(readVolumeHeader(path));
}

}  // namespace afam
