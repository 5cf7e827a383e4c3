"""The process that serves a codec for `codec_cases`: `python -m plc_conformance.serve FILE SPEC`
imports the module FILE, finds its decode, encode, check and verify functions and serves them with
plc_adapter.serve_codec as SPEC (JSON) says."""

import importlib
import json
import os
import sys

import plc_adapter
from plc_conformance.pytest_cases import SERVING, import_file


def _resolve(dotted):
    """"module:qualname" -> the object."""
    module, _, name = dotted.partition(":")
    value = importlib.import_module(module)
    for part in name.split("."):
        value = getattr(value, part)
    return value


def _attribute(module, qualname):
    value = module
    for part in qualname.split("."):
        value = getattr(value, part)
    return value


def _field(field):
    """A field shape as JSON carried it: widths' digit counts back to ints."""
    if field and "widths" in field:
        field = dict(field, widths={int(k): v for k, v in field["widths"].items()})
    return field


def main():
    file, spec = sys.argv[1], json.loads(sys.argv[2])
    os.environ[SERVING] = "1"
    module = import_file(file, spec["module"])
    plc_adapter.serve_codec(
        decode=_attribute(module, spec["decode"]) if spec["decode"] else None,
        encode=_attribute(module, spec["encode"]) if spec["encode"] else None,
        name=spec["name"], version=spec.get("version") or "pytest",
        decode_digits=spec["decode_digits"], encode_digits=spec["encode_digits"],
        width=spec["width"],
        errors={_resolve(k): v for k, v in spec["errors"].items()},
        decode_errors={_resolve(k): v for k, v in spec.get("decode_errors", {}).items()} or None,
        encode_errors={_resolve(k): v for k, v in spec.get("encode_errors", {}).items()} or None,
        decode_reading=spec.get("decode_reading"), encode_reading=spec.get("encode_reading"),
        field=_field(spec["field"]), decode_field=_field(spec["decode_field"]),
        encode_field=_field(spec["encode_field"]),
        protocol=spec.get("protocol"), fields=spec.get("fields"),
        cross_vendor=spec.get("cross_vendor", False),
        check=_attribute(module, spec["check"]) if spec.get("check") else None,
        verify=_attribute(module, spec["verify"]) if spec.get("verify") else None)


if __name__ == "__main__":
    main()
