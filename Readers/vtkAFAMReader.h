// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAFAMReader
 * @brief   Reads an Adaptive-FAM (.afam) file of multi-resolution B-spline micro-models.
 *
 * The output is a vtkMultiBlockDataSet with one leaf per level of detail and a last "Value range"
 * leaf. A level's leaf is a vtkImageData covering its micro-models' blocks (origin, spacing and
 * extent of the encoded volume) with no samples (its point array of the scalar's name is NaN and
 * holds no memory: ParaView then lists the array whole, not "(partial)"; the "Value range" leaf's
 * gives the range); its field data has one row per micro-model:
 * level, block index, NCP, degree, value range, achieved RMSE and max error, index in the file,
 * bytes of its decoded control points and bytes stored in the file (ParaView's spreadsheet shows
 * them). The root's field data names the file.
 * No payload (control points) is read: renderers open the file themselves, out of core.
 *
 * Output port 1 ("Decoded Level"): on request (DecodeLevel >= 0, 0 = coarsest) the reader decodes
 * that level to a vtkImageData on the level's own sample grid (the finest level is the encoded
 * volume's grid) with one float point array named like the encoded scalars, so that ordinary
 * filters (Slice, Contour, Plot Over Line) work on an .afam file. It reads and evaluates only the
 * micro-models of the requested update extent (sub-extents: each MPI rank decodes its own slab).
 * With DecodeLevel = -1 (default) port 1 is an empty image and no payload is read. A damaged
 * micro-model does not fail the decode: its samples come from the nearest intact coarser model
 * (else its intact children; NaN where neither exists), as the renderer draws it, with one warning
 * per decode naming the damaged blocks.
 *
 * MPI pieces of port 0: piece p of n keeps the micro-models whose coarsest-level ancestor lies in
 * its contiguous range of coarsest blocks (z-major slabs, spatially coherent); its level leaves
 * span only those blocks.
 *
 * Anything that is not a valid .afam file is reported once with vtkErrorMacro (what is wrong with
 * it, naming the path) and gives empty outputs, with no second error from the pipeline.
 */
#ifndef vtkAFAMReader_h
#define vtkAFAMReader_h

#include "vtkAFAMModule.h" // for export macro
#include "vtkMultiBlockDataSetAlgorithm.h"

#include <string> // for std::string
#include <vector> // for std::vector

class VTKAFAM_EXPORT vtkAFAMReader : public vtkMultiBlockDataSetAlgorithm
{
public:
  static vtkAFAMReader* New();
  vtkTypeMacro(vtkAFAMReader, vtkMultiBlockDataSetAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// Path of the .afam file to read. Default: none.
  vtkSetFilePathMacro(FileName);
  vtkGetFilePathMacro(FileName);
  ///@}

  ///@{
  /// Level decoded to image data on output port 1: -1 none (default), else 0 (coarsest) to
  /// levels-1 (finest). A level the file does not have is an error.
  vtkSetClampMacro(DecodeLevel, int, -1, 64);
  vtkGetMacro(DecodeLevel, int);
  ///@}

  /// What is wrong with the file, as the one error reported for it said (naming the path), or
  /// empty while it reads. Set by the reader's first pass over the pipeline (OpenDataFile's, in
  /// ParaView), so that a script can tell a bad file without parsing the output window: the
  /// reader proxy's "ReadError" property.
  const char* GetReadError()
  {
    return this->LastError.c_str();
  }

  /// 1 when `filename` starts with the .afam magic or is named .afam, whether or not the rest is
  /// valid: the reader then says what is wrong with it (truncated, checksum, version, not an .afam
  /// file, unreadable), once; 0 otherwise. Never throws.
  static int CanReadFile(const char* filename);

protected:
  vtkAFAMReader();
  ~vtkAFAMReader() override;

  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
  /// One warning for the damaged blocks of a decode (none when `damaged` is empty).
  void ReportDamagedBlocks(const std::vector<std::string>& damaged, const std::string& path);
  /// One error for a file that cannot be read, however many updates meet it (see LastError).
  void ReportOnce(const std::string& message);

  char* FileName = nullptr;
  int DecodeLevel = -1;
  /// The error last reported; cleared when the file opens again.
  std::string LastError;

private:
  vtkAFAMReader(const vtkAFAMReader&) = delete;
  void operator=(const vtkAFAMReader&) = delete;
};

#endif
