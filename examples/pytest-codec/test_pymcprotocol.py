"""pymcprotocol's MC-protocol ASCII value fields checked by pytest against the cross-vendor
corpus, one test per case: what a library maintainer adds to their own suite (docs/check-your-
library.md). Needs the plc-conformance wheel and pymcprotocol 0.3.0 (requirements.txt)."""
from pymcprotocol import Type3E
from plc_conformance.pytest_cases import codec_cases

codec = Type3E()
codec.setaccessopt(commtype="ascii")
MODE = {4: "short", 8: "long"}


def decode(text, digits):
    return codec._decode_value(text[:digits], MODE[digits])


def encode(value, digits):
    return codec._encode_value(value, MODE[digits])


test_pymcprotocol = codec_cases(decode, encode, name="pymcprotocol", digits=[4, 8], width=32,
                                errors={ValueError: "invalid-digit"},
                                known_differences="pymcprotocol.known.yaml")
