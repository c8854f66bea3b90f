# SPDX-License-Identifier: BSD-3-Clause
"""pvpython: a file that starts with the .afam magic or is named .afam is claimed by the reader,
which says what is wrong with it (truncated with the bytes expected and found, a damaged header, a
newer version, not an .afam file at all) in one error naming the path, and nothing after it: not
when the file is shown, rendered, updated again or asked for a decoded level; never ParaView's
"No reader found". Python can tell: the reader proxy's ReadError property is that error, word for
word, from OpenDataFile on (and empty for a good file), and afam_open.OpenAFAM raises it as a
RuntimeError, again with one error in the output window."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
sys.path.insert(0, os.path.join(os.environ.get("AFAM_TEST_SCRIPTS", ""), "..", "..", "Apps", "pvbatch"))
import afam_open  # noqa: E402
import afam_test_util as u  # noqa: E402

from paraview.simple import CreateRenderView, OpenDataFile, Render, Show  # noqa: E402
from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkStringOutputWindow  # noqa: E402

u.load_plugin(globals())
out = u.out_dir()
good = os.path.join(out, "wavelet.afam")
u.encode_wavelet(globals(), [-10, 10, -10, 10, -10, 10], 3, 4, 0.01, good)
data = open(good, "rb").read()
view = CreateRenderView()

def open_and_report(path):
    """The errors ParaView's output window shows for opening `path` and updating the reader, and
    the reader's ReadError right after OpenDataFile and at the end (None where no reader).
    (pvpython's print goes through the output window too: it is captured only meanwhile.)"""
    console = vtkOutputWindow.GetInstance()
    messages = vtkStringOutputWindow()
    vtkOutputWindow.SetInstance(messages)
    produced = 0
    read_errors = None
    try:
        reader = OpenDataFile(path)
        if reader is not None:
            read_errors = [reader.ReadError]
            reader.UpdatePipeline()
            produced = reader.GetDataInformation().GetNumberOfDataSets()
            Show(reader, view)  # what File > Open and Apply do next: nothing more may be said
            Render(view)
            reader.DecodeLevel = 1
            reader.UpdatePipeline()
            produced += reader.GetDataInformation().GetNumberOfDataSets()
            reader.UpdatePropertyInformation()
            read_errors.append(reader.ReadError)
        text = messages.GetOutput() if reader is not None else "no reader found " + messages.GetOutput()
    except RuntimeError as e:
        text = "OpenDataFile refused it: %s %s" % (e, messages.GetOutput())
    finally:
        vtkOutputWindow.SetInstance(console)
    if produced != 0:
        u.fail("%s produced data" % path)
    return text, read_errors


def error_text(output):
    """The text of the one vtkErrorMacro message in `output` (after "vtkAFAMReader (0x...): ")."""
    line = [l for l in output.splitlines() if "vtkAFAMReader (0x" in l][0]
    return line.split("): ", 1)[1].strip()


def check_read_error(path, text, read_errors):
    """ReadError is the reported error word for word, from OpenDataFile on; OpenAFAM raises it, with
    one error in the output window."""
    if read_errors is None:
        return
    said = error_text(text)
    if read_errors != [said, said]:
        u.fail("ReadError of %s is %s, the error said %r" % (path, read_errors, said))
    (raised, _), output = u.captured_messages(lambda: raises(path))
    print("  OpenAFAM raised: %s" % raised, flush=True)
    if raised != said:
        u.fail("OpenAFAM(%s) raised %r, not the error %r" % (path, raised, said))
    if output.count("ERROR:") != 1 or said not in output:
        u.fail("OpenAFAM(%s): not one error naming it: %s" % (path, output))


def raises(path):
    try:
        afam_open.OpenAFAM(path)
    except RuntimeError as e:
        return str(e), None
    return None, None


def expect(path, *words):
    text, read_errors = open_and_report(path)
    print("%s -> %s" % (os.path.basename(path), " ".join(text.split())[:400]))
    for w in (path,) + words:
        if w not in text:
            u.fail("the message for %s lacks '%s': %s" % (path, w, text))
    if "No reader found" in text or "no reader found" in text:
        u.fail("ParaView's generic message for %s" % path)
    errors = text.count("ERROR:") + text.count("OpenDataFile refused it")
    if errors != 1:
        u.fail("%d errors for %s, not one: %s" % (errors, path, text))
    check_read_error(path, text, read_errors)


# The first 60% of a valid file.
truncated = os.path.join(out, "truncated.afam")
cut = int(0.6 * len(data))
with open(truncated, "wb") as f:
    f.write(data[:cut])
expect(truncated, "truncated", "%d bytes" % cut, "header says %d" % len(data))

# A damaged header (a byte inside the volume's dimensions flipped): its checksum fails.
header = os.path.join(out, "header.afam")
damaged = bytearray(data)
damaged[40] ^= 0xFF
with open(header, "wb") as f:
    f.write(bytes(damaged))
text, read_errors = open_and_report(header)
print("header.afam -> %s" % " ".join(text.split())[:400])
if header not in text or not ("checksum" in text or "absurd" in text or "unsupported" in text):
    u.fail("the damaged header is not named: %s" % text)
if text.count("ERROR:") != 1:
    u.fail("not one error for the damaged header: %s" % text)
check_read_error(header, text, read_errors)

# A corrupt index (two bytes of the first entry flipped, docs/FORMAT.md: the index follows the
# 1024-byte header): its checksum fails.
index = os.path.join(out, "index.afam")
damaged = bytearray(data)
damaged[1024 + 12] ^= 0xFF
damaged[1024 + 13] ^= 0xFF
with open(index, "wb") as f:
    f.write(bytes(damaged))
expect(index, "index checksum mismatch (index damaged)")

# A file named .afam that is not one (readable, any other content): claimed and named, not left to
# ParaView's reader-choice dialog or "No reader found".
foreign = os.path.join(out, "foreign.afam")
with open(foreign, "wb") as f:
    f.write(b"P6\n4 4\n255\n" + bytes(range(48)) * 40)
expect(foreign, "not an .afam file")

# The same file again, after a good one: the error is said again for the new reader.
expect(truncated, "truncated")

# A newer format version (docs/FORMAT.md: the version is the uint32 at byte 8).
newer = os.path.join(out, "newer.afam")
damaged = bytearray(data)
damaged[8:12] = (99).to_bytes(4, "little")
with open(newer, "wb") as f:
    f.write(bytes(damaged))
expect(newer, "unsupported format version 99")

# An .afam that cannot be read at all: ParaView's own check names it before any reader is asked.
missing = os.path.join(out, "missing.afam")
if os.path.exists(missing):
    os.remove(missing)
expect(missing, "not readable")
# A good file: no ReadError, and OpenAFAM gives the reader.
(reader, output) = u.captured_messages(lambda: afam_open.OpenAFAM(good))
reader.UpdatePipeline()
print("good file: ReadError %r, %d data sets" % (reader.ReadError, reader.GetDataInformation().GetNumberOfDataSets()))
if reader.ReadError != "" or "ERROR:" in output or reader.GetDataInformation().GetNumberOfDataSets() < 2:
    u.fail("the good file: ReadError %r, output %r" % (reader.ReadError, output))
print("bad files: every message names the file and the problem")
