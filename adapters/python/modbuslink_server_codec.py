#!/usr/bin/env python3
"""plc-conformance codec-level backend: modbuslink's Modbus ASCII server (AsyncAsciiModbusServer).

modbuslink (PyPI, MIT) reads a request in AsyncAsciiModbusServer._process_frame
(modbuslink/server/ascii_server.py): it drops the ':', refuses an odd count of characters,
converts them with binascii.unhexlify, compares the LRC with LRCModbus.calculate of the bytes,
and hands the PDU to process_request; a frame it refuses gets no response (it logs a warning).
It writes a response as `b':' + binascii.hexlify(response_frame).upper() + b'\\r\\n'`.

This adapter gives _process_frame the frame itself (the serial port's reading loop strips the
line and finds the ':' before it), with a writer in process that keeps the response, and the
server's own data store:
- decode (register): ":" "01" "06" "0000", the field, an LRC (LRCModbus.calculate of the
  frame's bytes when binascii.unhexlify reads the frame with the field, else 00H, which the
  server never reaches): the value the server writes to holding register 0; no response is the
  server's refusal (mbsl: a slave that detects an error does not answer), answered as
  invalid-digit, and so is its exception response 86H 03H (data too short);
- encode (register): holding register 0 set in the data store, then ":010300000001FB": the 4
  characters of the register in the server's response;
- check (lrc): LRCModbus.calculate over the span's bytes, written as the server writes an LRC;
- verify (lrc): the frame given to _process_frame: accepted when the server answers at all.
No check of the adapter's own is added. Known differences: modbuslink_server_codec.known.yaml.
"""
import asyncio
import binascii
import logging
import os
import sys
from importlib.metadata import version

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_adapter  # noqa: E402
from modbuslink import AsyncAsciiModbusServer, LRCModbus, ModbusDataStore  # noqa: E402

logging.disable(logging.CRITICAL)  # its warnings go to stderr; nothing may go to stdout


class Writer:
    """The serial port's writer, in process: keeps what the server answers."""

    def __init__(self):
        self.written = b""

    def write(self, data):
        self.written += bytes(data)

    async def drain(self):
        pass


store = ModbusDataStore(holding_registers_size=16)
server = AsyncAsciiModbusServer("in-process", data_store=store, slave_id=1)
loop = asyncio.new_event_loop()
SENTINEL = 0xDEAD


def lrc_chars(frame):
    try:
        data = binascii.unhexlify(frame)
    except (binascii.Error, ValueError):
        return b"00"
    return binascii.hexlify(LRCModbus.calculate(data)).upper()


def serve(frame):
    """The server's answer to the frame: its response, or b"" for none."""
    server._writer = Writer()
    loop.run_until_complete(server._process_frame(b":" + frame))
    return server._writer.written


def decode(text, digits):
    store.write_holding_registers(0, [SENTINEL])
    frame = b"01060000" + bytes(text)
    response = serve(frame + lrc_chars(frame))
    if not response:
        raise plc_adapter.CodecError("invalid-digit", "no response: the server refused the frame")
    if response[3:5] == b"86":
        # An exception response (function 06 | 80H): 03, illegal data value, is the server's
        # answer to a request whose data ends before the value does (base_server.py,
        # _handle_write_single_register); a text that ends inside the field is invalid-digit.
        raise plc_adapter.CodecError("invalid-digit", "exception response %r" % response)
    return store.read_holding_registers(0, 1)[0]


def encode(value, digits):
    store.write_holding_registers(0, [value])
    response = serve(b"010300000001" + lrc_chars(b"010300000001"))
    # ":" "01" "03" "02" register (4) LRC (2) CR LF
    return response[7:11]


def check(span):
    return binascii.hexlify(LRCModbus.calculate(binascii.unhexlify(span))).upper()


def verify(frame):
    return bool(serve(bytes(frame)))


plc_adapter.serve_codec(
    decode=decode, encode=encode, check=check, verify=verify,
    name="modbuslink-server", version=version("modbuslink"),
    decode_digits=[4], encode_digits=[4], width=16,
    protocol="modbus-ascii", fields=["register", "lrc"], cross_vendor=True)
