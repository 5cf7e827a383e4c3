#!/usr/bin/env python3
"""plc-conformance codec-level backend: omniplc's MC protocol serial (3C, format 4) ASCII fields.

omniplc (PyPI, MIT) reads every hex field of a 3C ASCII response with one internal function,
omniplc.plc.melsec.codec_serial._hex_int(raw) (`int(raw.decode("ascii"), 16)`, any failure
raised as ProtocolFrameError): the read data, 4 characters a word cut with a slice
(parse_3c_response, `_hex_int(data_text[i : i + 4]...)`), and the NAK's error code
(`_hex_int(response[11:15], ...)`). decode calls it on the field's slice, as those callers do.
It writes a word with _ascii_core(..., is_write=True, data=[value]) (`f"{word:04X}"`): encode
builds a one-word batch write of D0 and returns its last 4 characters, the data. The sum check
is codec_serial.checksum(payload) (the low byte of the sum), which build_3c_request writes as
`f"{checksum(body):02X}"` and parse_3c_response compares with the received 2 characters: check
and verify do exactly that. No check of the adapter's own is added.
Known differences: omniplc_mc_codec.known.yaml.
"""
import os
import sys
from importlib.metadata import version

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_adapter  # noqa: E402
from omniplc.core.errors import ProtocolFrameError  # noqa: E402
from omniplc.plc.melsec import codec_serial  # noqa: E402
from omniplc.plc.melsec.address import parse_mc_address  # noqa: E402

D0 = parse_mc_address("D0")


def decode(text, digits):
    # parse_3c_response cuts each field out of the response with a slice, then converts it.
    return codec_serial._hex_int(bytes(text[:digits]))


def encode(value, digits):
    # _ascii_core(address, points, is_bit, is_write, data, codes): command, subcommand, device,
    # number and points, then the data, 4 characters a word.
    return codec_serial._ascii_core(D0, 1, False, True, [value], None)[-4:]


def check(span):
    # build_3c_request: checksum_text = f"{checksum(body):02X}"
    return "%02X" % codec_serial.checksum(span)


def verify(frame):
    # parse_3c_response: wanted = f"{checksum(...):02X}"; response[...] != wanted -> refused
    return frame[-2:] == ("%02X" % codec_serial.checksum(frame[:-2])).encode("ascii")


plc_adapter.serve_codec(
    decode=decode, encode=encode, check=check, verify=verify,
    name="omniplc-mc", version=version("omniplc"),
    decode_digits=[4], encode_digits=[4], width=16,
    # ProtocolFrameError: "十六进制域非法" (not a hex field), raised by _hex_int for any text
    # int(..., 16) refuses.
    errors={ProtocolFrameError: "invalid-digit"},
    protocol="mc-ascii", fields=["word", "end-code", "sum"], cross_vendor=True)
