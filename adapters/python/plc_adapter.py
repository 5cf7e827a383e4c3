"""Turn Python functions into a plc-conformance external backend.

The harness starts the adapter as a child process and speaks the JSON-lines protocol of
docs/protocol.md on its stdin and stdout. This module does the protocol; the adapter supplies
the conversion, at one of two levels.

Codec level (protocol version 2): two functions, text to value and value to text. The harness
runs the cross-vendor corpus against them directly, with no memory, devices or fill:

    import plc_adapter
    import mylib

    plc_adapter.serve_codec(
        decode=lambda text, digits: mylib.parse_hex(text),       # bytes -> int
        encode=lambda value, digits: mylib.format_hex(value, digits),  # int -> bytes or str
        name="mylib", version="1.2.0",
        decode_digits=[4], encode_digits=[4], width=16,
        errors={mylib.BadDigit: "invalid-digit"})

Instruction level (protocol version 1 or 2): one function that executes one case of a vendor's
instruction on a CPU's memory:

    def run(case):
        s, d = case.device("s"), case.device("d")
        case.write(d, case.read(s) + 1)      # or: case.fail(code=0x3401)

    plc_adapter.serve(run, name="my-emulator", version="1.0", profile="mitsubishi-iqr",
                      instructions=["INC"], flags={"SM705": [False]})

Raise plc_adapter.Unsupported("why") for a case the function cannot execute, and
plc_adapter.CodecError("invalid-count") for an error a codec signals itself; any other
exception (one that `errors` does not map) ends the process with its traceback on stderr, which
the harness shows with the case (as "crashed") before starting the adapter again for the next
one.

Standard library only, Python 3.8 or later. stdout is the protocol channel: while serving, the
module points sys.stdout at stderr, so a stray print() in a library goes to the log rather than
into the protocol.
"""

import json
import sys
from collections import namedtuple

__version__ = "0.2.0"

# The protocol versions this module speaks: 1 (instruction level), 2 (adds codec level), 3
# (byte-addressed families) and 4 (families whose unit is a 32-bit word).
PROTOCOL_VERSIONS = (1, 2, 3, 4)
PROTOCOL_VERSION = 2

# The error classes a codec answers with (docs/protocol.md, "Version 2").
ERROR_CLASSES = ("invalid-digit", "invalid-count", "device-range", "error")

# The two codec operations.
HEX_TO_VALUE = "hex-to-value"
VALUE_TO_HEX = "value-to-hex"

__all__ = [
    "Case",
    "CodecError",
    "Device",
    "ERROR_CLASSES",
    "PROTOCOL_VERSION",
    "PROTOCOL_VERSIONS",
    "Unsupported",
    "fill_word",
    "serve",
    "serve_codec",
]


class Unsupported(Exception):
    """The case cannot be executed by this backend (answered as "unsupported")."""


class CodecError(Exception):
    """A codec's refusal of its input, answered as an error of the given class.

    raise CodecError("invalid-digit"): the text holds a character that is not a hex digit;
    "invalid-count": the digit count is not one the conversion takes; "device-range": the data
    lies past the end of a device range; "error": an error whose kind the codec does not tell.
    """

    def __init__(self, error_class, detail=None):
        if error_class not in ERROR_CLASSES:
            raise ValueError("error class %r is not one of %s" % (error_class, ", ".join(ERROR_CLASSES)))
        Exception.__init__(self, error_class if detail is None else "%s: %s" % (error_class, detail))
        self.error_class = error_class


