"""`python -m plc_conformance.codec TESTS[:NAME] COMMAND [ARGS...]`: the plc-conformance command
on the codec a pytest module declares with codec_cases, so that `sweep`, `record`, `list`, `diff`
and `run` need no entry point beside the test file.

TESTS is the test module's file; NAME the test_ name codec_cases was assigned to, needed only
when the module declares more than one codec. The command gets the codec as its `--backend`
(served by plc_adapter in a process of its own, as pytest serves it), with codec_cases's
`timeout` and `known_differences` where the command takes them; ARGS are the command's own:

    python -m plc_conformance.codec tests/test_mylib.py sweep --operation hex-to-value \\
        --generator full
    python -m plc_conformance.codec tests/test_mylib.py list --filter xv-h2v
"""

import importlib.util
import os
import sys

from plc_conformance import binary
from plc_conformance.pytest_cases import DESCRIBING

__all__ = ["command"]

# The commands that take each option, as `plc-conformance COMMAND --help` lists them.
TAKES_TIMEOUT = {"run", "diff", "sweep", "record"}
TAKES_KNOWN_DIFFERENCES = {"run", "diff", "sweep"}


class UsageError(Exception):
    """What is wrong with the arguments, said as the command line would."""


def _codecs(path):
    """{test name: codec} of the module at `path`, imported as codec_cases describes itself."""
    if not os.path.isfile(path):
        raise UsageError("no test file %s" % path)
    os.environ[DESCRIBING] = "1"
    folder = os.path.dirname(os.path.abspath(path))
    sys.path[:0] = [folder, os.getcwd()]
    name = os.path.splitext(os.path.basename(path))[0]
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return {k: v.plc_conformance_codec for k, v in vars(module).items()
            if hasattr(v, "plc_conformance_codec")}


def command(target, subcommand, args):
    """The plc-conformance command line that runs `subcommand` on the codec `target` names."""
    path, colon, attribute = target.rpartition(":")
    if not colon or not path or os.path.isfile(target):
        path, attribute = target, ""
    codecs = _codecs(path)
    if not codecs:
        raise UsageError("%s declares no codec: assign codec_cases(...) to a test_ name" % path)
    if attribute:
        if attribute not in codecs:
            raise UsageError("%s has no codec %s; its codecs: %s"
                             % (path, attribute, ", ".join(sorted(codecs))))
        codec = codecs[attribute]
    elif len(codecs) == 1:
        codec = next(iter(codecs.values()))
    else:
        raise UsageError("%s declares %d codecs: name one as %s:NAME (%s)"
                         % (path, len(codecs), path, ", ".join(sorted(codecs))))
    line = [binary(), subcommand, *args, "--backend", codec["backend"]]
    if subcommand in TAKES_TIMEOUT:
        line += ["--timeout", str(codec["timeout"])]
    if subcommand in TAKES_KNOWN_DIFFERENCES and codec["known_differences"] is not None:
        line += ["--known-differences", "%s=%s" % (codec["name"], codec["known_differences"])]
    return line


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) < 2 or argv[0] in ("-h", "--help"):
        print(__doc__.strip(), file=sys.stderr)
        sys.exit(0 if argv[:1] in (["-h"], ["--help"]) else 2)
    try:
        line = command(argv[0], argv[1], argv[2:])
    except UsageError as e:
        print("error: %s" % e, file=sys.stderr)
        sys.exit(2)
    if os.name == "nt":
        import subprocess
        sys.exit(subprocess.call(line))
    os.execv(line[0], line)


if __name__ == "__main__":
    main()
