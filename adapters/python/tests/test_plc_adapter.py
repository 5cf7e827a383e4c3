"""The Python helper driven as the harness drives it: each backend runs as a child process, is
sent scripted protocol lines (hello, run, shutdown) and its answers are checked.

    python3 -m unittest discover adapters/python/tests
"""

import io
import json
import os
import subprocess
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
FIXTURES = os.path.join(HERE, "fixtures")
sys.path.insert(0, os.path.join(HERE, ".."))

import plc_adapter  # noqa: E402

HELLO_1 = {"type": "hello", "protocol": 1, "harness": "plc-conformance 0.1.0"}
HELLO_2 = {"type": "hello", "protocol": 2, "harness": "plc-conformance 0.2.0"}
HELLO_3 = {"type": "hello", "protocol": 3, "harness": "plc-conformance 0.3.0"}
SHUTDOWN = {"type": "shutdown"}


def drive(fixture, args, messages):
    """Runs a fixture with the messages on stdin; returns (answers, stderr, exit status)."""
    proc = subprocess.run(
        [sys.executable, os.path.join(FIXTURES, fixture)] + list(args),
        input="".join(json.dumps(m) + "\n" for m in messages),
        capture_output=True, text=True, timeout=30)
    lines = [line for line in proc.stdout.split("\n") if line]
    return [json.loads(line) for line in lines], proc.stderr, proc.returncode


def h2v(ident, text, digits):
    return {"id": ident, "case": "h2v-%d" % ident, "operation": "hex-to-value",
            "text": list(text.encode("latin-1")), "digits": digits}


def v2h(ident, value, digits):
    return {"id": ident, "case": "v2h-%d" % ident, "operation": "value-to-hex",
            "value": value, "digits": digits}


def ascii_list(text):
    return list(text.encode("latin-1"))


