#!/usr/bin/env python3
"""{{name}} as a codec-level backend of plc-conformance: the corpus asks it "this text, this many
digits: what value?" and "this value, this many digits: what text?" and compares each answer with
what the vendors' manuals give.

Written by `plc-conformance init codec --python`. Run it:

    plc-conformance run --backend 'external:{{name}}=python3 {{name}}_adapter.py' \
        --known-differences {{name}}={{name}}.known.yaml

The helper, plc_adapter, is the plc-conformance Python helper (standard library only):
pip install PATH/TO/plc-conformance/adapters/python
Guide: docs/check-your-library.md in plc-conformance.
"""
import plc_adapter

# 1. Import your library's conversions here, e.g.:
#    from mylib.codec import decode_word, encode_word, BadDigit


def decode(text, digits):
    """Text -> value. `text` is bytes, any byte values (the corpus sends lowercase letters,
    blanks, 00H and bytes above 7FH on purpose); `digits` is the count to convert.
    Return an int, or raise one of the errors mapped below."""
    # 2. Replace this stand-in (Python's own int(), a common choice) with your library's call.
    return int(text[:digits].decode("latin-1"), 16)


def encode(value, digits):
    """Value -> text: return bytes or str, `digits` characters."""
    # 3. Replace this stand-in with your library's call.
    return "%0*X" % (digits, value)


plc_adapter.serve_codec(
    decode=decode,           # leave out decode or encode if the library only goes one way
    encode=encode,
    name="{{name}}", version="0.0.0",   # 4. your library's version, as it reports it
    # 5. The digit counts it converts, and the width of its values (16 or 32 bits).
    decode_digits=[4], encode_digits=[4], width=16,
    # 6. Its exceptions, as the shared error classes: invalid-digit, invalid-count,
    #    device-range, or error (any other refusal).
    errors={ValueError: "invalid-digit"},
    # 7. The protocol it speaks, whose own manual then judges it, each difference naming the
    #    rule and its page: mc-ascii, modbus-ascii, fx-computer-link, mewtocol-com,
    #    omron-host-link or keyence-kv-l2 (leave it out for a codec of no protocol, which the
    #    instruction manuals judge). fields=[...] names the protocol's fields it implements,
    #    check= and verify= its check character (docs/check-your-library.md, section 1).
    {{protocol_py}}
    # 8. Optional: the field's shape, where it is not a fixed run of digits most significant
    #    first, e.g. {"widths": {2: 8}} for byte fields, {"byte_order": "low-first"} for
    #    MEWTOCOL, {"whole_frame": True} when the library checks the frame around the field.
    # field={"widths": {2: 8}},
    # 9. Optional: the built-in reading it means to follow; `plc-conformance sweep` then judges
    #    it against that reading.
    # decode_reading="fx5/hexa-16bit", encode_reading="fx5/asci-16bit",
)