class Device(namedtuple("Device", "code index hexadecimal", defaults=(False,))):
    """A word device such as D100: its letter code and number (and whether the number is
    written in hexadecimal, as MELSEC numbers W and SW: W1A is index 26)."""

    __slots__ = ()

    @classmethod
    def parse(cls, text, hexadecimal=()):
        """A code and the number after it: D100, MB20, DB1.DBB10, U1\\G10; for a code in
        `hexadecimal` (the case's `hexadecimal` list), a hexadecimal number: W1A."""
        for split in range(len(text) - 1, 0, -1):
            code, digits = text[:split], text[split:]
            if code in hexadecimal and all(c in "0123456789ABCDEF" for c in digits):
                return cls(code, int(digits, 16), True)
        split = len(text)
        while split > 0 and text[split - 1].isdigit():
            split -= 1
        code, number = text[:split], text[split:]
        if not code or not code[0].isalpha() or not code[-1].isalpha() \
                or code != code.upper() or not number.isdigit():
            raise ValueError("not a device name: %r" % (text,))
        return cls(code, int(number))

    def points(self):
        """Device numbers one word spans: 1, or 16 for a digit designation such as K4M
        (K4M0 is the 16 points M0-M15, and the next word is K4M16)."""
        c = self.code
        if len(c) > 2 and c[0] == "K" and c[1] in "12345678" and c[2:].isalpha() \
                and c[2:].isupper():
            return 4 * int(c[1])
        return 1

    def offset(self, n):
        """The device n words after this one, like (s)+n in the manuals (W9, WA, ... for a
        hexadecimal-numbered code)."""
        return Device(self.code, self.index + n * self.points(), self.hexadecimal)

    def __str__(self):
        return ("%s%X" if self.hexadecimal else "%s%d") % (self.code, self.index)


_DIGITS = b"0123456789ABCDEF"


def fill_word(fill, index, unit="word"):
    """The unit a device holds when the case does not set it (docs/protocol.md, "Fill").

    index: the device number, or a Device (whose word number counts: K4M32 is word 2).
    unit: "word", "byte" (the word's low byte) or "dword" (the word of the position low, that of
    the position eight on high)."""
    if isinstance(index, Device):
        index = index.index // index.points()
    i = index % 16

    def word(i):
        if fill == "A":
            return 0xA5A5 ^ ((i % 6) * 0x0101)
        return _DIGITS[i] | (_DIGITS[15 - i] << 8)

    if unit == "byte":
        return word(i) & 0xFF
    if unit == "dword":
        return word(i) | word((i + 8) % 16) << 16
    return word(i)


# What a unit holds at most, by the field its ranges are given in.
_UNITS = {"words": ("word", 0xFFFF), "bytes": ("byte", 0xFF), "dwords": ("dword", 0xFFFFFFFF)}


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
        # The codes whose numbers are hexadecimal (W1A is the word after W19).
        self.hexadecimal = tuple(message.get("hexadecimal", ()))
        # Indirect specification: each pointer with the device whose address it holds.
        self.addresses = {
            Device.parse(pointer, self.hexadecimal): Device.parse(target, self.hexadecimal)
            for pointer, target in message.get("addresses", {}).items()
        }
        memory = {}
        # A byte-addressed family's ranges carry bytes (protocol version 3), a family whose
        # unit is a 32-bit word dwords (version 4).
        self.unit = "word"
        for block in message.get("memory", []):
            start = Device.parse(block["start"], self.hexadecimal)
            field = next((f for f in _UNITS if f in block), "words")
            self.unit = _UNITS[field][0]
            for i, value in enumerate(block.get(field, [])):
                unit = start.offset(i)
                memory[(unit.code, unit.index)] = value
        self.memory = memory
        self.writes = {}
        self.error = None

    def flag(self, name):
        """The flag as this variant's CPU sees it: a flag the variant does not implement holds
        the value it behaves as, whatever the case set."""
        if name in self.ignored_flags:
            return bool(self.ignored_flags[name])
        return bool(self.flags.get(name, False))

    def operand(self, name):
        """A device operand as a Device, a constant as an int. An operand given by indirect
        specification (`@D10`) is the device its pointer addresses (`addresses`), as the CPU
        resolves it; an emulator with indirect specification of its own reads `operands` and
        `addresses` as they came, and stores the address in the pointer itself."""
        if name not in self.operands:
            raise Unsupported("%s needs operand %r" % (self.instruction, name))
        value = self.operands[name]
        if not isinstance(value, str):
            return value
        if value.startswith("@"):
            pointer = Device.parse(value[1:], self.hexadecimal)
            if pointer not in self.addresses:
                raise ValueError("%s is indirect and `addresses` says nothing of %s" % (value, pointer))
            return self.addresses[pointer]
        return Device.parse(value, self.hexadecimal)

    def pointer(self, name):
        """The device holding the address of an operand given by indirect specification, or
        None for an operand given directly."""
        value = self.operands.get(name)
        if isinstance(value, str) and value.startswith("@"):
            return Device.parse(value[1:], self.hexadecimal)
        return None

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
        return fill_word(self.fill, Device(*key), self.unit)

    def exists(self, device):
        """Whether the word exists on the case's variant, for words within 64 of a device
        operand: the request's window covers that span and is cut to the words that exist, so
        a word there that is not in the window lies past the end of the device range."""
        return (device[0], device[1]) in self.memory

    def write(self, device, value):
        most = {"byte": 0xFF, "word": 0xFFFF, "dword": 0xFFFFFFFF}[self.unit]
        if not 0 <= value <= most:
            raise ValueError("%s: %r does not fit a %s" % (device, value, self.unit))
        self.writes[(device[0], device[1])] = value

    def fail(self, code=None, flag=None):
        """Signal an operation error: the vendor's code, or the flag for flag-only vendors."""
        self.error = {"code": code} if flag is None else {"flag": str(flag)}

    def answer(self):
        return {
            "type": "result",
            "id": self.id,
            "writes": {str(Device(code, index, code in self.hexadecimal)): value
                       for (code, index), value in self.writes.items()},
            "error": self.error,
        }


