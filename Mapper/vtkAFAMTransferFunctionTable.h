// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
/**
 * The colour and opacity transfer functions of a vtkVolumeProperty as Core draws them: sampled
 * from the VTK functions themselves (vtkColorTransferFunction::GetTable in its own colour space,
 * with its above and below range colours and its NaN colour; vtkPiecewiseFunction::GetTable), as
 * VTK's own volume mappers sample them into their lookup textures, at a resolution that keeps the
 * lookup error under 1/255. The function's nodes are kept beside the table, so Core can name a
 * node that cannot be drawn (frame_settings.hpp).
 */
#ifndef vtkAFAMTransferFunctionTable_h
#define vtkAFAMTransferFunctionTable_h

#include "afam/scene/transfer_function.hpp"

class vtkVolumeProperty;

/// Entries of the sampled table (Core's tfTableSize): 4096 over the file's value range.
constexpr int vtkAFAMTransferFunctionTableSize = 4096;

/// Fills `tf` (colours, opacities, NaN colour when drawMissing, and the sampled table over
/// [lo, hi], the file's value range) from component 0 of `property`. Lengths are left to the
/// caller (referenceDistance).
void vtkAFAMSampleTransferFunctions(vtkVolumeProperty* property,
  double lo,
  double hi,
  bool drawMissing,
  afam::TransferFunction& tf);

#endif
