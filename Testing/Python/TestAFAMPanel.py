# SPDX-License-Identifier: BSD-3-Clause
"""pvpython: the "Adaptive-FAM Volume" display explains itself. Every setting the panel shows for
it has documentation (ParaView 5.11 makes a property widget's tooltip from it); Shade and Scalar
Opacity Unit Distance set on the display reach the Adaptive-FAM representation; and
GetDisplayProperties(reader) is the volume's display, also with the "Decoded Level" port shown."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview.simple import CreateView, GetDisplayProperties, OpenDataFile, OutputPort, Show  # noqa: E402

u.load_plugin(globals())
path = os.path.join(u.out_dir(), "panel.afam")
u.encode_wavelet(globals(), [-10, 10, -10, 10, -10, 10], 3, 4, 0.01, path)
reader = OpenDataFile(path)
reader.DecodeLevel = 1
view = CreateView("RenderView")
decoded = Show(OutputPort(reader, 1), view)  # the GUI's Apply shows both ports
display = Show(reader, view)
if display.Representation != "Adaptive-FAM Volume":
    u.fail("Show gave %r" % display.Representation)
found = GetDisplayProperties(reader, view)
if found.SMProxy != display.SMProxy:
    u.fail("GetDisplayProperties(reader) is %s (%s), not the volume's display"
           % (found.GetXMLName(), found.Representation))

# Tooltips: every Adaptive-FAM setting the panel shows has a description.
shown = 0
for name in display.ListProperties():
    prop = display.SMProxy.GetProperty(name)
    if not name.startswith("AFAM") or prop.GetInformationOnly() or prop.GetPanelVisibility() == "never":
        continue
    doc = prop.GetDocumentation()
    text = doc.GetDescription() if doc else ""
    if not text or len(text.split()) < 4:
        u.fail("%s shows no tooltip: documentation %r" % (name, text))
    shown += 1
if shown < 10:
    u.fail("only %d Adaptive-FAM settings found on the display" % shown)

# The Volume settings the representation honours reach it from the display.
for name, value in (("Shade", 1), ("ScalarOpacityUnitDistance", 2.5)):
    setattr(display, name, value)
    display.UpdateVTKObjects()
    active = display.GetClientSideObject().GetActiveRepresentation()
    if active.GetClassName() != "vtkAFAMVolumeRepresentation":
        u.fail("the active representation is %s" % active.GetClassName())
    volume = active.GetActor().GetProperty()
    got = volume.GetShade() if name == "Shade" else volume.GetScalarOpacityUnitDistance()
    if abs(got - value) > 1e-9:
        u.fail("%s = %s on the display is %s on the Adaptive-FAM representation" % (name, value, got))
print("panel: %d documented settings, Shade and unit distance reach the volume, display found" % shown)