_dumps = json.JSONEncoder(separators=(",", ":")).encode


def _negotiate(message, levels):
    """The protocol version to answer a harness hello with: the harness's own when this
    module speaks it, else the highest this module speaks (the harness then refuses)."""
    asked = message.get("protocol", 1)
    if asked in levels:
        return asked
    sys.stderr.write("plc_adapter: the harness speaks protocol %r; this adapter speaks %s\n"
                     % (asked, " or ".join(str(v) for v in levels)))
    return max(levels)


def _loop(stdin, stdout, hello, answer):
    """Reads the harness's messages until shutdown or end of input. hello(message) and
    answer(request) return the message to send back."""
    for line in stdin:
        if not line.strip():
            continue
        message = json.loads(line)
        kind = message.get("type")
        if kind == "hello":
            stdout.write(_dumps(hello(message)) + "\n")
        elif kind == "run":
            try:
                for request in message["cases"]:
                    # Each answer goes out at once: the harness's time limit for a case runs
                    # from the previous answer, and a buffered answer looks like a hang.
                    stdout.write(_dumps(answer(request)) + "\n")
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


def _serving(loop, stdin, stdout):
    """Runs loop(stdin, stdout) with sys.stdout pointed at stderr (when serving the process's
    own stdout), so that nothing but answers reaches the protocol channel."""
    stdin = stdin or sys.stdin
    if stdout is not None:
        return loop(stdin, stdout)
    channel = sys.stdout
    sys.stdout = sys.stderr
    try:
        return loop(stdin, channel)
    finally:
        sys.stdout = channel


def serve(run, name, version, profile, instructions, variants=None, flags=None,
          operands=None, device_ranges=None, stdin=None, stdout=None):
    """Answers the harness as an instruction-level backend until it says shutdown or closes
    stdin. Speaks protocol version 1 or 2, whichever the harness asks for.

    run: function(Case) executing one case (see the module documentation).
    profile: the vendor profile id implemented, e.g. "mitsubishi-iqr".
    instructions: the instructions implemented; variants: the profile variants (None: all).
    flags: {flag: [settings implemented]} for flags implemented in one setting only.
    operands: {operand: {"devices": [codes], "constants": [values]}} for operands implemented
      in some forms only (a form left out is all of its kind), e.g. {"n": {"constants": [4]}}.
    device_ranges: False for a backend with no device ranges of its own: the cases expecting a
      device-range error are skipped for it instead of failed.
    """
    capabilities = {"profile": profile, "instructions": list(instructions)}
    if variants is not None:
        capabilities["variants"] = list(variants)
    if flags:
        capabilities["flags"] = {k: [bool(v) for v in vs] for k, vs in flags.items()}
    if operands:
        capabilities["operands"] = operands
    if device_ranges is not None:
        capabilities["device_ranges"] = bool(device_ranges)

    def hello(message):
        return {"type": "hello", "protocol": _negotiate(message, PROTOCOL_VERSIONS),
                "backend": {"name": name, "version": version},
                "capabilities": capabilities}

    def answer(request):
        if "instruction" not in request:
            return {"type": "unsupported", "id": request["id"],
                    "reason": "%s is an instruction-level backend" % name}
        case = Case(request)
        try:
            run(case)
        except Unsupported as why:
            return {"type": "unsupported", "id": case.id, "reason": str(why)}
        return case.answer()

    _serving(lambda i, o: _loop(i, o, hello, answer), stdin, stdout)


