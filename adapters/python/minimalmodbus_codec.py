#!/usr/bin/env python3
"""plc-conformance codec-level backend: minimalmodbus's Modbus ASCII coding.

minimalmodbus (PyPI, Apache-2.0) converts a Modbus ASCII frame's characters with
_hexdecode(hexbytes) (an even length, then binascii.unhexlify, its errors raised as TypeError)
and writes them with _hexencode(bytes) (binascii.hexlify(...).upper()); a register's two bytes
are _two_bytes_to_num / _num_to_two_bytes; the LRC is _calculate_lrc(bytes), written
_hexencode(_calculate_lrc(first_part)) (_embed_payload); a response is checked by
_extract_payload(response, slaveaddress, "ascii", functioncode), which strips ':' and CR LF,
decodes and compares the LRC. decode and encode are those functions on the register field;
check is _hexencode(_calculate_lrc(_hexdecode(span))); verify is _extract_payload on
":" + the frame + CR LF, accepted when it returns. No check of the adapter's own is added.
Known differences: minimalmodbus_codec.known.yaml.
"""
import os
import sys
from importlib.metadata import version

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_adapter  # noqa: E402
import minimalmodbus as mm  # noqa: E402


def verify(frame):
    mm._extract_payload(b":" + bytes(frame) + b"\r\n", 1, mm.MODE_ASCII, 3)
    return True


plc_adapter.serve_codec(
    decode=lambda text, digits: mm._two_bytes_to_num(mm._hexdecode(bytes(text))),
    encode=lambda value, digits: mm._hexencode(mm._num_to_two_bytes(value)),
    check=lambda span: mm._hexencode(mm._calculate_lrc(mm._hexdecode(bytes(span)))),
    verify=verify,
    name="minimalmodbus", version=version("minimalmodbus"),
    decode_digits=[4], encode_digits=[4], width=16,
    # _hexdecode: ValueError for an odd length, TypeError for a character unhexlify refuses;
    # _two_bytes_to_num: ValueError for other than 2 bytes; _extract_payload:
    # InvalidResponseError (a MasterReportedException, an IOError) for a wrong LRC.
    errors={ValueError: "invalid-digit", TypeError: "invalid-digit",
            mm.InvalidResponseError: "invalid-digit"},
    protocol="modbus-ascii", fields=["register", "lrc"], cross_vendor=True)
