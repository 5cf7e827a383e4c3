#!/usr/bin/env python3
"""plc-conformance codec-level backend: modbuslink's Modbus ASCII client (SyncAsciiTransport).

modbuslink (PyPI, MIT) turns a Modbus ASCII reply into bytes in
SyncAsciiTransport.send_and_receive (modbuslink/transport/ascii_transport.py): it checks the
':' and CR LF, that the characters between them are an even number, converts them with
bytes.fromhex, and checks the LRC over the bytes (LRCModbus.validate). It writes a request as
`(request_frame + crc).hex().upper()` after ':'. The client's read_holding_registers then
unpacks the registers from the PDU.

This adapter runs the client on a serial port object in process (no device, no socket), which
hands the client the reply it is given and keeps what the client writes:
- decode (register): read_holding_registers(1, 0, 1) answered ":" "01" "03" "02", the field, an
  LRC, CR LF. The LRC is LRCModbus.calculate of the frame's bytes when bytes.fromhex reads the
  frame with the field, else 00H (the client refuses such a frame before the LRC);
- encode (register): write_single_register(1, 0, value): the 4 characters of the value in the
  request it writes (the reply is the request echoed, as a slave answers function 06);
- check (lrc): LRCModbus.calculate over the span's bytes, written `.hex().upper()` as the client
  writes its own LRC (ascii_transport.py:226-227);
- verify (lrc): send_and_receive answered ":" + the frame + CR LF: accepted when it returns.
No check of the adapter's own is added. Known differences: modbuslink_client_codec.known.yaml.
"""
import os
import sys
from importlib.metadata import version

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_adapter  # noqa: E402
from modbuslink import LRCModbus, SyncAsciiTransport, SyncModbusClient  # noqa: E402
from modbuslink.common.exceptions import InvalidReplyError, ModbusLinkError  # noqa: E402


class Port:
    """A serial port in process: read_until gives the reply, write keeps the request."""

    is_open = True
    in_waiting = 0

    def __init__(self):
        self.reply = b""
        self.written = b""
        self.echo = False

    def write(self, data):
        self.written = bytes(data)
        if self.echo:
            self.reply = self.written

    def flush(self):
        pass

    def reset_input_buffer(self):
        pass

    def read_until(self, terminator=b"\n"):
        return self.reply

    def close(self):
        self.is_open = False


port = Port()
transport = SyncAsciiTransport("in-process")
transport._serial = port
client = SyncModbusClient(transport)


def lrc_chars(text):
    try:
        data = bytes.fromhex(text.decode("latin-1"))
    except ValueError:
        return b"00"
    return LRCModbus.calculate(data).hex().upper().encode("ascii")


def decode(text, digits):
    frame = b"010302" + bytes(text)
    port.echo, port.reply = False, b":" + frame + lrc_chars(frame) + b"\r\n"
    return client.read_holding_registers(1, 0, 1)[0]


def encode(value, digits):
    port.echo = True
    client.write_single_register(1, 0, value)
    # ":" "01" "06" "0000" value (4) LRC (2) CR LF
    return port.written[9:13]


def check(span):
    return LRCModbus.calculate(bytes.fromhex(span.decode("latin-1"))).hex().upper()


def verify(frame):
    port.echo, port.reply = False, b":" + bytes(frame) + b"\r\n"
    transport.send_and_receive(1, bytes([0x03, 0, 0, 0, 1]))
    return True


plc_adapter.serve_codec(
    decode=decode, encode=encode, check=check, verify=verify,
    name="modbuslink-client", version=version("modbuslink"),
    decode_digits=[4], encode_digits=[4], width=16,
    # InvalidReplyError: odd length, not hex ("Invalid hexadecimal data"), a wrong LRC, a wrong
    # byte count; UnicodeDecodeError: a byte above 7FH (hex_ascii[1:-2].decode('ascii')).
    errors={InvalidReplyError: "invalid-digit", UnicodeDecodeError: "invalid-digit",
            ModbusLinkError: "error"},
    protocol="modbus-ascii", fields=["register", "lrc"], cross_vendor=True)