class CodecLevel(unittest.TestCase):
    def test_hello_declares_protocol_2_and_the_codec(self):
        answers, _, status = drive("codec.py", ["strict"], [HELLO_2, SHUTDOWN])
        self.assertEqual(status, 0)
        self.assertEqual(answers, [{
            "type": "hello", "protocol": 2,
            "backend": {"name": "codec-strict", "version": "1"},
            "capabilities": {"codec": {
                "hex-to-value": {"width": 32, "digits": [4, 8]},
                "value-to-hex": {"width": 32, "digits": [4, 8]},
            }},
        }])

    def test_digits_sets_both_directions_as_codec_cases_takes_it(self):
        stdin = io.StringIO(json.dumps(HELLO_2) + "\n" + json.dumps(SHUTDOWN) + "\n")
        stdout = io.StringIO()
        plc_adapter.serve_codec(decode=lambda t, d: int(t, 16), encode=lambda v, d: "%04X" % v,
                                name="both", version="1", digits=[4], stdin=stdin,
                                stdout=stdout)
        hello = json.loads(stdout.getvalue().splitlines()[0])
        codec = hello["capabilities"]["codec"]
        self.assertEqual(codec["hex-to-value"]["digits"], [4])
        self.assertEqual(codec["value-to-hex"]["digits"], [4])

    def test_cases_are_answered_in_order(self):
        cases = [h2v(1, "5A8D", 4), h2v(2, "5a8D", 4), h2v(3, "12345678", 8), h2v(4, "12", 4),
                 h2v(5, "7F", 2), v2h(6, 2748, 4), v2h(7, 0x12345678, 4), v2h(8, 0x10000, 8),
                 v2h(9, 1 << 32, 8)]
        answers, stderr, status = drive("codec.py", ["strict"], [HELLO_2, {"type": "run", "cases": cases}, SHUTDOWN])
        self.assertEqual(status, 0, stderr)
        self.assertEqual(answers[1:], [
            {"type": "result", "id": 1, "value": 0x5A8D},
            {"type": "result", "id": 2, "error": "invalid-digit"},
            {"type": "result", "id": 3, "value": 0x12345678},
            {"type": "result", "id": 4, "error": "invalid-digit"},
            {"type": "unsupported", "id": 5, "reason": "hex-to-value with 2 digits is not implemented"},
            {"type": "result", "id": 6, "text": ascii_list("0ABC")},
            {"type": "result", "id": 7, "text": ascii_list("5678")},
            {"type": "result", "id": 8, "text": ascii_list("00010000")},
            {"type": "unsupported", "id": 9, "reason": "4294967296 is wider than 32 bits"},
        ])

    def test_a_deliberately_wrong_codec_answers_differently(self):
        script = [HELLO_2, {"type": "run", "cases": [h2v(1, "5a8D", 4), h2v(2, " 5A8", 4), h2v(3, "5A8D", 4)]}, SHUTDOWN]
        strict, _, _ = drive("codec.py", ["strict"], script)
        wrong, _, _ = drive("codec.py", ["lowercase"], script)
        said = lambda answers: [a.get("error", a.get("value")) for a in answers[1:]]  # noqa: E731
        self.assertEqual(said(strict), ["invalid-digit", "invalid-digit", 0x5A8D])
        self.assertEqual(said(wrong), [0x5A8D, 0x05A8, 0x5A8D])
        # The difference the harness reports: an error class expected, a value answered.
        self.assertNotEqual(wrong[1], strict[1])
        self.assertEqual(wrong[3], strict[3])

    def test_an_unmapped_exception_crashes_after_the_answers_before_it(self):
        cases = [h2v(1, "5A8D", 4), h2v(2, "DEAD", 4), h2v(3, "BEEF", 4)]
        answers, stderr, status = drive("codec.py", ["crash"], [HELLO_2, {"type": "run", "cases": cases}])
        self.assertNotEqual(status, 0)
        self.assertEqual(answers[1:], [{"type": "result", "id": 1, "value": 0x5A8D}])
        self.assertIn("Traceback", stderr)
        self.assertIn("deliberate crash on DEAD", stderr)

    def test_print_goes_to_stderr_not_into_the_protocol(self):
        answers, stderr, status = drive("codec.py", ["noisy"], [HELLO_2, {"type": "run", "cases": [h2v(1, "5A8D", 4), v2h(2, 5, 4)]}, SHUTDOWN])
        self.assertEqual(status, 0)
        self.assertEqual(len(answers), 3)
        self.assertIn("decoding", stderr)
        self.assertIn("encoding 5", stderr)

    def test_told_protocol_1_it_still_answers_2_and_says_why(self):
        answers, stderr, _ = drive("codec.py", ["strict"], [HELLO_1, SHUTDOWN])
        self.assertEqual(answers[0]["protocol"], 2)
        self.assertIn("needs protocol version 2", stderr)

    def test_end_of_input_ends_the_backend(self):
        answers, _, status = drive("codec.py", ["strict"], [HELLO_2])
        self.assertEqual(status, 0)
        self.assertEqual(len(answers), 1)


def habin_case(ident, **overrides):
    case = {
        "id": ident, "case": "habin-%d" % ident, "instruction": "HABIN",
        "profile": "mitsubishi-iqr", "variant": "rcpu", "flags": {"SM705": False},
        "operands": {"s": "D100", "d": "D200"}, "fill": "A",
        "memory": [{"start": "D100", "words": [0x4135, 0x4438, 0xA5A5]},
                   {"start": "D200", "words": [0xA7A7]}],
    }
    case.update(overrides)
    return case


