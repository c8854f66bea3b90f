// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAFAMWriter
 * @brief   Saves Adaptive-FAM micro-models (the output of vtkAFAMEncoder or vtkAFAMReader) to
 * .afam.
 *
 * The input multiblock names the .afam file that holds its models (field data); the writer
 * validates that file through Core (header, index and every payload's checksum) and copies it to
 * FileName atomically (temporary file + rename): a failed write leaves no half file. Under MPI,
 * rank 0 alone writes (the encoder's models are on rank 0; a reader's file is the same on every
 * rank); the other ranks write nothing.
 */
#ifndef vtkAFAMWriter_h
#define vtkAFAMWriter_h

#include "vtkAFAMModule.h" // for export macro
#include "vtkWriter.h"

class VTKAFAM_EXPORT vtkAFAMWriter : public vtkWriter
{
public:
  static vtkAFAMWriter* New();
  vtkTypeMacro(vtkAFAMWriter, vtkWriter);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// Destination .afam path. Default: none.
  vtkSetFilePathMacro(FileName);
  vtkGetFilePathMacro(FileName);
  ///@}

protected:
  vtkAFAMWriter();
  ~vtkAFAMWriter() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  /// Under MPI, asks for this rank's piece (see the class documentation).
  vtkTypeBool ProcessRequest(vtkInformation* request,
    vtkInformationVector** inputVector,
    vtkInformationVector* outputVector) override;
  void WriteData() override;

  char* FileName = nullptr;

private:
  vtkAFAMWriter(const vtkAFAMWriter&) = delete;
  void operator=(const vtkAFAMWriter&) = delete;
};

#endif
