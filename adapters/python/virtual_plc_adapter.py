#!/usr/bin/env python3
"""plc-conformance backend: virtual-plc's MC protocol 3E ASCII server as an iQ-R CPU.

virtual-plc (PyPI, MIT) is a Mitsubishi MC protocol PLC simulator: a TCP server that holds
device memory and answers 3E/4E frames in binary and in ASCII code. In ASCII code every word
of a request or reply is 4 hex characters and every double word 8, most significant digit
first, and the server converts them to and from the values it stores. That is the conversion
HABIN/DHABIN (text -> binary) and BINHA/DBINHA (binary -> text) perform with SM705 off; this
adapter makes the server do it and checks it with the iQ-R corpus.

At start the adapter runs virtual_plc.Server (profile iQ-R, D0-D18431 as in the iQ-R profile)
on 127.0.0.1 with a port the system picks, connects one client socket, and stops the server
at shutdown. Per case:

- the request's window is loaded with binary batch writes (1401), so the server holds the
  case's memory;
- HABIN(P): (s), (s)+1 are read back in binary (0401) and their 4 characters, low byte first,
  are sent unchanged as the word data of an ASCII batch write (1401) of (d): the server
  converts them. DHABIN(P): 8 characters as the double word of an ASCII random write (1402);
- BINHA(P): an ASCII batch read (0401) of (s) returns the server's 4 characters, which are
  stored two per word from (d) (binary 1401), then 0000H unless SM701 is on. DBINHA(P): an
  ASCII random read (0403) of (s) as a double word. A constant (s) is first written to R0;
- the window is read back in binary (0401); the words that changed are the answer.

Server end codes: C05CH (request data error: a field that is not hex) answers 3401H; C056H
(address out of range) answers 2820H, so device range checks are the server's. Any other end
code ends the adapter with a message. Declared: SM705 off only (HABIN's 00H-terminated text
and BINHA's dropped leading zeros are nothing the protocol does). The server runs as shipped,
with its default ASCII double-word order ("swapped").
"""

import os
import socket
import sys
from importlib.metadata import version as _version

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import plc_adapter  # noqa: E402

try:
    from virtual_plc import Memory, Server
except ImportError as e:  # pragma: no cover - reported to the harness as a failed start
    sys.stderr.write(
        "virtual-plc is not installed (%s): python3 -m venv .venv-adapters && "
        ".venv-adapters/bin/pip install -r adapters/python/requirements.txt\n" % e
    )
    sys.exit(1)

ERR_INVALID_DATA = 0x3401
ERR_DEVICE_RANGE = 0x2820
END_REQUEST_DATA = 0xC05C
END_ADDRESS_RANGE = 0xC056

D_LAST = 18431  # vendors/mitsubishi-iqr.yaml: D0-D18431
SCRATCH = "R0"  # where a constant (s) is put for the server to convert
MAX_POINTS = 960  # words per batch read or write (the MC protocol's limit for word units)

# iQ-R device specification (subcommand 0002: 4-byte number and 2-byte code in binary; a
# 4-character code and 8 decimal digits in ASCII).
CODES = {"D": 0xA8, "R": 0xAF}
WORD_SUBCOMMAND = 0x0002
BATCH_READ, BATCH_WRITE, RANDOM_READ, RANDOM_WRITE = 0x0401, 0x1401, 0x0403, 0x1402

HABIN = {"HABIN": 1, "HABINP": 1, "DHABIN": 2, "DHABINP": 2}
BINHA = {"BINHA": 1, "BINHAP": 1, "DBINHA": 2, "DBINHAP": 2}


class EndCode(Exception):
    def __init__(self, code):
        Exception.__init__(self, "end code %04XH" % code)
        self.code = code