class InstructionLevel(unittest.TestCase):
    def test_hello_answers_the_version_the_harness_speaks(self):
        hellos = ((HELLO_1, 1), (HELLO_2, 2), (HELLO_3, 3), (dict(HELLO_3, protocol=4), 4),
                  (dict(HELLO_3, protocol=5), 5), (dict(HELLO_3, protocol=9), 5), ({"type": "hello"}, 1))
        for hello, version in hellos:
            answers, _, _ = drive("habin.py", [], [hello, SHUTDOWN])
            self.assertEqual(answers[0], {
                "type": "hello", "protocol": version,
                "backend": {"name": "habin-py", "version": "1"},
                "capabilities": {"profile": "mitsubishi-iqr", "instructions": ["HABIN", "HABINP"],
                                 "flags": {"SM705": [False]}},
            })

    def test_cases_run_on_the_window_the_fill_and_the_flags(self):
        cases = [
            habin_case(1),  # "5A8D" -> 5A8DH (p.478 example)
            habin_case(2, memory=[{"start": "D100", "words": [0x6135, 0x4438]}, {"start": "D200", "words": [0]}]),
            habin_case(3, flags={"SM705": True}),
            habin_case(4, variant="rcpu-no-sm705", flags={"SM705": True}, ignored_flags={"SM705": False}),
            habin_case(5, memory=[{"start": "D100", "words": [0x4135]}, {"start": "D200", "words": [0]}]),
            habin_case(6, operands={"s": "D100", "d": 200}),
        ]
        answers, stderr, status = drive("habin.py", [], [HELLO_1, {"type": "run", "cases": cases}, SHUTDOWN])
        self.assertEqual(status, 0, stderr)
        self.assertEqual(answers[1:], [
            {"type": "result", "id": 1, "writes": {"D200": 0x5A8D}, "error": None},
            {"type": "result", "id": 2, "writes": {}, "error": {"code": 0x3401}},
            {"type": "unsupported", "id": 3, "reason": "SM705 on"},
            {"type": "result", "id": 4, "writes": {"D200": 0x5A8D}, "error": None},
            {"type": "result", "id": 5, "writes": {}, "error": {"code": 0x2820}},
            {"type": "unsupported", "id": 6, "reason": "operand 'd' as a constant (K200) is not implemented"},
        ])


