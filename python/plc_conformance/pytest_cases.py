"""One pytest test per cross-vendor case, for a codec's decode and encode functions.

In a library's own test suite::

    from plc_conformance.pytest_cases import codec_cases
    import mylib

    def decode(text, digits):          # bytes -> int
        return mylib.decode_word(text[:digits])

    def encode(value, digits):         # int -> str or bytes
        return mylib.encode_word(value, digits)

    test_conformance = codec_cases(decode, encode, name="mylib", digits=[4],
                                   errors={ValueError: "invalid-digit"},
                                   known_differences="mylib.known.yaml")

At collection, the `plc-conformance` command installed with this package runs the cross-vendor
corpus against the two functions (served in a process of their own by `plc_adapter`, as any
codec), once; each case is then a test: passed, failed with the harness's diff, skipped with the
reason (a digit count the codec does not take), or an expected failure where the
known-differences file names the case. A harness that cannot run the codec at all (the command
missing, a bad known-differences file, a codec that does not start) is a collection error with
the harness's message, never a pass.

The same test module gives the codec every other command, with no second entry point:
`python -m plc_conformance.codec test_mylib.py sweep --operation hex-to-value --generator full`
(also `record`, `list`, `diff`, `run`), with the codec's name, timeout and known differences as
codec_cases was given them.
"""

import json
import os
import shlex
import subprocess
import sys
import tempfile

from plc_conformance import binary

__all__ = ["codec_cases"]

# Set in the process that serves the codec: the test module is imported there to find the
# functions, and its codec_cases() must not run the harness again.
SERVING = "PLC_CONFORMANCE_SERVING_CODEC"
# Set by `python -m plc_conformance.codec`: the test module is imported for its codec only, and
# codec_cases() returns what the command needs instead of running the corpus.
DESCRIBING = "PLC_CONFORMANCE_DESCRIBING_CODEC"


# The commands that take each option, as `plc-conformance COMMAND --help` lists them.
TAKES_TIMEOUT = {"run", "diff", "sweep", "record"}
TAKES_KNOWN_DIFFERENCES = {"run", "diff", "sweep"}


def command_line(codec, subcommand, args):
    """The plc-conformance command line running `subcommand` (with its own `args`) on `codec`
    as codec_cases describes it: the codec as the backend, its timeout and known differences
    where the command takes them."""
    line = [binary(), subcommand, *args, "--backend", codec["backend"]]
    if subcommand in TAKES_TIMEOUT:
        line += ["--timeout", str(codec["timeout"])]
    if subcommand in TAKES_KNOWN_DIFFERENCES and codec["known_differences"] is not None:
        line += ["--known-differences", "%s=%s" % (codec["name"], codec["known_differences"])]
    return line


def import_file(path, name):
    """The module in the file `path`, imported as `name` with its folder and the current folder
    on the path, as pytest's own imports see them (the serving process and the codec command
    import the test module this way)."""
    import importlib.util

    sys.path[:0] = [os.path.dirname(os.path.abspath(path)), os.getcwd()]
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def _where(function):
    """(file, qualified name) of a module-level function, for the serving process."""
    module = sys.modules.get(getattr(function, "__module__", None))
    path = getattr(module, "__file__", None)
    name = getattr(function, "__qualname__", "")
    if path is None or "<" in name:
        raise TypeError("codec_cases: %r must be a function defined at the top level of a module "
                        "(it runs in a process of its own)" % (function,))
    return os.path.abspath(path), name


def _error_names(errors):
    """{exception class: error class} as {"module:qualname": error class}."""
    return {"%s:%s" % (k.__module__, k.__qualname__): v for k, v in (errors or {}).items()}


