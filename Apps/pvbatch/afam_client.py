# SPDX-License-Identifier: BSD-3-Clause
"""Connects a pvpython client to a pvserver and makes sure the AdaptiveFAM plugin is usable there:
loaded on the server and on the client, at the same version. Without it, a client whose server
lacks the plugin only hears "No reader found" when it opens an .afam file.

    import afam_client
    afam_client.connect("127.0.0.1", 11111, "/path/to/AdaptiveFAM.so", ns=globals())

Raises RuntimeError with a message that names the server and what is missing or different.
"""

PLUGIN = "AdaptiveFAM"


def plugin_versions(information):
    """{name: version} of the plugins a vtkPVPluginsInformation lists as loaded."""
    return {information.GetPluginName(i): information.GetPluginVersion(i)
            for i in range(information.GetNumberOfPlugins()) if information.GetPluginLoaded(i)}


def check_plugin(local, remote, where):
    """The plugin must be loaded on both sides at one version; `local` and `remote` are the
    {name: version} maps of plugin_versions."""
    if PLUGIN not in remote:
        raise RuntimeError(
            "the %s plugin is not loaded on the server %s: load it there with "
            "LoadPlugin(path, remote=True), or start pvserver with PV_PLUGIN_PATH set to the folder "
            "of %s.so (a path on the server)" % (PLUGIN, where, PLUGIN))
    if PLUGIN not in local:
        raise RuntimeError("the %s plugin is not loaded on this client: "
                           "LoadPlugin(path, remote=False)" % PLUGIN)
    if local[PLUGIN] != remote[PLUGIN]:
        raise RuntimeError("%s version %s on this client but %s on the server %s: use the same build "
                           "on both sides" % (PLUGIN, local[PLUGIN], remote[PLUGIN], where))


def connect(host, port, plugin=None, server_plugin=None, ns=None, timeout=30):
    """Connect, load `plugin` on the client and `server_plugin` on the server (default: the same
    path; "" loads nothing there, for a server started with PV_PLUGIN_PATH naming the plugin's
    folder), then check both."""
    from paraview import servermanager
    from paraview.simple import Connect, LoadPlugin
    connection = Connect(host, port, timeout=timeout)
    if connection is None:
        raise RuntimeError("could not connect to pvserver at %s:%d" % (host, port))
    if server_plugin is None:
        server_plugin = plugin
    if server_plugin:
        LoadPlugin(server_plugin, remote=True, ns=ns)
    if plugin:
        LoadPlugin(plugin, remote=False, ns=ns)
    manager = servermanager.vtkSMProxyManager.GetProxyManager().GetPluginManager()
    check_plugin(plugin_versions(manager.GetLocalInformation()),
                 plugin_versions(manager.GetRemoteInformation(connection.Session)),
                 "%s:%d" % (host, port))
    return connection


STATISTICS = ("NumberOfRanks", "RanksDrawingBlocks", "TotalBytesRead", "MaxBytesRead",
              "TotalVisibleBlocks", "MaxTotalTime", "MinImageScale", "RanksOnGpu", "RanksThroughInterop",
              "TotalStandInBlocks", "TotalBlocksBehind", "TotalBytesBehind")


def frame_statistics(display):
    """The last frame of an "Adaptive-FAM Volume" display over all server ranks (a dict of
    STATISTICS). Call it after Render() and before any other render; the display's own AFAMLast...
    properties, read from a client, are those of the client's copy, which does not render."""
    from paraview import servermanager
    statistics = servermanager.misc.AFAMFrameStatistics(Representation=display)
    statistics.SMProxy.InvokeCommand("Gather")
    statistics.SMProxy.UpdatePropertyInformation()
    return {name: statistics.GetPropertyValue(name) for name in STATISTICS}
