#!/usr/bin/env python3
"""plc-conformance backend for pymcprotocol's hex-ASCII word conversion.

pymcprotocol (PyPI, MIT) implements the MELSEC communication protocol. In ASCII mode
("commtype=ascii") every word travels as 4 hex-ASCII characters, most significant digit first,
and every double word as 8: Type3E._encode_value(value, "short"/"long") builds that text and
Type3E._decode_value(text, "short"/"long") reads it back. That is the conversion HABIN/DHABIN
(text -> binary) and BINHA/DBINHA (binary -> text) perform with SM705 off, so the corpus of those
instructions checks pymcprotocol's codec.

What is pymcprotocol's and what is this adapter's:
- pymcprotocol: the text <-> number conversion, including what text it accepts (a ValueError is
  its "invalid data").
- the adapter: reading the characters from words two per word, low byte first, and writing them
  back the same way; the 0000H word BINHA writes after the text unless SM701 is on; a ValueError
  reported as the iQ-R error code 3401H (invalid data); a constant or a value read from memory
  passed as the unsigned word it is stored as; the CPU's device-range check (2820H), which is no
  part of a codec.

Declared capabilities: the iQ-R instructions above on every variant, with SM705 off only (with
SM705 on, HABIN reads 00H-terminated text of 1-4 digits and BINHA drops leading zeros: no
pymcprotocol function does that, so those cases are skipped with that reason).
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import plc_adapter  # noqa: E402

try:
    from importlib.metadata import version as _version

    from pymcprotocol import Type3E
except ImportError as e:  # pragma: no cover - reported to the harness as a failed start
    sys.stderr.write(
        "pymcprotocol is not installed (%s): python3 -m venv .venv-adapters && "
        ".venv-adapters/bin/pip install -r adapters/python/requirements.txt\n" % e
    )
    sys.exit(1)

# iQ-R operation errors: data that does not convert (MELSEC iQ-R programming manual, HABIN),
# and a device past the end of its range.
ERR_INVALID_DATA = 0x3401
ERR_DEVICE_RANGE = 0x2820

# Instruction -> (pymcprotocol value mode, words of binary data).
HABIN = {"HABIN": ("short", 1), "HABINP": ("short", 1), "DHABIN": ("long", 2), "DHABINP": ("long", 2)}
BINHA = {"BINHA": ("short", 1), "BINHAP": ("short", 1), "DBINHA": ("long", 2), "DBINHAP": ("long", 2)}

_codec = Type3E()
_codec.setaccessopt(commtype="ascii")


def text_at(case, head, count):
    """count characters stored two per word from head, low byte first."""
    out = bytearray()
    for k in range(count):
        word = case.read(head.offset(k // 2))
        out.append(word & 0xFF if k % 2 == 0 else word >> 8)
    return bytes(out)


def write_text(case, head, text):
    if len(text) % 2:
        text += b"\0"
    for i in range(0, len(text), 2):
        case.write(head.offset(i // 2), text[i] | (text[i + 1] << 8))


def in_range(case, head, count):
    """Whether count words from head exist on the variant (the CPU's 2820H check)."""
    return all(case.exists(head.offset(i)) for i in range(count))


def habin(case, mode, words):
    source, dest = case.device("s"), case.device("d")
    if not (in_range(case, source, 2 * words) and in_range(case, dest, words)):
        case.fail(code=ERR_DEVICE_RANGE)
        return
    field = text_at(case, source, 4 * words)
    try:
        value = _codec._decode_value(field, mode)
    except ValueError:
        case.fail(code=ERR_INVALID_DATA)
        return
    for w in range(words):
        case.write(dest.offset(w), (value >> (16 * w)) & 0xFFFF)


def binha(case, mode, words):
    source, dest = case.operand("s"), case.device("d")
    mask = (1 << (16 * words)) - 1
    if isinstance(source, int):
        value = source & mask
    elif in_range(case, source, words):
        value = sum(case.read(source.offset(w)) << (16 * w) for w in range(words))
    else:
        case.fail(code=ERR_DEVICE_RANGE)
        return
    text = _codec._encode_value(value, mode)
    if not case.flag("SM701"):
        text += b"\0\0"
    if not in_range(case, dest, len(text) // 2):
        case.fail(code=ERR_DEVICE_RANGE)
        return
    write_text(case, dest, text)


def run(case):
    if case.flag("SM705"):
        raise plc_adapter.Unsupported("SM705 on is not a pymcprotocol conversion")
    if case.instruction in HABIN:
        habin(case, *HABIN[case.instruction])
    elif case.instruction in BINHA:
        binha(case, *BINHA[case.instruction])
    else:
        raise plc_adapter.Unsupported("%s is not implemented" % case.instruction)


if __name__ == "__main__":
    plc_adapter.serve(
        run,
        name="pymcprotocol",
        version=_version("pymcprotocol"),
        profile="mitsubishi-iqr",
        instructions=sorted(HABIN) + sorted(BINHA),
        flags={"SM705": [False]},
    )
