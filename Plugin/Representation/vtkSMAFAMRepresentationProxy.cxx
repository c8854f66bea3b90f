// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkSMAFAMRepresentationProxy.h"

#include "vtkDataObject.h"
#include "vtkObjectFactory.h"
#include "vtkSMArrayListDomain.h"
#include "vtkSMProperty.h"

#include <cstring>

vtkStandardNewMacro(vtkSMAFAMRepresentationProxy);

const char* vtkSMAFAMRepresentationProxy::GetVolumeTypeName()
{
  return "Adaptive-FAM Volume";
}

bool vtkSMAFAMRepresentationProxy::SetRepresentationType(const char* type)
{
  // Colour before switching, so the volume's first frame already has its transfer functions.
  if (type && std::strcmp(type, GetVolumeTypeName()) == 0 && !this->GetUsingScalarColoring())
  {
    this->ColorByFirstPointArray();
  }
  return this->Superclass::SetRepresentationType(type);
}

bool vtkSMAFAMRepresentationProxy::ColorByFirstPointArray()
{
  vtkSMProperty* colorArray = this->GetProperty("ColorArrayName");
  auto* arrays = colorArray ? colorArray->FindDomain<vtkSMArrayListDomain>() : nullptr;
  if (!arrays)
  {
    return false;
  }
  for (unsigned int i = 0; i < arrays->GetNumberOfStrings(); ++i)
  {
    // The mapper samples point values only (the models' scalar), never cell data.
    if (arrays->GetFieldAssociation(i) == vtkDataObject::POINT)
    {
      // extend=true: a transfer function the session already holds for this array only grows to
      // cover the data, as when a user picks the array by hand.
      return this->SetScalarColoring(arrays->GetString(i), vtkDataObject::POINT) &&
        this->RescaleTransferFunctionToDataRange(true);
    }
  }
  return false;
}

void vtkSMAFAMRepresentationProxy::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "VolumeTypeName: " << GetVolumeTypeName() << "\n";
}
