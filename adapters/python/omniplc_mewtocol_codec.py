#!/usr/bin/env python3
"""plc-conformance codec-level backend: omniplc's Panasonic MEWTOCOL-COM data words and BCC.

omniplc (PyPI, MIT) reads data words in the client method _MewtocolBase._read_words
(omniplc/plc/panasonic/mewtocol.py): it sends an RD command, takes the response through
codec_mewtocol.parse_response (header, station, BCC), checks the data's length, converts it
with bytes.fromhex and unpacks it with struct ">H", high byte first. decode runs that very
method on a client whose transport (in process, no socket) answers the RD with the field as its
data, framed as a PLC would frame it: "%01$RD", the field, its BCC (codec_mewtocol.bcc), CR.
Writing a word is codec_mewtocol.build_write_words (`f"{word:04X}"`): encode builds a WD of one
word and returns its 4 data characters. The BCC is codec_mewtocol.bcc(text), which
parse_response compares with the received 2 characters (`if bcc(body) != expected_bcc`): check
and verify do exactly that. No check of the adapter's own is added.
Known differences: omniplc_mewtocol_codec.known.yaml.
"""
import os
import sys
from importlib.metadata import version

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_adapter  # noqa: E402
from omniplc.core.errors import ProtocolFrameError  # noqa: E402
from omniplc.plc.panasonic import codec_mewtocol  # noqa: E402
from omniplc.plc.panasonic.address import parse_mewtocol_address  # noqa: E402
from omniplc.plc.panasonic.mewtocol import PanasonicMewtocolTcpClient  # noqa: E402
from omniplc.transport.base import BaseTransport  # noqa: E402


class Reply(BaseTransport):
    """A stream transport in process: recv(size) gives the next size bytes of the prepared
    reply, as a TCP socket does; a reply that ends early times out, as on the wire."""

    def __init__(self, reply):
        super().__init__()
        self.reply = reply

    def connect(self):
        pass

    def close(self):
        pass

    def send(self, data):
        pass

    def recv(self, size):
        if len(self.reply) < size:
            raise TimeoutError("the reply ends after %d of %d bytes" % (len(self.reply), size))
        data, self.reply = self.reply[:size], self.reply[size:]
        return data


client = PanasonicMewtocolTcpClient("127.0.0.1", 1024, station=1)
DT0 = parse_mewtocol_address("D0", False)


def decode(text, digits):
    body = b"%01$RD" + bytes(text)
    client._transport = Reply(body + codec_mewtocol.bcc(body.decode("latin-1")).encode("latin-1")
                               + b"\r")
    return client._read_words(DT0, 1)[0]


def encode(value, digits):
    # "%01#WDD" + start (5) + end (5) + data + BCC (2) + CR: the data is before the BCC.
    return codec_mewtocol.build_write_words("01", DT0.area, DT0.word, [value])[-7:-3]


def check(span):
    return codec_mewtocol.bcc(span.decode("latin-1"))


def verify(frame):
    # parse_response: body = text[:-3]; expected_bcc = text[-3:-1]; if bcc(body) != expected_bcc
    text = frame.decode("latin-1")
    return codec_mewtocol.bcc(text[:-2]) == text[-2:]


plc_adapter.serve_codec(
    decode=decode, encode=encode, check=check, verify=verify,
    name="omniplc-mewtocol", version=version("omniplc"),
    decode_digits=[4], encode_digits=[4], width=16,
    # ProtocolFrameError: the data is not hex ("含非十六进制数据"), has the wrong length, or the
    # frame's BCC does not check. TimeoutError: the reply ends before the RD's data does, which
    # the client waits for; the text ends inside the field, where memory has 00H, no digit.
    errors={ProtocolFrameError: "invalid-digit", TimeoutError: "invalid-digit"},
    protocol="mewtocol-com", fields=["word", "bcc"], cross_vendor=True)