FIELD_KEYS = ("widths", "variable", "leading_zeros", "byte_order", "whole_frame")


def _codec_capability(digits, width, reading, field=None):
    if width not in (16, 32):
        raise ValueError("width must be 16 or 32, not %r" % (width,))
    capability = {"width": width}
    if reading is not None:
        capability["reading"] = str(reading)
    if digits is not None:
        digits = sorted(set(int(d) for d in digits))
        if not digits or not all(1 <= d <= 8 for d in digits):
            raise ValueError("digits must be counts from 1 to 8, not %r" % (digits,))
        capability["digits"] = digits
    for key, value in (field or {}).items():
        if key not in FIELD_KEYS:
            raise ValueError("field: %r is not one of %s" % (key, ", ".join(FIELD_KEYS)))
        if key == "widths":
            if not all(int(d) >= 1 and w in (8, 16, 32) for d, w in value.items()):
                raise ValueError("field widths: digit counts to 8, 16 or 32 bits, not %r" % (value,))
            capability["widths"] = {str(int(d)): w for d, w in value.items()}
        elif key == "byte_order":
            if value not in ("high-first", "low-first"):
                raise ValueError("field byte_order: 'high-first' or 'low-first', not %r" % (value,))
            capability["byte-order"] = value
        else:
            capability[key.replace("_", "-")] = bool(value)
    return capability


def _takes(declared, digits):
    """Whether a declared operation takes a digit count: its digits, or its field's widths."""
    if "digits" in declared:
        return digits in declared["digits"]
    if "widths" in declared:
        return str(digits) in declared["widths"]
    return 1 <= digits <= 8


def _width(declared, digits):
    return declared.get("widths", {}).get(str(digits), declared["width"])


def _error_class(error, errors):
    """The class `errors` maps the exception to (its most specific listed class), or None."""
    if isinstance(error, CodecError):
        return error.error_class
    for klass in type(error).__mro__:
        if klass in errors:
            return errors[klass]
    return None


def _text_bytes(text):
    if isinstance(text, str):
        return text.encode("utf-8")
    if isinstance(text, (bytes, bytearray, memoryview)):
        return bytes(text)
    if isinstance(text, (list, tuple)) and all(isinstance(b, int) and 0 <= b <= 255 for b in text):
        return bytes(text)
    raise TypeError("encode must return bytes or str, not %s" % type(text).__name__)


