#!/usr/bin/env python3
"""plc-conformance codec-level backend: melsec-mc-protocol's MC protocol ASCII word field.

melsec-mc-protocol (PyPI, MIT; module melsec_mc) has one client, MelsecMCProtocol, whose ASCII
mode (MCProtocolType.ASCII) converts a word in its client methods only:
- reading, MelsecMCProtocol._send_request (melsec_mc/protocol.py:294-349): the reply is
  decoded as ASCII and stripped (:328), the text after '*' is taken (:337), its last 4
  characters dropped as a "CRC" (:339, never compared), the end code read with int(..., 16)
  (:343), and the rest converted with bytes.fromhex (:348); read_batch_registers then unpacks
  each word with struct '<H' (:511);
- writing, write_batch_registers puts each word as f'{value:04X}' (:621), and _send_request
  then writes every character of the request as two hex digits of its ASCII code (:305).

This adapter runs that client on a socket object in process (no device, no network): it hands
the client the reply it is given and keeps what the client sends.
- decode (word): read_single_register(DeviceType.D, 0) answered "@00FF03FF00" "0000" "0000"
  "*" + end code "0000" + the field + 4 characters of "CRC" (the client's own _calculate_crc,
  :351, of the text before it) + CR LF;
- encode (word): write_single_register(DeviceType.D, 0, value) answered with end code 0000:
  the request's characters that carry the word, the last 8 before its 4 "CRC" characters.
The end code (int(..., 16) at :343) is not wired: a non-zero code only raises RuntimeError, so
the value is never returned. The frame's "CRC" is an XOR of its own that no MC format has (the
serial sum check is a sum), and it is never checked on receipt: not wired either.
No check of the adapter's own is added. Known differences: melsec_mc_codec.known.yaml.
"""
import contextlib
import io
import os
import struct
import sys
from importlib.metadata import version

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_adapter  # noqa: E402
from melsec_mc.protocol import DeviceType, MCProtocolType, MelsecMCProtocol  # noqa: E402


class Socket:
    """A TCP socket in process: sendall keeps the request, recv gives the prepared reply."""

    def __init__(self):
        self.reply = b""
        self.sent = b""

    def sendall(self, data):
        self.sent = bytes(data)

    def recv(self, size):
        data, self.reply = self.reply[:size], self.reply[size:]
        return data

    def close(self):
        pass


sock = Socket()
client = MelsecMCProtocol("127.0.0.1", 1025, protocol_type=MCProtocolType.ASCII)
client.socket = sock
HEAD = "@00FF03FF0000000000*"


def reply(data):
    """A reply in the library's own ASCII format: head, end code 0000, data, its "CRC", CR LF."""
    body = HEAD + "0000" + data.decode("latin-1")
    return (body + client._calculate_crc(body)).encode("latin-1") + b"\r\n"


def quiet(call, *args):
    # The client prints every request and reply (print at :312-313, :329-330): kept off the channel.
    with contextlib.redirect_stdout(io.StringIO()):
        return call(*args)


def decode(text, digits):
    sock.reply = reply(bytes(text))
    return quiet(client.read_single_register, DeviceType.D, 0)


def encode(value, digits):
    sock.reply = reply(b"")
    quiet(client.write_single_register, DeviceType.D, 0, value)
    # "@" ... "*" + the request's characters, each as 2 hex digits + "CRC" (4): the word is
    # the request's last 4 characters, so the 8 digits before the "CRC".
    return sock.sent[-12:-4]


plc_adapter.serve_codec(
    decode=decode, encode=encode,
    name="melsec-mc", version=version("melsec-mc-protocol"),
    decode_digits=[4], encode_digits=[4], width=16,
    # ValueError: bytes.fromhex refuses a character or an odd count (:348);
    # UnicodeDecodeError (a ValueError): a byte above 7FH (response.decode('ascii'), :328);
    # struct.error: fewer than 2 bytes for the word's '<H' (:511), a field that ends early.
    errors={ValueError: "invalid-digit", struct.error: "invalid-digit"},
    protocol="mc-ascii", fields=["word"], cross_vendor=True)
