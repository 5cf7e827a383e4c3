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

import os
import sys

from plc_conformance.pytest_cases import DESCRIBING, command_line, import_file

__all__ = ["command"]


class UsageError(Exception):
    """What is wrong with the arguments, said as the command line would."""


def _codecs(path):
    """{test name: codec} of the module at `path`, imported as codec_cases describes itself."""
    if not os.path.isfile(path):
        raise UsageError("no test file %s" % path)
    os.environ[DESCRIBING] = "1"
    module = import_file(path, os.path.splitext(os.path.basename(path))[0])
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
    return command_line(codec, subcommand, args)


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
