#!/usr/bin/env python3
"""plc-conformance codec-level backend: libmodbuspy's Modbus ASCII client (ModbusAscPort).

libmodbuspy (PyPI, MIT) frames Modbus ASCII in libmodbuspy/ascport.py: ModbusAscPort.readBuffer
(:54) checks the length, ':' and CR LF, converts the characters between them with
mbglobal.asciiToBytes (ascport.py:70; mbglobal.py:377, `bytes.fromhex(ascii_buff.decode('ascii'))`
at :386-387; any exception becomes AscCharError) and compares the LRC (ascport.py:77,
mbglobal.lrc at :270). writeBuffer (ascport.py:31) appends the LRC and writes the bytes with
bytesToAscii (`bytes_buff.hex().upper()`, mbglobal.py:375). ModbusClientPort._readHoldingRegisters
(clientport.py:481) checks the byte count against the data (:516) and stores each register
as native bytes, low byte first (:523-525), which readHoldingRegistersF unpacks with its
default format, MB_FMT_UINT16_LE ("<H", mbglobal.py:149); _writeSingleRegister puts the value
high byte first (:639-640).

This adapter runs a blocking ModbusAscPort under a ModbusClientPort on a serial object in
process (no device): it hands the port the reply it is given and keeps what the port writes.
- decode (register): readHoldingRegistersF(1, 0, 1) answered ":" "01" "03" "02" + the field +
  LRC + CR LF; the LRC is mbglobal.lrc of the frame's bytes when bytes.fromhex reads the frame
  with the field, else "00" (asciiToBytes then refuses the frame before the LRC);
- encode (register): writeSingleRegister(1, 0, value), the request echoed as a slave answers
  function 06: the 4 characters of the value in the request written;
- check (lrc): ModbusAscPort.writeBuffer of the span's bytes (unit, function, data): the 2
  characters of the LRC it writes;
- verify (lrc): ModbusAscPort.readBuffer of ":" + the frame + CR LF: accepted when it returns,
  bad-check when it raises LrcError.
No check of the adapter's own is added. Known differences: libmodbuspy_ascii_codec.known.yaml.
"""
import os
import sys
from importlib.metadata import version

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_adapter  # noqa: E402
from libmodbuspy import exceptions  # noqa: E402
from libmodbuspy.ascport import ModbusAscPort  # noqa: E402
from libmodbuspy.clientport import ModbusClientPort  # noqa: E402
from libmodbuspy.mbglobal import lrc  # noqa: E402


class Serial:
    """A serial port in process (pyserial's interface as ModbusSerialPort uses it): read gives
    the prepared reply, write keeps the request (and, echoing, makes it the reply)."""

    is_open = True

    def __init__(self):
        self.reply = b""
        self.written = b""
        self.echo = False

    def open(self):
        self.is_open = True

    def close(self):
        pass

    def reset_input_buffer(self):
        pass

    def write(self, data):
        self.written = bytes(data)
        if self.echo:
            self.reply = self.written

    def read(self, size):
        return self.reply[:size]


serial = Serial()
port = ModbusAscPort(True)
port._serial = serial
client = ModbusClientPort(port)


def lrc_chars(frame):
    try:
        data = bytes.fromhex(frame.decode("latin-1"))
    except ValueError:
        return b"00"
    return b"%02X" % lrc(data)


def decode(text, digits):
    frame = b"010302" + bytes(text)
    serial.echo, serial.reply = False, b":" + frame + lrc_chars(frame) + b"\r\n"
    return client.readHoldingRegistersF(1, 0, 1)[0]


def encode(value, digits):
    serial.echo = True
    client.writeSingleRegister(1, 0, value)
    # ":" "01" "06" "0000" value (4) LRC (2) CR LF
    return serial.written[9:13]


def check(span):
    data = bytes.fromhex(span.decode("latin-1"))
    port.writeBuffer(data[0], data[1], data[2:])
    # ":" unit, function, data, LRC (2), CR LF
    return bytes(port._buff[-4:-2])


def verify(frame):
    port._buff = bytearray(b":" + bytes(frame) + b"\r\n")
    port.readBuffer()
    return True


plc_adapter.serve_codec(
    decode=decode, encode=encode, check=check, verify=verify,
    name="libmodbuspy-ascii", version=version("libmodbuspy"),
    decode_digits=[4], encode_digits=[4], width=16,
    # AscCharError: asciiToBytes refused the characters (a non-hex character, an odd count, a
    # byte above 7FH); NotCorrectResponseError: the byte count does not match the data
    # ("Incorrect received data size", clientport.py:516-517); LrcError: the LRC does not match.
    errors={exceptions.AscCharError: "invalid-digit",
            exceptions.NotCorrectResponseError: "invalid-digit",
            exceptions.LrcError: "bad-check"},
    protocol="modbus-ascii", fields=["register", "lrc"], cross_vendor=True)
