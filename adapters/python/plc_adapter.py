"""Turn Python functions into a plc-conformance external backend.

The harness starts the adapter as a child process and speaks the JSON-lines protocol of
docs/protocol.md on its stdin and stdout. This module does the protocol; the adapter supplies
the conversion, at one of two levels.

Codec level (protocol version 2, and 5 for batched conversions): two functions, text to value
and value to text. The harness runs the cross-vendor corpus against them directly, with no
memory, devices or fill, and `plc-conformance sweep` runs millions of generated texts through
them (protocol version 5: one `convert` message of many texts, answered by one line):

    import plc_adapter
    import mylib

    plc_adapter.serve_codec(
        decode=lambda text, digits: mylib.parse_hex(text),       # bytes -> int
        encode=lambda value, digits: mylib.format_hex(value, digits),  # int -> bytes or str
        name="mylib", version="1.2.0",
        decode_digits=[4], encode_digits=[4], width=16,
        errors={mylib.BadDigit: "invalid-digit"})

A library whose field is not a plain run of digits says so with field= (both directions) or
decode_field= / encode_field= (one direction each), e.g. one that reads the low byte first but
writes the high byte first: decode_field={"byte_order": "low-first"}.

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
from itertools import repeat

__version__ = "0.1.0"

# The protocol versions this module speaks: 1 (instruction level), 2 (adds codec level), 3
# (byte-addressed families), 4 (families whose unit is a 32-bit word) and 5 (adds `convert`:
# many conversions of a codec in one message, answered by one `converted` line).
PROTOCOL_VERSIONS = (1, 2, 3, 4, 5)
PROTOCOL_VERSION = 2
# The first version that carries `convert` messages: a codec answers a hello of 5 or later
# with 5, an older one with 2.
CONVERT_VERSION = 5

# The error classes a codec answers with (docs/protocol.md, "Version 2").
ERROR_CLASSES = ("invalid-digit", "invalid-count", "device-range", "error", "bad-check")

# The codec operations: the conversions, and a protocol's check characters.
HEX_TO_VALUE = "hex-to-value"
VALUE_TO_HEX = "value-to-hex"
CHECK = "check"
VERIFY = "verify"

__all__ = [
    "Case",
    "CONVERT_VERSION",
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


class _SmallInts(dict):
    """parse_int for the `convert` messages of text: their ints are digit counts (and the id),
    which a dict gives faster than int() parses them. Only short numbers are kept."""

    __slots__ = ()

    def __missing__(self, text):
        value = int(text)
        if len(text) <= 3:
            self[text] = value
        return value


_loads_texts = json.JSONDecoder(parse_int=_SmallInts().__getitem__).decode


def _loads(line):
    """json.loads, with the faster reading of ints for a `convert` message of texts (both read
    every line alike: which one runs is only a matter of speed)."""
    if line.startswith('{"type":"convert"') and '"value-to-hex"' not in line:
        return _loads_texts(line)
    return json.loads(line)


def _negotiate(message, levels):
    """The protocol version to answer a harness hello with: the harness's own when this
    module speaks it, else the highest this module speaks (the harness then refuses)."""
    asked = message.get("protocol", 1)
    if asked in levels:
        return asked
    sys.stderr.write("plc_adapter: the harness speaks protocol %r; this adapter speaks %s\n"
                     % (asked, " or ".join(str(v) for v in levels)))
    return max(levels)


def _loop(stdin, stdout, hello, answer, convert=None):
    """Reads the harness's messages until shutdown or end of input. hello(message) and
    answer(request) return the message to send back; convert(message), for a codec, the whole
    `converted` line (protocol version 5)."""
    write, flush = stdout.write, stdout.flush
    for line in stdin:
        if not line.strip():
            continue
        message = _loads(line)
        kind = message.get("type")
        if kind == "convert" and convert is not None:
            # One line for the whole message, written once: an exception that ends the process
            # leaves none of its answers, and the harness asks the items again one by one.
            write(convert(message))
            flush()
            continue
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


FIELD_KEYS = ("widths", "variable", "leading_zeros", "byte_order", "whole_frame",
              "blanks_between_pairs")


def _codec_capability(digits, width, reading, field=None, operation=HEX_TO_VALUE, label="field"):
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
            raise ValueError("%s: %r is not one of %s" % (label, key, ", ".join(FIELD_KEYS)))
        if key == "widths":
            if not all(int(d) >= 1 and w in (8, 16, 32) for d, w in value.items()):
                raise ValueError("%s widths: digit counts to 8, 16 or 32 bits, not %r" % (label, value))
            capability["widths"] = {str(int(d)): w for d, w in value.items()}
        elif key == "byte_order":
            if value not in ("high-first", "low-first"):
                raise ValueError("%s byte_order: 'high-first' or 'low-first', not %r" % (label, value))
            capability["byte-order"] = value
        elif key == "blanks_between_pairs" and operation != HEX_TO_VALUE:
            # Only a text is read: value -> text has no blanks to skip (the harness refuses it).
            raise ValueError("%s blanks_between_pairs: a shape of hex-to-value only (text -> "
                             "value skips blanks between byte pairs); give it in decode_field=, "
                             "not for value-to-hex" % (label,))
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


# --- protocol version 5: `convert`, many conversions of one operation in one message ----------
#
# A sweep sends millions of texts; the loops below are what a conversion costs beyond the
# library's own call. Until the first exception of a message the library is called by map()
# over the items (C-level iteration, no Python frame of this module per item) and the returns
# are checked afterwards, by type, in one pass; from the first exception on (a message of
# random texts has many), a plain loop catches each where it is raised, which costs far less
# per exception than restarting map(). Plain answers are the library's ints and strings
# themselves; an error answer is one shared object per exception type. Each item answers
# exactly what a `run` case with the same text (or value) and digit count answers.


class _Answer(dict):
    """An answer of a `converted` line that is not a plain value or text: {"error": class} or
    {"unsupported": reason}. A type of its own, so that a dict a library returns is never taken
    for one."""

    __slots__ = ()


def _failed(error, table, cache):
    """The answer to an exception the library raised, as the per-case path answers it, or None
    for one `table` does not map (the caller re-raises it). cache: exception type -> answer,
    for the types whose class does not depend on the instance (all but CodecError)."""
    if isinstance(error, Unsupported):
        return _Answer(unsupported=str(error))
    answer = cache.get(type(error))
    if answer is None:
        error_class = _error_class(error, table)
        if error_class is None:
            return None
        answer = _Answer(error=error_class)
        if not isinstance(error, CodecError):
            cache[type(error)] = answer
    return answer


def _decoded(value, table):
    """A value decode returned that is not exactly an int: the per-case check, and its answer."""
    try:
        if isinstance(value, bool) or not isinstance(value, int):
            raise TypeError("decode must return an int, not %s" % type(value).__name__)
        return value
    except Exception as error:  # noqa: BLE001 - mapped, or re-raised to crash
        error_class = _error_class(error, table)
        if error_class is None:
            raise
        return _Answer(error=error_class)


def _encoded(text, table):
    """What encode returned, as the characters of the answer (one per byte): the per-case
    conversion (str as UTF-8, bytes, a list of byte values) and its check."""
    try:
        if type(text) is str and text.isascii():
            return text
        return _text_bytes(text).decode("latin-1")
    except Exception as error:  # noqa: BLE001 - mapped, or re-raised to crash
        error_class = _error_class(error, table)
        if error_class is None:
            raise
        return _Answer(error=error_class)


def _check_values(out, table):
    """Checks the values decode returned (out holds nothing else)."""
    if list(map(type, out)).count(int) != len(out):
        for k, value in enumerate(out):
            if type(value) is not int:
                out[k] = _decoded(value, table)


def _check_texts(out, table):
    """Turns the texts encode returned (out holds nothing else) into answers."""
    kinds = list(map(type, out))
    if kinds.count(str) == len(out) and "".join(out).isascii():
        return
    if kinds.count(bytes) == len(out):
        out[:] = map(bytes.decode, out, repeat("latin-1"))
        return
    out[:] = [_encoded(text, table) for text in out]


def _convert_fast(function, arguments, digits, table, decoding):
    """function(argument, digits) over items the declared capabilities all take, as the list
    of answers. An exception `table` does not map propagates (ending the process), after the
    returns before it are checked, as the per-case path would have met them first."""
    out = []
    arguments, digits = iter(arguments), iter(digits)
    try:
        # list.extend keeps the items map() gave before an exception.
        out.extend(map(function, arguments, digits))
    except Exception as error:  # noqa: BLE001 - mapped, or re-raised to crash
        (_check_values if decoding else _check_texts)(out, table)
        cache = {}
        answer = _failed(error, table, cache)
        if answer is None:
            raise
        append = out.append
        append(answer)
    else:
        (_check_values if decoding else _check_texts)(out, table)
        return out
    # From the first exception on, item by item; the answer to a type of exception seen before
    # is looked up here, without a call (a message of random texts raises on most items).
    get = cache.get
    if decoding:
        for argument, d in zip(arguments, digits):
            try:
                value = function(argument, d)
            except Exception as error:  # noqa: BLE001 - mapped, or re-raised to crash
                answer = get(error.__class__)
                if answer is None:
                    answer = _failed(error, table, cache)
                    if answer is None:
                        raise
                append(answer)
                continue
            append(value if type(value) is int else _decoded(value, table))
    else:
        for argument, d in zip(arguments, digits):
            try:
                text = function(argument, d)
            except Exception as error:  # noqa: BLE001 - mapped, or re-raised to crash
                answer = _failed(error, table, cache)
                if answer is None:
                    raise
                append(answer)
                continue
            append(text if type(text) is str and text.isascii() else _encoded(text, table))
    return out


def _takes_all(declared, digits):
    """Whether the operation takes every digit count of the message (then no item is refused
    for its count, and the library is called on all of them)."""
    counts = set(digits)
    return all(type(d) is int and _takes(declared, d) for d in counts)


def _latin1(texts):
    """The texts as bytes, one per character (U+0000-U+00FF), or None when one is not such a
    text (the item-by-item path then ends the process on it)."""
    try:
        # One join, encode and split is faster than an encode per text; a text holding the
        # separator splits into more parts, and then each is encoded on its own.
        data = "\0".join(texts).encode("latin-1").split(b"\0")
        return data if len(data) == len(texts) else list(map(str.encode, texts, repeat("latin-1")))
    except (TypeError, UnicodeError):
        return None


def _convert_decode(decode, declared, table, texts, digits):
    data = _latin1(texts)
    if data is not None and _takes_all(declared, digits):
        return _convert_fast(decode, data, digits, table, True)
    out = []
    append = out.append
    for text, d in zip(texts, digits):
        # One character per byte (U+0000-U+00FF); a character above is the harness's error.
        text = text.encode("latin-1")
        try:
            if not _takes(declared, d):
                raise Unsupported("%s with %s digits is not implemented" % (HEX_TO_VALUE, d))
            append(_decoded(decode(text, d), table))
        except Unsupported as why:
            append(_Answer(unsupported=str(why)))
        except Exception as error:  # noqa: BLE001 - mapped, or re-raised to crash
            error_class = _error_class(error, table)
            if error_class is None:
                raise
            append(_Answer(error=error_class))
    return out


def _one_width(declared, digits):
    """The width every digit count of the message has, or None when they differ."""
    widths = set(_width(declared, d) for d in set(digits))
    return widths.pop() if len(widths) == 1 else None


def _convert_encode(encode, declared, table, values, digits):
    fast = _takes_all(declared, digits)
    if fast and values:
        width = _one_width(declared, digits)
        try:
            fast = width is not None and 0 <= min(values) and max(values) < 1 << width
        except TypeError:
            fast = False
    if fast:
        return _convert_fast(encode, values, digits, table, False)
    out = []
    append = out.append
    for value, d in zip(values, digits):
        try:
            if not _takes(declared, d):
                raise Unsupported("%s with %s digits is not implemented" % (VALUE_TO_HEX, d))
            if not 0 <= value < 1 << _width(declared, d):
                raise Unsupported("%s is wider than %d bits" % (value, _width(declared, d)))
            append(_encoded(encode(value, d), table))
        except Unsupported as why:
            append(_Answer(unsupported=str(why)))
        except Exception as error:  # noqa: BLE001 - mapped, or re-raised to crash
            error_class = _error_class(error, table)
            if error_class is None:
                raise
            append(_Answer(error=error_class))
    return out


def serve_codec(decode=None, encode=None, name=None, version=None, decode_digits=None,
                encode_digits=None, width=16, errors=None, stdin=None, stdout=None,
                decode_reading=None, encode_reading=None, decode_errors=None,
                encode_errors=None, field=None, decode_field=None, encode_field=None,
                protocol=None, fields=None, cross_vendor=False, check=None, verify=None,
                digits=None):
    """Answers the harness as a codec-level backend until it says shutdown or closes stdin.
    Speaks protocol version 2 (one `run` case at a time) and 5 (also `convert`: many texts or
    values of one operation in one message, answered by one `converted` line, which is what
    makes a sweep of millions of texts fast): 5 to a harness that speaks it, else 2.

    decode: function(text: bytes, digits: int) -> int, for hex-to-value (None: not
      implemented). text is the characters to convert, any byte values.
    encode: function(value: int, digits: int) -> bytes or str, for value-to-hex (None: not
      implemented). The harness reads the text up to its first 00H.
    decode_digits, encode_digits: the digit counts each implements (None: any count 1-8);
      digits sets both at once, as codec_cases takes it;
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
      the low byte), "whole_frame": True (the field is checked with the frame around it),
      "blanks_between_pairs": True (text -> value skips blanks between byte pairs, as
      bytes.fromhex does; hex-to-value only: given for value-to-hex it is refused at start-up).
      The harness decides which cases each shape skips or reads otherwise; this module only
      declares the shape in its hello.
    decode_field, encode_field: the field shape of one direction, used instead of `field` for
      it (keys as for `field`): a library that reads the low byte first but writes the high
      byte first gives decode_field={"byte_order": "low-first"}; blanks_between_pairs goes in
      decode_field (or in `field` of a codec without encode).

    protocol: the communication protocol whose fields the library reads and writes, as
      vendors/protocols/ names it ("mc-ascii", "modbus-ascii", "fx-computer-link",
      "mewtocol-com", "omron-host-link", "keyence-kv-l2"): the codec is then judged by that
      protocol's corpus (vectors/protocols/), each difference naming the protocol's rule and
      page, instead of the cross-vendor (instruction) corpus. A field's digit count says which
      field is asked (a request also carries its name, `field`).
    fields: the protocol's fields implemented, by the profile's names (["word", "dword"]);
      None for every field.
    cross_vendor: with protocol, also run the cross-vendor corpus (the instruction view).
    check: function(span: bytes) -> bytes or str: the protocol's check characters (LRC, sum
      check, BCC, FCS) of the checked span, e.g. b"010304010001" -> "F6" for Modbus ASCII.
    verify: function(frame: bytes) -> bool: whether the span followed by its check characters
      checks (True is accepted, False the error bad-check); an exception maps as for decode.

    Each item of a `convert` message answers exactly what a `run` case with the same text (or
    value) and digit count answers: the value (or text), {"error": class} for an exception
    `errors` maps or a CodecError, {"unsupported": reason} outside the declared digit counts or
    width, or for Unsupported. An exception `errors` does not map ends the process with its
    traceback and none of the message's answers; the harness then asks its items one by one.
    """
    if digits is not None:
        decode_digits = digits if decode_digits is None else decode_digits
        encode_digits = digits if encode_digits is None else encode_digits
    if name is None or version is None:
        raise TypeError("serve_codec needs name= and version=")
    if decode is None and encode is None and check is None and verify is None:
        raise TypeError("serve_codec needs decode=, encode=, check= or verify=")
    if protocol is None and (fields is not None or cross_vendor or check is not None
                             or verify is not None):
        raise TypeError("serve_codec: fields=, cross_vendor=, check= and verify= belong to a "
                        "protocol: give protocol= too")
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
        CHECK: {**(errors or {}), **(decode_errors or {})},
        VERIFY: {**(errors or {}), **(decode_errors or {})},
    }
    if decode_field is not None and decode is None:
        raise TypeError("serve_codec: decode_field= is the field of decode=, which is not given")
    if encode_field is not None and encode is None:
        raise TypeError("serve_codec: encode_field= is the field of encode=, which is not given")
    codec = {}
    if decode is not None:
        codec[HEX_TO_VALUE] = _codec_capability(
            decode_digits, width, decode_reading,
            field if decode_field is None else decode_field, HEX_TO_VALUE,
            "field" if decode_field is None else "decode_field")
    if encode is not None:
        codec[VALUE_TO_HEX] = _codec_capability(
            encode_digits, width, encode_reading,
            field if encode_field is None else encode_field, VALUE_TO_HEX,
            "field" if encode_field is None else "encode_field")

    if check is not None:
        codec[CHECK] = {}
    if verify is not None:
        codec[VERIFY] = {}
    if protocol is not None:
        codec["protocol"] = protocol
        if fields is not None:
            codec["fields"] = list(fields)
        if cross_vendor:
            codec["cross-vendor"] = True

    def hello(message):
        asked = message.get("protocol", 1)
        if asked < 2:
            sys.stderr.write("plc_adapter: %s is a codec-level backend, which needs protocol "
                             "version 2; the harness speaks %r\n" % (name, message.get("protocol")))
        # 5 (convert) to a harness that speaks it (or a newer one), else 2 as before.
        return {"type": "hello", "protocol": CONVERT_VERSION if asked >= CONVERT_VERSION else 2,
                "backend": {"name": name, "version": version},
                "capabilities": {"codec": codec}}

    def convert(message):
        # Everything that does not depend on the item is resolved here, once per message.
        ident = message["id"]
        operation = message.get("operation")
        digits = message["digits"]
        items = message["texts"] if operation == HEX_TO_VALUE else \
            message["values"] if operation == VALUE_TO_HEX else \
            message.get("texts", message.get("values", ()))
        if len(items) != len(digits):
            raise ValueError("convert %r: %d digit counts for %d items"
                             % (ident, len(digits), len(items)))
        declared = codec.get(operation)
        table = by_operation.get(operation, {})
        if declared is None:
            answers = [_Answer(unsupported="%s is not implemented by %s" % (operation, name))] \
                * len(items)
        elif operation == HEX_TO_VALUE:
            answers = _convert_decode(decode, declared, table, items, digits)
        else:
            answers = _convert_encode(encode, declared, table, items, digits)
        return _dumps({"type": "converted", "id": ident, "answers": answers}) + "\n"

    def answer(request):
        ident = request["id"]
        operation = request.get("operation")
        digits = request.get("digits")
        try:
            declared = codec.get(operation)
            if operation in (CHECK, VERIFY):
                declared = None  # a check character's length is its protocol's
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
            if operation == CHECK and check is not None:
                text = _text_bytes(check(bytes(request["text"])))
                return {"type": "result", "id": ident, "text": list(text)}
            if operation == VERIFY and verify is not None:
                if verify(bytes(request["text"])):
                    return {"type": "result", "id": ident, "accepted": True}
                return {"type": "result", "id": ident, "error": "bad-check"}
            what = operation if operation is not None else "instruction %s" % request.get("instruction")
            raise Unsupported("%s is not implemented by %s" % (what, name))
        except Unsupported as why:
            return {"type": "unsupported", "id": ident, "reason": str(why)}
        except Exception as error:  # noqa: BLE001 - mapped, or re-raised to crash
            error_class = _error_class(error, by_operation.get(operation, {}))
            if error_class is None:
                raise
            return {"type": "result", "id": ident, "error": error_class}

    _serving(lambda i, o: _loop(i, o, hello, answer, convert), stdin, stdout)
