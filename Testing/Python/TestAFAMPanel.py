# SPDX-License-Identifier: BSD-3-Clause
"""pvpython: the "Adaptive-FAM Volume" display explains itself. Every setting the panel shows for
it has documentation (ParaView 5.11 makes a property widget's tooltip from it); Shade and Scalar
Opacity Unit Distance set on the display reach the Adaptive-FAM representation; the panel shows them
for "Adaptive-FAM Volume" as it does for "Volume" (the decision pqProxyWidget makes from the
property-group and property hints, evaluated here), and hides the Volume settings the representation
does not read; and GetDisplayProperties(reader) is the volume's display, also with the "Decoded
Level" port shown."""
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


# The panel's decision (ParaView 5.11's pqProxyWidget): a property widget is shown when every
# PropertyWidgetDecorator in its group's hints and in its own hints agrees, and, when its
# panel_visibility is "advanced", only with the advanced toggle unless
# panel_visibility_default_for_representation names the representation type.
def decorator_shows(element, representation):
    kind = element.GetAttribute("type")
    if kind == "GenericDecorator":
        if element.GetAttribute("mode") != "visibility" or element.GetAttribute("property") != "Representation":
            return True  # decorators on other properties (BlendMode, UseCropping) are not under test
        shown = element.GetAttribute("value") == representation
        return not shown if element.GetAttribute("inverse") == "1" else shown
    if kind == "CompositeDecorator":
        return expression_shows(element.GetNestedElement(0), representation)
    return True


def expression_shows(element, representation):
    results = []
    for i in range(element.GetNumberOfNestedElements()):
        child = element.GetNestedElement(i)
        if child.GetName() == "Expression":
            results.append(expression_shows(child, representation))
        elif child.GetName() == "PropertyWidgetDecorator":
            results.append(decorator_shows(child, representation))
    return any(results) if element.GetAttribute("type") == "or" else all(results)


def hints_show(hints, representation):
    if hints is None:
        return True
    return all(decorator_shows(hints.GetNestedElement(i), representation)
               for i in range(hints.GetNumberOfNestedElements())
               if hints.GetNestedElement(i).GetName() == "PropertyWidgetDecorator")


def panel_shows(proxy, name, representation):
    """(shown at all, shown without the advanced toggle) for property `name`."""
    prop = proxy.GetProperty(name)
    groups = [proxy.GetPropertyGroup(g) for g in range(proxy.GetNumberOfPropertyGroups())]
    groups = [g for g in groups
              if any(g.GetProperty(i) is prop for i in range(g.GetNumberOfProperties()))]
    shown = prop.GetPanelVisibility() != "never" and hints_show(prop.GetHints(), representation)
    shown = shown and all(hints_show(g.GetHints(), representation) for g in groups)
    default_for = (prop.GetPanelVisibilityDefaultForRepresentation() or "").lower()
    basic = prop.GetPanelVisibility() != "advanced" or default_for == representation.lower()
    return shown, shown and basic


proxy = display.SMProxy
for rep in ("Volume", "Adaptive-FAM Volume"):
    for name in ("Shade", "ScalarOpacityUnitDistance"):
        if not panel_shows(proxy, name, rep)[0]:
            u.fail("the panel hides %s for %r" % (name, rep))
    if not panel_shows(proxy, "Shade", rep)[1]:
        u.fail("Shade is behind the advanced toggle for %r (ParaView shows it for Volume)" % rep)
for name in ("Shade", "ScalarOpacityUnitDistance"):
    if panel_shows(proxy, name, "Outline")[0]:
        u.fail("the panel shows %s for Outline" % name)
# Volume settings the Adaptive-FAM mapper does not read: ParaView's Volume keeps them, ours hides them.
for name in ("VolumeRenderingMode", "UseSeparateOpacityArray", "BlendMode", "UseCropping"):
    if not panel_shows(proxy, name, "Volume")[0]:
        u.fail("the panel hides %s for ParaView's Volume" % name)
    if panel_shows(proxy, name, "Adaptive-FAM Volume")[0]:
        u.fail("the panel shows %s for Adaptive-FAM Volume, which does not read it" % name)
# The change is this proxy's own copy of the hints: ParaView's definition, used by the Decoded Level
# display (UniformGridRepresentation), stays as it is.
plain = decoded
if plain.SMProxy.GetXMLName() == proxy.GetXMLName():
    u.fail("the Decoded Level port uses %s" % proxy.GetXMLName())
if panel_shows(plain.SMProxy, "Shade", "Adaptive-FAM Volume")[0]:
    u.fail("ParaView's %s shows Shade for Adaptive-FAM Volume" % plain.SMProxy.GetXMLName())

print("panel: %d documented settings, Shade and unit distance reach the volume, display found" % shown)
