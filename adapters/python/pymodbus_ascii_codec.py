#!/usr/bin/env python3
"""plc-conformance codec-level backend: pymodbus's Modbus ASCII framer (FramerAscii).

pymodbus (PyPI, BSD-3-Clause) reads and writes Modbus ASCII frames in
pymodbus.framer.ascii.FramerAscii; its transaction manager hands every received buffer to
FramerBase.processIncomingFrame (pymodbus/framer/base.py:66, called at
transaction/transaction.py:87 and :187), which calls FramerAscii.decode (framer/ascii.py:36):
the device id is read with int(buffer[1:3], 16) (:54), the LRC with int(buffer[end-2:end], 16)
(:55), the characters between ':' and the LRC with binascii.a2b_hex (:56), and a frame whose
LRC (check_LRC, :84) does not match is skipped (:58-60). The PDU is then decoded by DecodePDU
(pdu/decoders.py:101); a read-holding-registers response unpacks each register with struct
'>H' (pdu/register_message.py:60-65). A frame is written by FramerBase.buildFrame (base.py:57)
through FramerAscii.encode (ascii.py:63): the device id as f"{device_id:02x}" (:69), the PDU
with b2a_hex (:70), the LRC (compute_LRC, :77) as f"{checksum:02x}" (:71), all upper-cased
(:73).

This adapter drives those functions on a client-side framer (DecodePDU(is_server=False)), no
transport:
- decode (register): processIncomingFrame(":" "01" "03" "02" + the field + LRC + CR LF): the
  response's registers[0]. The LRC is compute_LRC of the frame's bytes when a2b_hex reads the
  frame with the field, else "00" (a2b_hex then refuses the frame before the LRC is compared);
- decode (byte): the device id: processIncomingFrame(":" + the field + "03" "02" "0000" + LRC +
  CR LF): the response's dev_id (int(buffer[1:3], 16), :54), the LRC made as above;
- encode (register): buildFrame(WriteSingleRegisterRequest(address=0, registers=[value],
  dev_id=1)): the 4 characters of the value; encode (byte): buildFrame of a read request to
  device id value: the 2 characters of the device id;
- check (lrc): FramerAscii.encode of the span's bytes (device id and PDU): the LRC it writes;
- verify (lrc): FramerAscii.decode(":" + the frame + CR LF): accepted when it returns the
  message, bad-check when it skips the frame (check_LRC false, :58-60).
processIncomingFrame returns no PDU, with no exception, for a frame it is still waiting to
complete (shorter than MIN_SIZE, :41-43): that answers invalid-digit, as a text that ends
inside its field (the frame never completes). No check of the adapter's own is added.
Known differences: pymodbus_ascii_codec.known.yaml.
"""
import os
import sys
from binascii import a2b_hex
from importlib.metadata import version

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_adapter  # noqa: E402
from pymodbus.exceptions import ModbusIOException  # noqa: E402
from pymodbus.framer.ascii import FramerAscii  # noqa: E402
from pymodbus.pdu import DecodePDU  # noqa: E402
from pymodbus.pdu.register_message import (  # noqa: E402
    ReadHoldingRegistersRequest,
    WriteSingleRegisterRequest,
)

framer = FramerAscii(DecodePDU(False))


def lrc_chars(frame):
    """The LRC a slave would send after these characters (the framer's own compute_LRC), or
    "00" when a2b_hex cannot read them (the framer refuses them before comparing any LRC)."""
    try:
        data = a2b_hex(frame)
    except ValueError:
        return b"00"
    return b"%02X" % FramerAscii.compute_LRC(data)


def received(frame):
    used, pdu = framer.processIncomingFrame(b":" + frame + lrc_chars(frame) + b"\r\n")
    if pdu is None:
        # Still waiting for the frame to complete: nothing was decoded.
        raise plc_adapter.CodecError("invalid-digit")
    return pdu


def decode(text, digits):
    if digits == 2:
        return received(bytes(text) + b"03020000").dev_id
    return received(b"010302" + bytes(text)).registers[0]


def encode(value, digits):
    if digits == 2:
        return framer.buildFrame(ReadHoldingRegistersRequest(address=0, count=1, dev_id=value))[1:3]
    frame = framer.buildFrame(WriteSingleRegisterRequest(address=0, registers=[value], dev_id=1))
    # ":" "01" "06" "0000" value (4) LRC (2) CR LF
    return frame[9:13]


def check(span):
    data = a2b_hex(span)
    # ":" device id (2), PDU, LRC (2), CR LF
    return framer.encode(data[1:], data[0], 0)[-4:-2]


def verify(frame):
    used, dev_id, tid, msg = framer.decode(b":" + bytes(frame) + b"\r\n")
    return bool(msg)


plc_adapter.serve_codec(
    decode=decode, encode=encode, check=check, verify=verify,
    name="pymodbus-ascii", version=version("pymodbus"),
    decode_digits=[2, 4], encode_digits=[2, 4], field={"widths": {2: 8, 4: 16}},
    # ValueError: int(..., 16) of the device id or LRC (:54, :55), and binascii.Error (a
    # ValueError) from a2b_hex (:56): a character that is no hex digit, an odd count, a byte
    # above 7FH. ModbusIOException: "Unable to decode request" (base.py:98), DecodePDU found no
    # PDU in the bytes (a byte count larger than the data, an unknown function code).
    errors={ValueError: "invalid-digit", ModbusIOException: "invalid-digit"},
    protocol="modbus-ascii", fields=["byte", "register", "lrc"], cross_vendor=True)