class InProcess(unittest.TestCase):
    def serve_codec(self, messages, **options):
        out = io.StringIO()
        stdin = io.StringIO("".join(json.dumps(m) + "\n" for m in messages))
        plc_adapter.serve_codec(stdin=stdin, stdout=out, **options)
        return [json.loads(line) for line in out.getvalue().splitlines()]

    def test_codec_error_nearest_mapped_class_and_text_kinds(self):
        class FieldError(Exception):
            pass

        class WideError(FieldError):
            pass

        def decode(text, digits):
            if text == b"AAAA":
                raise plc_adapter.CodecError("invalid-count")
            if text == b"WXYZ":
                raise WideError("a subclass maps like its nearest listed base")
            if text == b"RXYZ":
                raise KeyError("R")
            return 0xFFFFFFFF

        answers = self.serve_codec(
            [HELLO_2, {"type": "run", "cases": [h2v(1, "AAAA", 4), h2v(2, "WXYZ", 4), h2v(3, "RXYZ", 4),
                                                h2v(4, "FFFFFFFF", 8), v2h(5, 1, 4), v2h(6, 2, 4), v2h(7, 3, 4)]},
             SHUTDOWN],
            decode=decode, encode=lambda value, digits: [b"0ABC\0junk", "0ABC", bytearray(b"00")][value - 1],
            name="x", version="1", width=32,
            errors={FieldError: "invalid-digit", Exception: "error", KeyError: "device-range"})
        self.assertEqual(answers[1:], [
            {"type": "result", "id": 1, "error": "invalid-count"},
            {"type": "result", "id": 2, "error": "invalid-digit"},
            {"type": "result", "id": 3, "error": "device-range"},
            {"type": "result", "id": 4, "value": 0xFFFFFFFF},
            {"type": "result", "id": 5, "text": ascii_list("0ABC\0junk")},
            {"type": "result", "id": 6, "text": ascii_list("0ABC")},
            {"type": "result", "id": 7, "text": ascii_list("00")},
        ])

    def test_an_operation_not_implemented_is_unsupported(self):
        answers = self.serve_codec([HELLO_2, {"type": "run", "cases": [v2h(1, 5, 4)]}, SHUTDOWN],
                                   decode=lambda t, d: 0, name="x", version="1")
        self.assertEqual(answers[0]["capabilities"], {"codec": {"hex-to-value": {"width": 16}}})
        self.assertEqual(answers[1]["type"], "unsupported")

    def test_each_direction_maps_its_own_errors(self):
        def decode(text, digits):
            raise ValueError("not a digit")

        def encode(value, digits):
            raise ValueError("too wide")

        answers = self.serve_codec(
            [HELLO_2, {"type": "run", "cases": [h2v(1, "5a8D", 4), v2h(2, 0x1234, 4)]}, SHUTDOWN],
            decode=decode, encode=encode, name="x", version="1",
            errors={ValueError: "error"}, decode_errors={ValueError: "invalid-digit"})
        self.assertEqual(answers[1:], [
            {"type": "result", "id": 1, "error": "invalid-digit"},
            {"type": "result", "id": 2, "error": "error"},
        ])
        with self.assertRaises(ValueError):
            plc_adapter.serve_codec(decode=decode, name="x", version="1",
                                    encode_errors={ValueError: "wrong"})

    def test_a_declared_reading_is_in_the_hello(self):
        answers = self.serve_codec([HELLO_2, SHUTDOWN], decode=lambda t, d: 0,
                                   encode=lambda v, d: "0", name="x", version="1",
                                   decode_reading="fx5/hexa-16bit")
        self.assertEqual(answers[0]["capabilities"], {"codec": {
            "hex-to-value": {"width": 16, "reading": "fx5/hexa-16bit"},
            "value-to-hex": {"width": 16}}})

    def test_a_field_shape_is_declared_and_bounds_what_is_answered(self):
        answers = self.serve_codec(
            [HELLO_2, {"type": "run", "cases": [h2v(1, "7F", 2), h2v(2, "5A8D", 4),
                                                v2h(3, 0x7F, 2), v2h(4, 0x1FF, 2)]}, SHUTDOWN],
            decode=lambda t, d: int(t.decode(), 16), encode=lambda v, d: "%02X" % v,
            name="byte-field", version="1",
            field={"widths": {2: 8}, "whole_frame": True, "byte_order": "low-first",
                   "leading_zeros": True, "variable": False})
        self.assertEqual(answers[0]["capabilities"]["codec"]["hex-to-value"], {
            "width": 16, "widths": {"2": 8}, "whole-frame": True, "byte-order": "low-first",
            "leading-zeros": True, "variable": False})
        self.assertEqual(answers[1], {"type": "result", "id": 1, "value": 0x7F})
        self.assertEqual(answers[2]["type"], "unsupported")
        self.assertEqual(answers[3], {"type": "result", "id": 3, "text": list(b"7F")})
        self.assertEqual(answers[4]["type"], "unsupported")
        for field in ({"widths": {2: 12}}, {"order": "low"}, {"byte_order": "middle"}):
            with self.assertRaises(ValueError):
                plc_adapter.serve_codec(decode=lambda t, d: 0, name="x", version="1", field=field)

    def test_what_the_protocol_cannot_say_is_refused(self):
        with self.assertRaises(ValueError):
            plc_adapter.CodecError("bad-class")
        with self.assertRaises(TypeError):
            plc_adapter.serve_codec(name="x", version="1")
        with self.assertRaises(ValueError):
            plc_adapter.serve_codec(decode=lambda t, d: 0, name="x", version="1", width=24)
        with self.assertRaises(ValueError):
            plc_adapter.serve_codec(decode=lambda t, d: 0, name="x", version="1", decode_digits=[0])
        with self.assertRaises(ValueError):
            plc_adapter.serve_codec(decode=lambda t, d: 0, name="x", version="1", errors={ValueError: "wrong"})

    def test_fill_word_and_case(self):
        self.assertEqual(plc_adapter.fill_word("A", 0), 0xA5A5)
        self.assertEqual(plc_adapter.fill_word("A", 1), 0xA4A4)
        self.assertEqual(plc_adapter.fill_word("A", plc_adapter.Device.parse("D17")), 0xA4A4)
        self.assertEqual(plc_adapter.fill_word("B", 0), 0x4630)
        self.assertEqual(plc_adapter.fill_word("B", 110), 0x3145)
        k4m = plc_adapter.Device.parse("K4M100")
        self.assertEqual(str(k4m.offset(1)), "K4M116")
        self.assertEqual(str(plc_adapter.Device.parse("D100").offset(1)), "D101")
        self.assertEqual(plc_adapter.fill_word("B", k4m.offset(1)), plc_adapter.fill_word("B", 7))
        case = plc_adapter.Case(habin_case(1, fill="B", flags={"SM705": True, "SM701": True},
                                           ignored_flags={"SM705": False}))
        self.assertEqual(case.read(plc_adapter.Device.parse("D100")), 0x4135)
        self.assertEqual(case.read(plc_adapter.Device.parse("D300")), plc_adapter.fill_word("B", 300))
        self.assertFalse(case.flag("SM705"))
        self.assertTrue(case.flag("SM701"))

    def test_a_byte_addressed_case_reads_bytes(self):
        device = plc_adapter.Device.parse("DB1.DBB10")
        self.assertEqual((device.code, device.index), ("DB1.DBB", 10))
        self.assertEqual(str(device.offset(1)), "DB1.DBB11")
        for bad in ("DB1.10", "db1.DBB10", "DB1.DBB"):
            with self.assertRaises(ValueError):
                plc_adapter.Device.parse(bad)
        message = habin_case(1, fill="B")
        message["memory"] = [{"start": "MB20", "bytes": [0x30, 0x41]}]
        case = plc_adapter.Case(message)
        self.assertEqual(case.read(plc_adapter.Device.parse("MB21")), 0x41)
        # A byte the case does not set holds the low byte of the word fill.
        self.assertEqual(case.read(plc_adapter.Device.parse("MB30")),
                         plc_adapter.fill_word("B", 30) & 0xFF)

    def test_a_case_of_32_bit_units_reads_dwords(self):
        message = habin_case(1, fill="B")
        message["memory"] = [{"start": "DW10", "dwords": [0x89ABCDEF, 0x31]}]
        case = plc_adapter.Case(message)
        self.assertEqual(case.read(plc_adapter.Device.parse("DW10")), 0x89ABCDEF)
        # A unit the case does not set: the word fill of its position low, eight on high.
        self.assertEqual(case.read(plc_adapter.Device.parse("DW3")),
                         plc_adapter.fill_word("B", 3) | plc_adapter.fill_word("B", 11) << 16)
        case.write(plc_adapter.Device.parse("DW30"), 0xFFFFFFFF)
        with self.assertRaises(ValueError):
            case.write(plc_adapter.Device.parse("DW31"), 0x100000000)

    def test_a_digit_designated_range_steps_sixteen_points(self):
        message = habin_case(1, fill="B")
        message["memory"] = [{"start": "K4M100", "words": [0x1234, 0x5678]}]
        case = plc_adapter.Case(message)
        self.assertEqual(case.read(plc_adapter.Device.parse("K4M116")), 0x5678)
        self.assertEqual(case.read(plc_adapter.Device.parse("K4M101")),
                         plc_adapter.fill_word("B", 6))
        self.assertEqual(case.read(plc_adapter.Device.parse("K4M132")),
                         plc_adapter.fill_word("B", 8))

    def test_a_hexadecimal_numbered_code_reads_steps_and_answers_in_hexadecimal(self):
        message = habin_case(1, hexadecimal=["W"], operands={"s": "W19", "d": "W1A"},
                             memory=[{"start": "W19", "words": [1, 2]}])
        case = plc_adapter.Case(message)
        self.assertEqual(str(case.device("s").offset(1)), "W1A")
        self.assertEqual(case.read(case.device("d")), 2)
        self.assertEqual(plc_adapter.Device.parse("W10", ["W"]).index, 16)
        self.assertEqual(plc_adapter.Device.parse("W10").index, 10)
        case.write(case.device("s").offset(7), 9)
        self.assertEqual(case.answer()["writes"], {"W20": 9})

    def test_module_buffer_memory_is_a_device(self):
        device = plc_adapter.Device.parse("U1\\G10")
        self.assertEqual((device.code, device.index), ("U1\\G", 10))
        self.assertEqual(str(device.offset(1)), "U1\\G11")

    def test_an_indirect_operand_is_the_device_its_pointer_addresses(self):
        message = habin_case(1, operands={"s": "@D10", "d": "D200"},
                             memory=[{"start": "D100", "words": [7]}])
        message["addresses"] = {"D10": "D100"}
        case = plc_adapter.Case(message)
        self.assertEqual(case.device("s"), plc_adapter.Device.parse("D100"))
        self.assertEqual(case.read(case.device("s")), 7)
        self.assertEqual(case.pointer("s"), plc_adapter.Device.parse("D10"))
        self.assertIsNone(case.pointer("d"))
        message["addresses"] = {}
        with self.assertRaises(ValueError):
            plc_adapter.Case(message).operand("s")


