#!/usr/bin/env python3
"""plc-conformance codec-level backend: fx3u-mcprotocol's MC protocol (1E frame) ASCII word.

fx3u-mcprotocol (PyPI, MIT) reads words from an FX3 CPU through an FX3U-ENET-ADP in the MC
protocol's A-compatible 1E frame, ASCII code: FX3UClient.readRegs (fx3u_mcprotocol/client.py:74)
sends ASCIIProtocol.build_read_words and hands the reply to ASCIIProtocol.parse_read_words
(fx3u_mcprotocol/protocol_ascii.py:73), which decodes it with `response.decode("ascii",
errors="ignore")` (:78), checks the completion code "00" (:119), cuts each word with a slice of
4 characters (:86), refuses a slice that is not 4 long (:90) and converts it with
`int(raw, 16)` (:94). Its ASCII backend has no write of words (no build_write_words:
FX3UClient.writeRegs raises "Write not supported", client.py:135-136), so only decoding is wired.

This adapter runs FX3UClient.readReg("D0") in ASCII mode on a transport object in process (no
socket), which answers the 1E read with subheader "81", completion code "00" and the field.
No check of the adapter's own is added. Known differences: fx3u_mcprotocol_codec.known.yaml.
"""
import os
import sys
from importlib.metadata import version

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_adapter  # noqa: E402
from fx3u_mcprotocol import FX3UClient  # noqa: E402
from fx3u_mcprotocol.exceptions import PLCError  # noqa: E402


class Transport:
    """The client's transport in process: send keeps the request, receive gives the reply."""

    def __init__(self):
        self.reply = b""
        self.sent = b""

    def send(self, data):
        self.sent = bytes(data)

    def receive(self, size=4096):
        return self.reply[:size]


transport = Transport()
client = FX3UClient("127.0.0.1", mode="ascii")
client.transport = transport


def decode(text, digits):
    # 1E response, ASCII code: subheader "81" (batch read in word units), completion code "00",
    # then the words.
    transport.reply = b"8100" + bytes(text)
    return client.readReg("D0")


plc_adapter.serve_codec(
    decode=decode,
    name="fx3u-mcprotocol", version=version("fx3u-mcprotocol"),
    decode_digits=[4], width=16,
    # ValueError: int(raw, 16) refuses the slice (:94); PLCError: "Incomplete word response",
    # the slice is not 4 characters (:90-93).
    errors={ValueError: "invalid-digit", PLCError: "invalid-digit"},
    protocol="mc-ascii", fields=["word"], cross_vendor=True)
