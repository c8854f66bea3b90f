// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAFAMEncoder
 * @brief   Encodes a vtkImageData scalar field into Adaptive-FAM micro-models.
 *
 * Input: vtkImageData with a point-data array of any scalar type (selected with
 * SetInputArrayToProcess(0, 0, 0, vtkDataObject::FIELD_ASSOCIATION_POINTS, name); default: the
 * active scalars), converted to float32 for fitting. The encoding runs in Core (encodeVolume);
 * progress is reported and the abort flag (ParaView's abort button) cancels it.
 *
 * Output: the same metadata multiblock as vtkAFAMReader (one block per level, one leaf per
 * micro-model). The models are stored in a temporary .afam file owned by this filter (removed when
 * the filter is destroyed or re-executes), which vtkAFAMVolumeMapper renders at once and
 * vtkAFAMWriter copies to its destination.
 */
#ifndef vtkAFAMEncoder_h
#define vtkAFAMEncoder_h

#include "vtkAFAMModule.h" // for export macro
#include "vtkMultiBlockDataSetAlgorithm.h"

#include <string> // for std::string

class VTKAFAM_EXPORT vtkAFAMEncoder : public vtkMultiBlockDataSetAlgorithm
{
public:
  static vtkAFAMEncoder* New();
  vtkTypeMacro(vtkAFAMEncoder, vtkMultiBlockDataSetAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// RMSE bound per micro-model. Default 1e-3, >= 0. Relative (to the value range) when
  /// RelativeBound is on (default on).
  vtkSetClampMacro(ErrorBound, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(ErrorBound, double);
  vtkSetMacro(RelativeBound, bool);
  vtkGetMacro(RelativeBound, bool);
  vtkBooleanMacro(RelativeBound, bool);
  ///@}

  ///@{
  /// Levels of detail, [1, 16]; finest blocks per axis, [1, 4096]. 0 (the default) for each: from
  /// the image's dimensions (blocks of about 32 samples, levels down to 2 blocks along the longest axis).
  vtkSetClampMacro(Levels, int, 0, 16);
  vtkGetMacro(Levels, int);
  vtkSetClampMacro(BlocksPerAxis, int, 0, 4096);
  vtkGetMacro(BlocksPerAxis, int);
  ///@}

  ///@{
  /// B-spline degree, default 2, range [1, 5].
  vtkSetClampMacro(Degree, int, 1, 5);
  vtkGetMacro(Degree, int);
  ///@}

  ///@{
  /// Mode: 0 adaptive (default, the paper's cross-level search), 1 in-level, 2 fixed NCP,
  /// 3 downsampled raw blocks. FixedNcp: NCP per axis for mode 2 (0 = n).
  vtkSetClampMacro(Mode, int, 0, 3);
  vtkGetMacro(Mode, int);
  vtkSetClampMacro(FixedNcp, int, 0, 4096);
  vtkGetMacro(FixedNcp, int);
  ///@}

  ///@{
  /// Encoder threads, 0 = all cores (default).
  vtkSetClampMacro(NumberOfThreads, int, 0, 1024);
  vtkGetMacro(NumberOfThreads, int);
  ///@}

  /// The temporary .afam file holding the last encoding (empty before the first execution).
  const char* GetModelFileName() { return this->ModelFile.c_str(); }

  ///@{
  /// Statistics of the last encoding.
  vtkGetMacro(LastEncodeSeconds, double);
  vtkGetMacro(LastMaxRmse, double);
  vtkGetMacro(LastCompressionRatio, double);
  ///@}

protected:
  vtkAFAMEncoder();
  ~vtkAFAMEncoder() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  void RemoveModelFile();

  double ErrorBound = 1e-3;
  bool RelativeBound = true;
  int Levels = 0;
  int BlocksPerAxis = 0;
  int Degree = 2;
  int Mode = 0;
  int FixedNcp = 0;
  int NumberOfThreads = 0;
  double LastEncodeSeconds = 0, LastMaxRmse = 0, LastCompressionRatio = 0;
  std::string ModelFile;

private:
  vtkAFAMEncoder(const vtkAFAMEncoder&) = delete;
  void operator=(const vtkAFAMEncoder&) = delete;
};

#endif
