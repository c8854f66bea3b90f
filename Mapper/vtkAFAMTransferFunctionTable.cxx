// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMTransferFunctionTable.h"

#include "vtkColorTransferFunction.h"
#include "vtkPiecewiseFunction.h"
#include "vtkVolumeProperty.h"

#include <vector>

namespace
{
void ReadNodes(vtkColorTransferFunction* ctf, afam::TransferFunction& tf)
{
  double node[6];
  for (int i = 0; i < ctf->GetSize(); ++i)
  {
    ctf->GetNodeValue(i, node);
    tf.colors.push_back({ node[0], node[1], node[2], node[3] });
  }
}

void ReadNodes(vtkPiecewiseFunction* pwf, afam::TransferFunction& tf)
{
  double node[4];
  for (int i = 0; i < pwf->GetSize(); ++i)
  {
    pwf->GetNodeValue(i, node);
    tf.opacities.push_back({ node[0], node[1] });
  }
}
}

void vtkAFAMSampleTransferFunctions(vtkVolumeProperty* property,
  double lo,
  double hi,
  bool drawMissing,
  afam::TransferFunction& tf)
{
  vtkColorTransferFunction* ctf = property->GetRGBTransferFunction(0);
  vtkPiecewiseFunction* pwf = property->GetScalarOpacity(0);
  if (ctf)
  {
    ReadNodes(ctf, tf);
    if (drawMissing)
    {
      ctf->GetNanColor(tf.nanColor.data());
      tf.nanOpacity = ctf->GetNanOpacity();
    }
  }
  if (pwf)
  {
    ReadNodes(pwf, tf);
  }
  // Without nodes there is nothing to sample: Core refuses the function and names why.
  if (tf.colors.empty() || tf.opacities.empty())
  {
    return;
  }
  const int n = vtkAFAMTransferFunctionTableSize;
  const double top = hi > lo ? hi : lo; // a range of zero width: one value, a constant table
  std::vector<float> rgb(3 * static_cast<size_t>(n)), alpha(static_cast<size_t>(n));
  ctf->GetTable(lo, top, n, rgb.data());
  pwf->GetTable(lo, top, n, alpha.data());
  tf.sampled.resize(4 * static_cast<size_t>(n));
  for (size_t i = 0; i < static_cast<size_t>(n); ++i)
  {
    tf.sampled[4 * i + 0] = rgb[3 * i + 0];
    tf.sampled[4 * i + 1] = rgb[3 * i + 1];
    tf.sampled[4 * i + 2] = rgb[3 * i + 2];
    tf.sampled[4 * i + 3] = alpha[i];
  }
  tf.sampledLo = lo;
  tf.sampledHi = top;
}
