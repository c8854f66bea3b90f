// SPDX-License-Identifier: BSD-3-Clause
// Volumes described by a text header: NRRD (.nrrd with attached data, .nhdr with a detached data
// file) and MetaImage (.mha attached, .mhd detached), read as a streaming VolumeSource.
//
// Supported: 3-D scalar volumes of any SampleType (8- to 64-bit integers, float32, float64),
// little or big endian, raw or compressed (NRRD `encoding: gzip`, MetaImage `CompressedData =
// True`, both inflated by zlib), one data file (NRRD `data file`, MetaImage `ElementDataFile`),
// with NRRD `byte skip` (-1: the data are the file's last bytes) and `line skip`, MetaImage
// `HeaderSize`. Spacing comes from NRRD `spacings` or the lengths of `space directions` (the
// orientation is dropped, as VTK's image data drop it), MetaImage `ElementSpacing` (else
// `ElementSize`); origin from NRRD `space origin`, MetaImage `Offset` / `Origin` / `Position`.
// Refused with an error naming the file and the field: other dimensions, types and encodings
// (ascii, hex, bzip2), several data files, vector data, and a payload whose size is not the one
// the header's sizes and type give.
//
// Why a parser of our own over zlib rather than teem's nrrdLoad: MetaImage needs a header parser
// anyway (teem reads only NRRD), and both formats reduce to the same few `key: value` fields over
// the same payload (raw or zlib-compressed bytes in this or another file), so one payload path
// serves both. nrrdLoad reads and converts the whole array at once, while raw payloads here stream
// plane by plane like RawFileSource; it reads only the bytes the header asks for, so a raw payload
// longer than the header says (an error here) passes; and its errors come as biff text that does
// not name the field. zlib, a packaged library, does the part that needs care (inflating gzip and
// zlib streams).
//
// Memory: a raw payload is read plane by plane (pread) as the encoder asks; a compressed one is
// inflated once, when the source is opened, and held in its original type (1-8 bytes a voxel).
// Samples become floats through samplesToFloat, as the encoder reads them.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "afam/volume/volume_source.hpp"

namespace afam {

/// What a NRRD or MetaImage header says about its volume and where the samples are.
struct VolumeFileHeader {
  std::string format;      ///< "NRRD" or "MetaImage"
  std::string headerPath;  ///< the file the header was read from
  std::string dataPath;    ///< the file holding the samples (headerPath when attached)
  Index3 dims{};
  SampleType type = SampleType::UInt8;
  bool bigEndian = false;
  bool compressed = false;  ///< gzip or zlib stream (inflate detects which)
  uint64_t dataOffset = 0;  ///< attached: the first byte after the header
  int64_t lineSkip = 0;     ///< detached: lines to skip in dataPath first
  int64_t byteSkip = 0;     ///< detached: bytes to skip next; -1: the data end the file (raw only)
  std::array<double, 3> origin{0, 0, 0}, spacing{1, 1, 1};
  /// The header's names of its size, type and data file fields, for error messages.
  std::string sizesField = "sizes", typeField = "type", dataField = "data file";
};

/// Parse a header. Throw IoError (cannot open or read, a directory, an empty file) or FormatError
/// naming the file and the field (missing, unknown or unsupported value).
VolumeFileHeader readNrrdHeader(const std::string& path);
VolumeFileHeader readMetaImageHeader(const std::string& path);

/// A volume behind a NRRD or MetaImage header. The constructor checks the payload against the
/// header (FormatError naming the data file and the header's sizes/type fields when they
/// disagree; IoError when the data file is missing or unreadable) and inflates compressed data.
class HeaderVolumeSource : public VolumeSource {
 public:
  explicit HeaderVolumeSource(VolumeFileHeader header);
  ~HeaderVolumeSource() override;
  HeaderVolumeSource(const HeaderVolumeSource&) = delete;
  HeaderVolumeSource& operator=(const HeaderVolumeSource&) = delete;
  Index3 dims() const override { return header_.dims; }
  std::array<double, 3> origin() const override { return header_.origin; }
  std::array<double, 3> spacing() const override { return header_.spacing; }
  /// The header file's name up to its first '_' or '.', as RawFileSource names a raw file.
  std::string name() const override;
  void readSlab(int64_t z0, int64_t zCount, float* out) override;
  int bytesPerVoxel() const override { return sampleTypeSize(header_.type); }
  /// Raw payloads are read by offset, compressed ones were inflated whole: any thread.
  bool concurrentReads() const override { return true; }
  /// Its samples as stored where they are integers of 1 or 2 bytes in this host's byte order.
  std::optional<SampleType> storedType() const override;
  void readStoredRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount, void* out) override;
  const VolumeFileHeader& header() const { return header_; }

 private:
  void openRaw();
  void inflateAll();
  VolumeFileHeader header_;
  int fd_ = -1;
  uint64_t rawOffset_ = 0;
  std::vector<unsigned char> inflated_;  ///< compressed payloads, inflated
};

/// True for the extensions this file reads: .nrrd, .nhdr, .mha, .mhd (any case).
bool hasVolumeHeaderExtension(const std::string& path);
/// The header of a .nrrd/.nhdr (readNrrdHeader) or .mha/.mhd (readMetaImageHeader) file; throws
/// as they do, and InvalidArgument for another extension.
VolumeFileHeader readVolumeHeader(const std::string& path);
/// HeaderVolumeSource(readVolumeHeader(path)).
std::unique_ptr<HeaderVolumeSource> openHeaderVolume(const std::string& path);

}  // namespace afam