class Client:
    """One TCP connection speaking MC 3E frames, binary or ASCII code."""

    def __init__(self, address):
        self.sock = socket.create_connection(address, timeout=5)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def close(self):
        self.sock.close()

    def _recv(self, n):
        out = b""
        while len(out) < n:
            chunk = self.sock.recv(n - len(out))
            if not chunk:
                raise ConnectionError("virtual-plc closed the connection")
            out += chunk
        return out

    def request(self, command, data, ascii_code):
        """Sends one request; returns the reply's data, or raises EndCode."""
        if ascii_code:
            body = b"0010" + b"%04X%04X" % (command, WORD_SUBCOMMAND) + data
            self.sock.sendall(b"500000FF03FF00" + b"%04X" % len(body) + body)
            head = self._recv(18)  # D000, route (10), length (4)
            reply = self._recv(int(head[14:18], 16))
            end, data = int(reply[:4], 16), reply[4:]
        else:
            body = (0x10).to_bytes(2, "little") + command.to_bytes(2, "little")
            body += WORD_SUBCOMMAND.to_bytes(2, "little") + data
            self.sock.sendall(b"\x50\x00\x00\xff\xff\x03\x00" + len(body).to_bytes(2, "little") + body)
            head = self._recv(9)
            reply = self._recv(int.from_bytes(head[7:9], "little"))
            end, data = int.from_bytes(reply[:2], "little"), reply[2:]
        if end:
            raise EndCode(end)
        return data

    # Binary code: no text conversion involved.
    def read_words(self, device, count):
        data = self.request(BATCH_READ, _spec(device) + count.to_bytes(2, "little"), False)
        return [int.from_bytes(data[i:i + 2], "little") for i in range(0, 2 * count, 2)]

    def write_words(self, device, words):
        data = _spec(device) + len(words).to_bytes(2, "little")
        self.request(BATCH_WRITE, data + b"".join(w.to_bytes(2, "little") for w in words), False)

    # ASCII code: the server converts the text.
    def write_text(self, device, text):
        """Writes a word (4 characters) or a double word (8) given as text."""
        if len(text) == 4:
            self.request(BATCH_WRITE, _ascii_spec(device) + b"0001" + text, True)
        else:
            self.request(RANDOM_WRITE, b"0001" + _ascii_spec(device) + text, True)

    def read_text(self, device, words):
        """Reads a word (as 4 characters) or a double word (as 8)."""
        if words == 1:
            return self.request(BATCH_READ, _ascii_spec(device) + b"0001", True)
        return self.request(RANDOM_READ, b"0001" + _ascii_spec(device), True)


def _spec(device):
    return device.index.to_bytes(4, "little") + CODES[device.code].to_bytes(2, "little")


def _ascii_spec(device):
    return device.code.encode().ljust(4, b"*") + b"%08d" % device.index


def text_at(case, client, head, count):
    """count characters stored two per word from head, low byte first, as the server holds them."""
    words = client.read_words(head, (count + 1) // 2)
    return bytes((words[k // 2] >> (8 * (k % 2))) & 0xFF for k in range(count))


def habin(case, client, words):
    source, dest = case.device("s"), case.device("d")
    text = text_at(case, client, source, 4 * words)
    client.write_text(dest, text)


def binha(case, client, words):
    source, dest = case.operand("s"), case.device("d")
    if isinstance(source, int):
        scratch = plc_adapter.Device.parse(SCRATCH)
        value = source & ((1 << (16 * words)) - 1)
        client.write_words(scratch, [(value >> (16 * w)) & 0xFFFF for w in range(words)])
        source = scratch
    text = client.read_text(source, words)
    if not case.flag("SM701"):
        text += b"\0\0"
    client.write_words(dest, [text[i] | (text[i + 1] << 8) for i in range(0, len(text), 2)])


def run_case(case, client):
    if case.flag("SM705"):
        raise plc_adapter.Unsupported("SM705 on is not an MC protocol conversion")
    if case.instruction in HABIN:
        step = lambda: habin(case, client, HABIN[case.instruction])  # noqa: E731
    elif case.instruction in BINHA:
        step = lambda: binha(case, client, BINHA[case.instruction])  # noqa: E731
    else:
        raise plc_adapter.Unsupported("%s is not implemented" % case.instruction)
    blocks = {}
    for (code, index), word in sorted(case.memory.items()):
        blocks.setdefault(code, []).append((index, word))
    ranges = []  # runs of consecutive words, at most MAX_POINTS each
    for code, cells in blocks.items():
        prev = None
        for index, _ in cells:
            if prev is None or index != prev + 1 or ranges[-1][2] == MAX_POINTS:
                ranges.append([code, index, 0])
            ranges[-1][2] += 1
            prev = index
    for code, start, count in ranges:
        head = plc_adapter.Device(code, start)
        client.write_words(head, [case.memory[(code, start + i)] for i in range(count)])
    try:
        step()
    except EndCode as e:
        if e.code == END_REQUEST_DATA:
            case.fail(code=ERR_INVALID_DATA)
        elif e.code == END_ADDRESS_RANGE:
            case.fail(code=ERR_DEVICE_RANGE)
        else:
            raise
    for code, start, count in ranges:
        head = plc_adapter.Device(code, start)
        for i, word in enumerate(client.read_words(head, count)):
            if word != case.memory[(code, start + i)]:
                case.write(head.offset(i), word)


def main():
    server = Server(host="127.0.0.1", port=0, profile="iQ-R",
                    memory=Memory("iQ-R", limits={"D": (0, D_LAST)}))
    server.start()
    client = Client(server.address)
    try:
        plc_adapter.serve(
            lambda case: run_case(case, client),
            name="virtual-plc",
            version=_version("virtual-plc"),
            profile="mitsubishi-iqr",
            instructions=sorted(HABIN) + sorted(BINHA),
            flags={"SM705": [False]},
        )
    finally:
        client.close()
        server.stop()


if __name__ == "__main__":
    main()
