"""`python -m plc_conformance ARGS` runs the installed `plc-conformance ARGS`."""

import os
import sys

from plc_conformance import binary


def main():
    path = binary()
    if os.name == "nt":
        import subprocess
        sys.exit(subprocess.call([path, *sys.argv[1:]]))
    os.execv(path, [path, *sys.argv[1:]])


if __name__ == "__main__":
    main()
