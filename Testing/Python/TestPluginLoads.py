# SPDX-License-Identifier: BSD-3-Clause
"""The built AdaptiveFAM plugin loads into pvbatch and registers its proxies.

Fails (non-zero exit) when the plugin cannot be loaded or a proxy is missing."""
import os
import sys

from paraview import servermanager
from paraview.simple import LoadPlugin

plugin = os.environ.get("AFAM_PLUGIN", "")
if not os.path.isfile(plugin):
    print("AFAM-TEST-FAIL: plugin file not found: %r" % plugin)
    sys.exit(1)

# LoadPlugin raises RuntimeError when the library cannot be loaded.
LoadPlugin(plugin, remote=False, ns=globals())

pxm = servermanager.ProxyManager()
expected = [("sources", "AFAMReader"), ("filters", "AFAMEncoder"), ("writers", "AFAMWriter"),
            ("representations", "AFAMVolumeRepresentation")]
missing = [(g, n) for g, n in expected if pxm.GetPrototypeProxy(g, n) is None]
if missing:
    print("AFAM-TEST-FAIL: proxies not registered: %s" % missing)
    sys.exit(1)

# the pvpython function comes from the XML label, and the proxy builds its VTK object
reader = AdaptiveFAMReader()  # noqa: F821 (defined by LoadPlugin in globals())
if reader.SMProxy.GetVTKClassName() != "vtkAFAMReader":
    print("AFAM-TEST-FAIL: AdaptiveFAMReader proxy does not create vtkAFAMReader")
    sys.exit(1)
print("plugin loaded: %s" % plugin)
