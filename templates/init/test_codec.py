"""{{name}} checked against plc-conformance's corpus by pytest: one test per case the corpus asks
("this text, this many digits: what value?", "this value, this many digits: what text?"), each
difference failing with the harness's diff, the ones on record expected failures.

Written by `plc-conformance init codec --python`. It runs green as written, on a stand-in that
reads as the manuals do; put your library's calls where the stand-in is, then run

    pytest -q test_{{ident}}_conformance.py

and every other command on the same codec (sweep, record, list, diff) with

    python -m plc_conformance.codec test_{{ident}}_conformance.py sweep --operation hex-to-value

Needs the plc-conformance wheel with pytest: pip install "plc-conformance[pytest]=={{version}}".
Guide: docs/check-your-library.md in plc-conformance.
"""
from plc_conformance.pytest_cases import codec_cases

# 1. Import your library's conversions here, e.g.:
#    from mylib.codec import decode_word, encode_word, BadDigit


def decode(text, digits):
    """Text -> value. `text` is bytes, any byte values (the corpus sends lowercase letters,
    blanks, 00H and bytes above 7FH on purpose); `digits` is the count to convert.
    Return an int, or raise one of the errors mapped below."""
    # 2. Replace this stand-in with your library's call. It reads as the manuals do (exactly
    #    the digits asked, each 0-9 or A-F), which is why the scaffold runs green as written.
    {{field_py}}
    if any(c not in b"0123456789ABCDEF" for c in field):
        raise ValueError("not a hex digit in %r" % field)
    return int(field, 16)


def encode(value, digits):
    """Value -> text: return bytes or str, `digits` characters."""
    # 3. Replace this stand-in with your library's call.
    return "%0*X" % (digits, value)


test_{{ident}} = codec_cases(
    decode,                  # leave out decode or encode if the library only goes one way
    encode,
    name="{{name}}", version="0.0.0",   # 4. your library's version, as it reports it
    # 5. The digit counts it converts, and the width of its values (16 or 32 bits).
    decode_digits=[4], encode_digits=[4], width=16,
    # 6. Its exceptions, as the shared error classes: invalid-digit, invalid-count,
    #    device-range, or error (any other refusal).
    errors={ValueError: "invalid-digit", IndexError: "invalid-count"},
    # 7. The protocol it speaks, whose own manual then judges it, each difference naming the
    #    rule and its page: mc-ascii, modbus-ascii, fx-computer-link, mewtocol-com,
    #    omron-host-link or keyence-kv-l2 (leave it out for a codec of no protocol, which the
    #    instruction manuals judge). fields=[...] names the protocol's fields it implements,
    #    check= and verify= its check character (docs/check-your-library.md, section 1).
    {{protocol_py}}
    # 8. What it gets wrong on purpose or by accident, one entry per cause: `python -m
    #    plc_conformance.codec test_{{ident}}_conformance.py record --known FILE` drafts it.
    known_differences="{{name}}.known.yaml",
    # 9. Optional: the field's shape, where it is not a fixed run of digits most significant
    #    first, e.g. {"widths": {2: 8}} for byte fields, {"byte_order": "low-first"} for
    #    MEWTOCOL, {"whole_frame": True} when the library checks the frame around the field.
    # field={"widths": {2: 8}},
    # 10. Optional: the built-in reading it means to follow; a sweep then judges it against
    #    that reading.
    # decode_reading="fx5/hexa-16bit", encode_reading="fx5/asci-16bit",
)
