"""Turn a Python function into a plc-conformance external backend.

The harness starts the adapter as a child process and speaks the JSON-lines protocol of
docs/protocol.md (version 1) on its stdin and stdout. This module does the protocol; the adapter
writes one function that executes one case:

    import plc_adapter

    def run(case):
        s, d = case.device("s"), case.device("d")
        case.write(d, case.read(s) + 1)      # or: case.fail(code=0x3401)

    plc_adapter.serve(run, name="my-emulator", version="1.0", profile="mitsubishi-iqr",
                      instructions=["INC"], flags={"SM705": [False]})

Raise plc_adapter.Unsupported("why") for a case the function cannot execute; any other
exception ends the process with its traceback on stderr, which the harness shows with the case
(as "crashed") before starting the adapter again for the next one.

Standard library only, Python 3.8 or later. Nothing may be printed to stdout except through
this module: stdout is the protocol channel (use stderr for logs).
"""

import json
import sys
from collections import namedtuple

PROTOCOL_VERSION = 1

__all__ = ["Case", "Device", "Unsupported", "fill_word", "serve", "PROTOCOL_VERSION"]


class Unsupported(Exception):
    """The case cannot be executed by this backend (answered as "unsupported")."""


class Device(namedtuple("Device", "code index")):
    """A word device such as D100: its letter code and number."""

    __slots__ = ()

    @classmethod
    def parse(cls, text):
        split = 0
        while split < len(text) and text[split].isalpha():
            split += 1
        code, number = text[:split], text[split:]
        if not code or not code.isupper() or not number.isdigit():
            raise ValueError("not a device name: %r" % (text,))
        return cls(code, int(number))

    def offset(self, n):
        """The device n words after this one, like (s)+n in the manuals."""
        return Device(self.code, self.index + n)

    def __str__(self):
        return "%s%d" % (self.code, self.index)


_DIGITS = b"0123456789ABCDEF"


def fill_word(fill, index):
    """The word a device holds when the case does not set it (docs/protocol.md, "Fill")."""
    i = index % 16
    if fill == "A":
        return 0xA5A5 ^ ((i % 6) * 0x0101)
    return _DIGITS[i] | (_DIGITS[15 - i] << 8)


class Case:
    """One case to execute: its setting, the memory before, and what it did."""

    def __init__(self, message):
        self.id = message["id"]
        self.case = message["case"]
        self.instruction = message["instruction"]
        self.profile = message["profile"]
        self.variant = message["variant"]
        self.flags = message.get("flags", {})
        self.ignored_flags = message.get("ignored_flags", {})
        self.operands = message.get("operands", {})
        self.fill = message.get("fill", "A")
        memory = {}
        for block in message.get("memory", []):
            start = Device.parse(block["start"])
            for i, word in enumerate(block["words"]):
                memory[(start.code, start.index + i)] = word
        self.memory = memory
        self.writes = {}
        self.error = None

    def flag(self, name):
        """The flag as this variant's CPU sees it: a flag the variant does not implement holds
        the value it behaves as, whatever the case set."""
        if name in self.ignored_flags:
            return self.ignored_flags[name]
        return bool(self.flags.get(name, False))

    def operand(self, name):
        """A device operand as a Device, a constant as an int."""
        if name not in self.operands:
            raise Unsupported("%s needs operand %r" % (self.instruction, name))
        value = self.operands[name]
        return Device.parse(value) if isinstance(value, str) else value

    def device(self, name):
        """An operand that must be a device."""
        value = self.operand(name)
        if not isinstance(value, Device):
            raise Unsupported("operand %r as a constant (K%d) is not implemented" % (name, value))
        return value

    def read(self, device):
        """A word as the instruction reads it: its latest write, else memory before."""
        key = (device[0], device[1])
        if key in self.writes:
            return self.writes[key]
        if key in self.memory:
            return self.memory[key]
        return fill_word(self.fill, device[1])

    def exists(self, device):
        """Whether the word exists on the case's variant, for words within 64 of a device
        operand: the request's window covers that span and is cut to the words that exist, so
        a word there that is not in the window lies past the end of the device range."""
        return (device[0], device[1]) in self.memory

    def write(self, device, value):
        if not 0 <= value <= 0xFFFF:
            raise ValueError("%s: %r is not a 16-bit word" % (device, value))
        self.writes[(device[0], device[1])] = value

    def fail(self, code=None, flag=None):
        """Signal an operation error: the vendor's code, or the flag for flag-only vendors."""
        self.error = {"code": code} if flag is None else {"flag": str(flag)}

    def answer(self):
        return {
            "type": "result",
            "id": self.id,
            "writes": {"%s%d" % key: value for key, value in self.writes.items()},
            "error": self.error,
        }


def serve(run, name, version, profile, instructions, variants=None, flags=None,
          stdin=None, stdout=None):
    """Answers the harness until it says shutdown or closes stdin.

    run: function(Case) executing one case (see the module documentation).
    profile: the vendor profile id implemented, e.g. "mitsubishi-iqr".
    instructions: the instructions implemented; variants: the profile variants (None: all).
    flags: {flag: [settings implemented]} for flags implemented in one setting only.
    """
    stdin = stdin or sys.stdin
    stdout = stdout or sys.stdout
    capabilities = {"profile": profile, "instructions": list(instructions)}
    if variants is not None:
        capabilities["variants"] = list(variants)
    if flags:
        capabilities["flags"] = {k: [bool(v) for v in vs] for k, vs in flags.items()}
    dumps = json.JSONEncoder(separators=(",", ":")).encode
    for line in stdin:
        if not line.strip():
            continue
        message = json.loads(line)
        kind = message.get("type")
        if kind == "hello":
            answer = {"type": "hello", "protocol": PROTOCOL_VERSION,
                      "backend": {"name": name, "version": version},
                      "capabilities": capabilities}
            stdout.write(dumps(answer) + "\n")
        elif kind == "run":
            try:
                for request in message["cases"]:
                    case = Case(request)
                    try:
                        run(case)
                        answer = case.answer()
                    except Unsupported as why:
                        answer = {"type": "unsupported", "id": case.id, "reason": str(why)}
                    # Each answer goes out at once: the harness's time limit for a case runs
                    # from the previous answer, and a buffered answer looks like a hang.
                    stdout.write(dumps(answer) + "\n")
                    stdout.flush()
            finally:
                # The answers before a failing case reach the harness, so that it blames the
                # right case.
                stdout.flush()
        elif kind == "shutdown":
            stdout.flush()
            return
        else:
            raise ValueError("unknown message type %r" % (kind,))
        stdout.flush()