def codec_cases(decode=None, encode=None, *, name="codec", version=None, digits=None,
                decode_digits=None, encode_digits=None, width=16, errors=None,
                decode_errors=None, encode_errors=None, decode_reading=None,
                encode_reading=None, field=None, decode_field=None, encode_field=None,
                known_differences=None, timeout=5.0, protocol=None, fields=None,
                cross_vendor=False, check=None, verify=None):
    """A pytest test function, parametrized by cross-vendor case: assign it to a `test_` name.

    decode(text: bytes, digits) -> int and encode(value, digits) -> str or bytes are functions
    at the top level of a module (the test module itself will do); digits sets both directions'
    digit counts (decode_digits / encode_digits one each); version, width, errors,
    decode_errors / encode_errors, decode_reading / encode_reading and the field shapes are
    those of plc_adapter.serve_codec (docs/protocol.md, "Field shapes"), which takes digits too;
    known_differences is a known-differences file, relative to the calling module's folder.
    protocol, fields, cross_vendor, check and verify are those of plc_adapter.serve_codec: a
    library of a protocol's fields ("mc-ascii", "modbus-ascii", ...) is judged by that
    protocol's corpus, one test per protocol-field case (docs/protocol.md, "A protocol's
    fields"); check(span) and verify(frame) are module-level functions too.
    """
    if os.environ.get(SERVING):
        # The serving process imports the test module only for the functions (pytest need not
        # be there: `python -m plc_conformance.codec` starts it too).
        def serving():
            """The codec's own process."""

        return serving
    if decode is None and encode is None and check is None and verify is None:
        raise TypeError("codec_cases: give decode, encode, check or verify")
    first = decode or encode or check or verify
    file, _ = _where(first)
    spec = {
        "module": os.path.splitext(os.path.basename(file))[0],
        "decode": _where(decode)[1] if decode else None,
        "encode": _where(encode)[1] if encode else None,
        "name": name,
        "version": version,
        "decode_errors": _error_names(decode_errors),
        "encode_errors": _error_names(encode_errors),
        "decode_reading": decode_reading,
        "encode_reading": encode_reading,
        "decode_digits": decode_digits if decode_digits is not None else digits,
        "encode_digits": encode_digits if encode_digits is not None else digits,
        "width": width,
        "errors": _error_names(errors),
        "field": field,
        "decode_field": decode_field,
        "encode_field": encode_field,
        "protocol": protocol,
        "fields": fields,
        "cross_vendor": cross_vendor,
        "check": _where(check)[1] if check else None,
        "verify": _where(verify)[1] if verify else None,
    }
    serve = [sys.executable, "-m", "plc_conformance.serve", file, json.dumps(spec)]
    codec = {
        "name": name,
        "backend": "external:%s=%s" % (name, shlex.join(serve)),
        "timeout": timeout,
        "known_differences": (os.path.join(os.path.dirname(file), known_differences)
                              if known_differences is not None else None),
    }
    if os.environ.get(DESCRIBING):
        def described():
            """The codec as `python -m plc_conformance.codec` runs it."""

        described.plc_conformance_codec = codec
        return described
    import pytest

    with tempfile.TemporaryDirectory(prefix="plc-conformance-") as folder:
        output = os.path.join(folder, "results.json")
        command = command_line(codec, "run", ["--format", "json", "--output", output])
        # Run where the test module is, away from any project folder above the current one: the
        # corpus is the one built into the command.
        done = subprocess.run(command, cwd=folder, capture_output=True, text=True)
        if done.returncode not in (0, 1) or not os.path.exists(output):
            raise RuntimeError("plc-conformance could not run %s (exit status %s):\n%s"
                               % (name, done.returncode, done.stderr.strip()))
        with open(output, encoding="utf-8") as f:
            records = [r for r in json.load(f)["records"]
                       if r["column"].split("/")[0] == name]
    if not records:
        raise RuntimeError("plc-conformance ran no case of %s:\n%s" % (name, done.stderr.strip()))

    @pytest.mark.parametrize("record", records, ids=[r["row"] for r in records])
    def test_case(record):
        status, detail = record["status"], record["detail"]
        if status == "fail":
            pytest.fail(detail, pytrace=False)
        if record["label"] == "known-difference":
            pytest.xfail(detail)
        if status == "skipped":
            pytest.skip(detail)
        if status == "ignored":
            pytest.skip("not judged (the manuals leave it open): " + record["shown"])

    test_case.plc_conformance_codec = codec
    return test_case
