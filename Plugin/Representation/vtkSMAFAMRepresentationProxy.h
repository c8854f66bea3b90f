// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkSMAFAMRepresentationProxy
 * @brief   Server-manager class of "AFAMRepresentation", the render-view representation of the
 *          Adaptive-FAM reader and encoder: picking "Adaptive-FAM Volume" colours the volume by
 *          its point scalars, as picking ParaView's own "Volume" does.
 *
 * Why a class of our own: in ParaView 5.11 the colouring that comes with picking a volume
 * representation is decided in C++ only, by vtkSMPVRepresentationProxy::SetRepresentationType,
 * which recognises the names "Volume" and "Slice" (and NVIDIA IndeX's) and nothing else; no XML
 * hint or domain reaches that decision. Every way of picking a representation goes through that
 * virtual method: Show (the reader's RepresentationType hint), the GUI's representation combo box
 * and paraview.simple's SetRepresentationType. Alternatives considered: an object-factory override
 * of vtkSMPVRepresentationProxy would change every representation of every source in the session;
 * observers on the proxy manager would colour after the fact and miss the order ParaView keeps
 * (colour, then switch). So the reader and the encoder name, through their `Representation` hint,
 * a proxy that inherits ParaView's UniformGridRepresentation definition unchanged (what a render
 * view picks for their multiblock of image data: Outline, Slice, the "Adaptive-FAM Volume"
 * extension, state files) and whose XML tag makes the proxy manager
 * instantiate this class (it creates "vtkSM" + tag through the client-server interpreter, where the
 * plugin registers its wrapped classes).
 */
#ifndef vtkSMAFAMRepresentationProxy_h
#define vtkSMAFAMRepresentationProxy_h

#include "vtkAFAMParaViewModule.h" // for export macro
#include "vtkSMPVRepresentationProxy.h"

class VTKAFAMPARAVIEW_EXPORT vtkSMAFAMRepresentationProxy : public vtkSMPVRepresentationProxy
{
public:
  static vtkSMAFAMRepresentationProxy* New();
  vtkTypeMacro(vtkSMAFAMRepresentationProxy, vtkSMPVRepresentationProxy);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// The representation type whose picking sets up scalar colouring ("Adaptive-FAM Volume").
  static const char* GetVolumeTypeName();

  /**
   * Switches to `type`. For "Adaptive-FAM Volume", when nothing colours the representation yet,
   * first colour it by the first point array it offers, with the session's colour and opacity
   * transfer functions for that array rescaled to its data range (ParaView's default volume
   * colour map and an opacity ramp over the range, for a new array). Other types: ParaView's
   * behaviour unchanged.
   */
  bool SetRepresentationType(const char* type) override;

protected:
  vtkSMAFAMRepresentationProxy() = default;
  ~vtkSMAFAMRepresentationProxy() override = default;

  /// ParaView's definition, then ShowVolumeSettingsForAFAM.
  int ReadXMLAttributes(vtkSMSessionProxyManager* pm, vtkPVXMLElement* element) override;

private:
  /**
   * The panel: ParaView's "Volume Rendering" property group (the one holding Shade) is shown only
   * for the types "Volume" and "NVIDIA IndeX" (a decorator in its XML hints, which plugin XML
   * cannot change). On this proxy's own copy of those hints, the group is also shown for
   * "Adaptive-FAM Volume"; the group's settings the Adaptive-FAM mapper does not read get a
   * decorator that hides them for "Adaptive-FAM Volume", and the ones it reads that ParaView shows
   * for "Volume" without the advanced toggle are shown so for both.
   */
  void ShowVolumeSettingsForAFAM();

  /// Colours by the first point array of the ColorArrayName domain; false when there is none.
  bool ColorByFirstPointArray();

  vtkSMAFAMRepresentationProxy(const vtkSMAFAMRepresentationProxy&) = delete;
  void operator=(const vtkSMAFAMRepresentationProxy&) = delete;
};

#endif
