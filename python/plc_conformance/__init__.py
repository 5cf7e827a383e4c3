"""plc-conformance for Python users.

The wheel installs the `plc-conformance` command (the harness, a native binary: no Rust needed)
beside this package, the `plc_adapter` helper that serves a codec or an emulator to it, and
`plc_conformance.pytest_cases.codec_cases`, which turns a codec's two functions into one pytest
test per cross-vendor case. docs/check-your-library.md walks through it.
"""

import os
import shutil
import sys
import sysconfig

__all__ = ["binary"]


def binary():
    """The path of the `plc-conformance` command installed with this package: the scripts folder
    of this interpreter's installation (a venv's `bin/`), then the user scheme's, then PATH."""
    name = "plc-conformance" + (".exe" if os.name == "nt" else "")
    folders = [sysconfig.get_path("scripts")]
    user = "%s_user" % os.name
    if user in sysconfig.get_scheme_names():
        folders.append(sysconfig.get_path("scripts", scheme=user))
    for folder in folders:
        candidate = os.path.join(folder, name)
        if os.path.isfile(candidate):
            return candidate
    found = shutil.which(name)
    if found:
        return found
    raise FileNotFoundError(
        "the plc-conformance command is not installed with this Python (%s): install the "
        "plc-conformance wheel, or put the command on PATH" % sys.executable)
