// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAFAMReader
 * @brief   Reads an Adaptive-FAM (.afam) file of multi-resolution B-spline micro-models.
 *
 * The output is a vtkMultiBlockDataSet with one block per level of detail and one leaf per
 * micro-model. A leaf is a vtkImageData covering the micro-model's block (origin, spacing and
 * extent of the encoded volume) with no point data; its field data holds the model's level, block
 * index, NCP, value range, achieved RMSE and max error, its index in the file and the file path.
 * No payload (control points) is read: renderers open the file themselves, out of core.
 *
 * Optionally (DecodeLevel >= 0) the reader decodes one level to a single vtkImageData instead, so
 * that ordinary filters (Slice, Contour, Plot Over Line) work on an .afam file.
 *
 * Anything that is not a valid .afam file is reported with vtkErrorMacro and a failed request.
 */
#ifndef vtkAFAMReader_h
#define vtkAFAMReader_h

#include "vtkAFAMModule.h" // for export macro
#include "vtkMultiBlockDataSetAlgorithm.h"

#include <string> // for std::string

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

  /// 1 when `filename` starts with the .afam magic and its header parses, 0 otherwise. Never throws.
  static int CanReadFile(const char* filename);

protected:
  vtkAFAMReader();
  ~vtkAFAMReader() override;

  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* FileName = nullptr;

private:
  vtkAFAMReader(const vtkAFAMReader&) = delete;
  void operator=(const vtkAFAMReader&) = delete;
};

#endif