def serve_codec(decode=None, encode=None, name=None, version=None, decode_digits=None,
                encode_digits=None, width=16, errors=None, stdin=None, stdout=None,
                decode_reading=None, encode_reading=None, decode_errors=None,
                encode_errors=None, field=None):
    """Answers the harness as a codec-level backend (protocol version 2) until it says shutdown
    or closes stdin.

    decode: function(text: bytes, digits: int) -> int, for hex-to-value (None: not
      implemented). text is the characters to convert, any byte values.
    encode: function(value: int, digits: int) -> bytes or str, for value-to-hex (None: not
      implemented). The harness reads the text up to its first 00H.
    decode_digits, encode_digits: the digit counts each implements (None: any count 1-8);
      cases with another count are skipped with that reason.
    width: the value width in bits, 16 or 32: cases whose value does not fit are skipped.
    errors: {exception class: error class}, e.g. {ValueError: "invalid-digit"}: how the
      library's exceptions answer. A subclass maps like its nearest listed base class.
    decode_errors, encode_errors: the same for one direction, over `errors` (a library that
      raises ValueError for a bad digit when decoding and for a value too wide when encoding:
      decode_errors={ValueError: "invalid-digit"}, encode_errors={ValueError: "error"}).
    decode_reading, encode_reading: the built-in reading each follows, as `plc-conformance
      sweep` names it (e.g. "fx5/hexa-16bit", "fx5/asci-16bit"): a sweep of the operation
      judges the codec against it.
    field: what the protocol's field is, where it is not a fixed run of digits, most
      significant first (docs/protocol.md, "Field shapes"): {"widths": {2: 8, 4: 16}} (the bits
      for each digit count taken), "variable": True (a token of whatever length), "leading_zeros":
      False (value -> text writes none), "byte_order": "low-first" (the first character pair is
      the low byte), "whole_frame": True (the field is checked with the frame around it).
    """
    if name is None or version is None:
        raise TypeError("serve_codec needs name= and version=")
    if decode is None and encode is None:
        raise TypeError("serve_codec needs decode=, encode= or both")
    for label, table in (("errors", errors), ("decode_errors", decode_errors),
                         ("encode_errors", encode_errors)):
        for klass, error_class in (table or {}).items():
            if not (isinstance(klass, type) and issubclass(klass, BaseException)):
                raise TypeError("%s: %r is not an exception class" % (label, klass))
            if error_class not in ERROR_CLASSES:
                raise ValueError("%s: %r is not one of %s"
                                 % (label, error_class, ", ".join(ERROR_CLASSES)))
    # Each direction's table: its own entries over the shared ones.
    by_operation = {
        HEX_TO_VALUE: {**(errors or {}), **(decode_errors or {})},
        VALUE_TO_HEX: {**(errors or {}), **(encode_errors or {})},
    }
    codec = {}
    if decode is not None:
        codec[HEX_TO_VALUE] = _codec_capability(decode_digits, width, decode_reading, field)
    if encode is not None:
        codec[VALUE_TO_HEX] = _codec_capability(encode_digits, width, encode_reading, field)

    def hello(message):
        if message.get("protocol", 1) < 2:
            sys.stderr.write("plc_adapter: %s is a codec-level backend, which needs protocol "
                             "version 2; the harness speaks %r\n" % (name, message.get("protocol")))
        return {"type": "hello", "protocol": 2,
                "backend": {"name": name, "version": version},
                "capabilities": {"codec": codec}}

    def answer(request):
        ident = request["id"]
        operation = request.get("operation")
        digits = request.get("digits")
        try:
            declared = codec.get(operation)
            if declared is not None and not _takes(declared, digits):
                # Outside the declared capabilities: the harness skips such cases, and the
                # library is never called with a count it does not take.
                raise Unsupported("%s with %s digits is not implemented" % (operation, digits))
            if operation == VALUE_TO_HEX and declared is not None \
                    and not 0 <= request["value"] < 1 << _width(declared, digits):
                raise Unsupported("%s is wider than %d bits"
                                  % (request["value"], _width(declared, digits)))
            if operation == HEX_TO_VALUE and decode is not None:
                value = decode(bytes(request["text"]), digits)
                if isinstance(value, bool) or not isinstance(value, int):
                    raise TypeError("decode must return an int, not %s" % type(value).__name__)
                return {"type": "result", "id": ident, "value": value}
            if operation == VALUE_TO_HEX and encode is not None:
                text = _text_bytes(encode(request["value"], digits))
                return {"type": "result", "id": ident, "text": list(text)}
            what = operation if operation is not None else "instruction %s" % request.get("instruction")
            raise Unsupported("%s is not implemented by %s" % (what, name))
        except Unsupported as why:
            return {"type": "unsupported", "id": ident, "reason": str(why)}
        except Exception as error:  # noqa: BLE001 - mapped, or re-raised to crash
            error_class = _error_class(error, by_operation.get(operation, {}))
            if error_class is None:
                raise
            return {"type": "result", "id": ident, "error": error_class}

    _serving(lambda i, o: _loop(i, o, hello, answer), stdin, stdout)
