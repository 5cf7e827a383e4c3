#!/usr/bin/env python3
"""plc-conformance codec-level backend: aslmp's SLMP ASCII numeric fields.

aslmp (PyPI, Apache-2.0) codes every numeric field of an SLMP ASCII frame with one object,
aslmp.wire.codec.ASCII: ASCII.read_number(buf, offset, bits=8/16/32) reads 2, 4 or 8 hex
characters and refuses any byte outside 0-9, A-F (SlmpHexDigitError) or a buffer that ends
inside the field (SlmpShortBufferError); ASCII.number(value, bits=...) writes the value in
uppercase and refuses one wider than the field (SlmpCodecValueError).
Known differences: aslmp_codec.known.yaml.
"""
import os
import sys
from importlib.metadata import version

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_adapter  # noqa: E402
from aslmp.wire.codec import ASCII, SlmpCodecValueError, SlmpHexDigitError, SlmpShortBufferError  # noqa: E402

plc_adapter.serve_codec(
    decode=lambda text, digits: ASCII.read_number(text, 0, bits=4 * digits),
    encode=lambda value, digits: ASCII.number(value, bits=4 * digits),
    name="aslmp", version=version("aslmp"),
    decode_digits=[2, 4, 8], encode_digits=[2, 4, 8], width=32,
    # A text that ends inside the field ends with 00H in memory: not a digit.
    errors={SlmpHexDigitError: "invalid-digit", SlmpShortBufferError: "invalid-digit",
            SlmpCodecValueError: "error"},
    # Judged by the MC protocol's own manual (words, double words, end codes), and by the
    # cross-vendor corpus too.
    protocol="mc-ascii", fields=["word", "dword", "end-code"], cross_vendor=True)