if __name__ == "__main__":
    unittest.main()


MODBUS = os.path.join(HERE, "..", "..", "..", "tests", "fixtures", "external", "modbus_ascii_codec.py")


def drive_script(script, args, messages):
    proc = subprocess.run(
        [sys.executable, script] + list(args),
        input="".join(json.dumps(m) + "\n" for m in messages),
        capture_output=True, text=True, timeout=30)
    return [json.loads(line) for line in proc.stdout.split("\n") if line], proc.stderr, proc.returncode


class ProtocolFields(unittest.TestCase):
    def test_hello_names_the_protocol_and_its_check_operations(self):
        answers, stderr, status = drive_script(MODBUS, ["strict"], [HELLO_2, SHUTDOWN])
        self.assertEqual(status, 0, stderr)
        codec = answers[0]["capabilities"]["codec"]
        self.assertEqual(codec["protocol"], "modbus-ascii")
        self.assertEqual(codec["check"], {})
        self.assertEqual(codec["verify"], {})
        self.assertNotIn("fields", codec)

    def test_check_and_verify_answer_text_accepted_and_bad_check(self):
        def case(ident, operation, text):
            return {"id": ident, "case": "c%d" % ident, "operation": operation,
                    "text": ascii_list(text), "digits": 2, "field": "lrc"}
        cases = [case(1, "check", "010304010001"), case(2, "verify", "010304010001F6"),
                 case(3, "verify", "010304010001F7"), case(4, "check", "01G3")]
        run = [HELLO_2, {"type": "run", "cases": cases}, SHUTDOWN]
        strict, stderr, status = drive_script(MODBUS, ["strict"], run)
        self.assertEqual(status, 0, stderr)
        self.assertEqual(strict[1:], [
            {"type": "result", "id": 1, "text": ascii_list("F6")},
            {"type": "result", "id": 2, "accepted": True},
            {"type": "result", "id": 3, "error": "bad-check"},
            {"type": "result", "id": 4, "error": "invalid-digit"},
        ])
        lax, _, _ = drive_script(MODBUS, ["never-compares"], run)
        self.assertEqual(lax[3], {"type": "result", "id": 3, "accepted": True})

    def test_protocol_arguments_without_a_protocol_are_refused(self):
        with self.assertRaises(TypeError):
            plc_adapter.serve_codec(check=lambda span: "00", name="x", version="1")
