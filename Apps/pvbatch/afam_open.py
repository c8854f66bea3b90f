# SPDX-License-Identifier: BSD-3-Clause
"""Opens an .afam file in pvpython / pvbatch and raises what is wrong with it.

ParaView 5.11's paraview.simple.OpenDataFile raises RuntimeError only when the file cannot be read at
all or no reader claims it; a reader's error during the pipeline's passes goes to the output window
and UpdatePipeline returns as usual. The Adaptive-FAM reader claims every file named .afam or
starting with its magic and keeps the one error it reported (truncated, damaged header or index, a
newer version, not an .afam file) in its "ReadError" property, which any script can read:

    reader = OpenDataFile(path)
    if reader.ReadError:
        ...

OpenAFAM does that and raises:

    import afam_open
    reader = afam_open.OpenAFAM(path)   # RuntimeError("<path>: truncated: ...") for a bad file

The output window still shows the error once (the GUI's and pvpython's usual channel).
"""


def OpenAFAM(filename, **properties):
    """paraview.simple.OpenDataFile(filename, **properties) for an .afam file: the reader proxy, or
    RuntimeError with the reader's one error (the proxy is deleted first). Also RuntimeError, from
    OpenDataFile itself, for a file that cannot be read or that no reader claims."""
    from paraview.simple import Delete, OpenDataFile
    reader = OpenDataFile(filename, **properties)
    if reader is None:
        raise RuntimeError("no reader for %s" % filename)
    if reader.GetProperty("ReadError") is None:
        return reader  # another reader claimed it (not an .afam name, no .afam magic)
    reader.UpdatePipelineInformation()
    error = reader.GetPropertyValue("ReadError")
    if error:
        Delete(reader)
        raise RuntimeError(error)
    return reader
