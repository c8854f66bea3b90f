// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkSMAFAMRepresentationProxy.h"

#include "vtkDataObject.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPVXMLElement.h"
#include "vtkSMArrayListDomain.h"
#include "vtkSMProperty.h"
#include "vtkSMPropertyGroup.h"

#include <cstring>

vtkStandardNewMacro(vtkSMAFAMRepresentationProxy);

namespace
{
// The settings of ParaView's "Volume Rendering" group that the Adaptive-FAM mapper reads
// (vtkAFAMVolumeMapper::ReadFrameSettings and the transfer-function tables); its blend mode is
// AFAMBlendMode, its other settings (2D transfer functions, separate opacity array, rendering
// mode, isosurfaces, slice function, cropping, scattering) it does not read.
const char* const HonouredVolumeSettings[] = { "ScalarOpacityUnitDistance",
  "ScalarOpacityFunction",
  "Shade" };

bool IsHonoured(const char* name)
{
  for (const char* honoured : HonouredVolumeSettings)
  {
    if (name && std::strcmp(name, honoured) == 0)
    {
      return true;
    }
  }
  return false;
}

bool Is(vtkPVXMLElement* element, const char* attribute, const char* value)
{
  return std::strcmp(element->GetAttributeOrEmpty(attribute), value) == 0;
}

/// `<PropertyWidgetDecorator type="GenericDecorator" mode="visibility" property="Representation"
/// value=value/>`: visible when the representation type is `value` (not `value` when inverse).
vtkSmartPointer<vtkPVXMLElement> NewRepresentationDecorator(const char* value, bool inverse)
{
  auto decorator = vtkSmartPointer<vtkPVXMLElement>::New();
  decorator->SetName("PropertyWidgetDecorator");
  decorator->SetAttribute("type", "GenericDecorator");
  decorator->SetAttribute("mode", "visibility");
  decorator->SetAttribute("property", "Representation");
  decorator->SetAttribute("value", value);
  if (inverse)
  {
    decorator->SetAttribute("inverse", "1");
  }
  return decorator;
}

/// In every `<Expression type="or">` under `element` that accepts the representation type
/// "Volume", also accepts `type`. Returns whether one was changed.
bool AlsoAcceptWhereVolumeIs(vtkPVXMLElement* element, const char* type)
{
  bool changed = false;
  const bool isOr = std::strcmp(element->GetName() ? element->GetName() : "", "Expression") == 0 &&
    Is(element, "type", "or");
  bool acceptsVolume = false;
  bool acceptsType = false;
  for (unsigned int i = 0; i < element->GetNumberOfNestedElements(); ++i)
  {
    vtkPVXMLElement* child = element->GetNestedElement(i);
    if (isOr && Is(child, "type", "GenericDecorator") && Is(child, "property", "Representation") &&
      !child->GetAttribute("inverse"))
    {
      acceptsVolume = acceptsVolume || Is(child, "value", "Volume");
      acceptsType = acceptsType || Is(child, "value", type);
    }
    changed = AlsoAcceptWhereVolumeIs(child, type) || changed;
  }
  if (acceptsVolume && !acceptsType)
  {
    element->AddNestedElement(NewRepresentationDecorator(type, false));
    changed = true;
  }
  return changed;
}
}

int vtkSMAFAMRepresentationProxy::ReadXMLAttributes(vtkSMSessionProxyManager* pm,
  vtkPVXMLElement* element)
{
  if (!this->Superclass::ReadXMLAttributes(pm, element))
  {
    return 0;
  }
  this->ShowVolumeSettingsForAFAM();
  return 1;
}

void vtkSMAFAMRepresentationProxy::ShowVolumeSettingsForAFAM()
{
  vtkSMProperty* shade = this->GetProperty("Shade");
  for (size_t g = 0; shade && g < this->GetNumberOfPropertyGroups(); ++g)
  {
    vtkSMPropertyGroup* group = this->GetPropertyGroup(g);
    bool hasShade = false;
    for (unsigned int i = 0; i < group->GetNumberOfProperties(); ++i)
    {
      hasShade = hasShade || group->GetProperty(i) == shade;
    }
    if (!hasShade || !group->GetHints())
    {
      continue;
    }
    // The group's hints are this proxy's own copy: ParaView's definition stays as it is.
    vtkNew<vtkPVXMLElement> hints;
    group->GetHints()->CopyTo(hints);
    if (!AlsoAcceptWhereVolumeIs(hints, GetVolumeTypeName()))
    {
      continue;
    }
    group->SetHints(hints);
    for (unsigned int i = 0; i < group->GetNumberOfProperties(); ++i)
    {
      vtkSMProperty* property = group->GetProperty(i);
      const char* name = this->GetPropertyName(property);
      if (IsHonoured(name))
      {
        // ParaView shows these for "Volume" without the advanced toggle
        // (panel_visibility_default_for_representation="volume", one type only); shown for
        // both types alike here (the group's decorator hides them for the others).
        if (property->GetPanelVisibilityDefaultForRepresentation())
        {
          property->SetPanelVisibility("default");
        }
        continue;
      }
      vtkNew<vtkPVXMLElement> own;
      own->SetName("Hints");
      if (property->GetHints())
      {
        property->GetHints()->CopyTo(own);
      }
      own->AddNestedElement(NewRepresentationDecorator(GetVolumeTypeName(), true));
      property->SetHints(own);
    }
  }
}

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
