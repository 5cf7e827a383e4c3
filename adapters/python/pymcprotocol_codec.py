#!/usr/bin/env python3
"""plc-conformance codec-level backend: pymcprotocol's MC-protocol ASCII value fields.

In ASCII mode pymcprotocol (PyPI, MIT) sends a word as 4 hex characters and a double word as 8,
most significant digit first: Type3E._decode_value(text, "short"/"long") reads such a field and
Type3E._encode_value(value, "short"/"long") writes it. Its callers cut the field out of a
response with a slice, as decode does here. Judged by the MC protocol's corpus (its word and
double-word fields) and the cross-vendor one. Known differences: pymcprotocol_codec.known.yaml.
"""
import os
import sys
from importlib.metadata import version

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_adapter  # noqa: E402
from pymcprotocol import Type3E  # noqa: E402

codec = Type3E()
codec.setaccessopt(commtype="ascii")
MODE = {4: "short", 8: "long"}


def encode(value, digits):
    try:
        return codec._encode_value(value, MODE[digits])
    except ValueError as e:  # "Exceeeded Device value range": the value is wider than the field
        raise plc_adapter.CodecError("error", e)


plc_adapter.serve_codec(
    decode=lambda text, digits: codec._decode_value(text[:digits], MODE[digits]),
    encode=encode,
    name="pymcprotocol", version=version("pymcprotocol"),
    decode_digits=[4, 8], encode_digits=[4, 8], width=32,
    errors={ValueError: "invalid-digit"},
    # Judged by the MC protocol's own manual (its word and double-word fields), and by the
    # cross-vendor corpus too.
    protocol="mc-ascii", fields=["word", "dword"], cross_vendor=True)
