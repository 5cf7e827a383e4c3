"""Protocol version 5 in the Python helper: the `convert` message (many conversions of one
operation, answered by one `converted` line), and the field shapes per direction
(decode_field=, encode_field=, blanks_between_pairs).

    python3 -m unittest discover adapters/python/tests

Each batch is also asked as `run` cases, one by one, and every item must answer what its case
answers: the batch is a faster path to the same answers, never other ones.
"""

import io
import json
import os
import random
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))

import plc_adapter  # noqa: E402

# The fixtures are driven as test_plc_adapter.py drives them.
from test_plc_adapter import HELLO_2, SHUTDOWN, drive  # noqa: E402

HELLO_5 = {"type": "hello", "protocol": 5, "harness": "plc-conformance 0.5.0"}


def h2v_batch(ident, texts, digits):
    return {"type": "convert", "id": ident, "operation": "hex-to-value",
            "digits": list(digits), "texts": list(texts)}


def v2h_batch(ident, values, digits):
    return {"type": "convert", "id": ident, "operation": "value-to-hex",
            "digits": list(digits), "values": list(values)}


def as_cases(batch, first_id):
    """The batch's items as `run` cases, ids from first_id on."""
    cases = []
    for k, d in enumerate(batch["digits"]):
        case = {"id": first_id + k, "case": "c%d" % k, "operation": batch["operation"], "digits": d}
        if batch["operation"] == "hex-to-value":
            case["text"] = list(batch["texts"][k].encode("latin-1"))
        else:
            case["value"] = batch["values"][k]
        cases.append(case)
    return cases


def as_item(answer):
    """A `run` answer as the item of a `converted` line says the same."""
    if answer["type"] == "unsupported":
        return {"unsupported": answer["reason"]}
    if "error" in answer:
        return {"error": answer["error"]}
    if "value" in answer:
        return answer["value"]
    return bytes(answer["text"]).decode("latin-1")


def serve(messages, **options):
    """serve_codec in this process; returns the answers."""
    out = io.StringIO()
    plc_adapter.serve_codec(stdin=io.StringIO("".join(json.dumps(m) + "\n" for m in messages)),
                            stdout=out, **options)
    return [json.loads(line) for line in out.getvalue().splitlines()]


class Handshake(unittest.TestCase):
    def test_a_codec_answers_5_to_a_harness_of_5_and_2_to_older_ones(self):
        self.assertIn(5, plc_adapter.PROTOCOL_VERSIONS)
        for asked, answered in ((5, 5), (9, 5), (4, 2), (3, 2), (2, 2)):
            answers, _, status = drive("codec.py", ["strict"], [dict(HELLO_5, protocol=asked), SHUTDOWN])
            self.assertEqual(status, 0)
            self.assertEqual(answers[0]["protocol"], answered, "asked %d" % asked)
            self.assertEqual(answers[0]["capabilities"]["codec"]["hex-to-value"], {"width": 32, "digits": [4, 8]})


class Convert(unittest.TestCase):
    def assertSameAsRun(self, fixture, args, batch):
        """The batch's answers are the `run` answers of its items; returns them."""
        converted, stderr, status = drive(fixture, args, [HELLO_5, batch, SHUTDOWN])
        self.assertEqual(status, 0, stderr)
        self.assertEqual(len(converted), 2, converted)
        self.assertEqual(set(converted[1]), {"type", "id", "answers"})
        self.assertEqual((converted[1]["type"], converted[1]["id"]), ("converted", batch["id"]))
        run, stderr, status = drive(fixture, args, [HELLO_2, {"type": "run", "cases": as_cases(batch, 1)}, SHUTDOWN])
        self.assertEqual(status, 0, stderr)
        self.assertEqual(converted[1]["answers"], [as_item(a) for a in run[1:]])
        return converted[1]["answers"]

    def test_hex_to_value_values_errors_and_unsupported_in_order(self):
        batch = h2v_batch(12, ["5A8D", "5a8D", "5A\u00e9D", "7F", "12345678", "DEAD", "\u00e9\u00e9\u00e9\u00e9"],
                          [4, 4, 4, 2, 8, 4, 4])
        self.assertEqual(self.assertSameAsRun("codec.py", ["strict"], batch), [
            0x5A8D,
            {"error": "invalid-digit"},  # lowercase: BadDigit, mapped
            {"error": "invalid-digit"},  # E9H
            {"unsupported": "hex-to-value with 2 digits is not implemented"},
            0x12345678,
            0xDEAD,
            {"error": "invalid-digit"},
        ])

    def test_every_declared_count_and_mapped_errors_between_values(self):
        # All counts declared: the map() path, then item by item after the first exception.
        batch = h2v_batch(3, ["0001", "5a8D", "0002", " 5A8", "0003", "FFFF"], [4] * 6)
        self.assertEqual(self.assertSameAsRun("codec.py", ["strict"], batch),
                         [1, {"error": "invalid-digit"}, 2, {"error": "invalid-digit"}, 3, 0xFFFF])
        # The deliberately wrong codec: int() takes lowercase and blanks; "5A\u00e9D" is a
        # ValueError that is no BadDigit, mapped to "error".
        batch = h2v_batch(4, ["5a8D", " 5A8", "5A\u00e9D", "0001"], [4] * 4)
        self.assertEqual(self.assertSameAsRun("codec.py", ["lowercase"], batch),
                         [0x5A8D, 0x5A8, {"error": "error"}, 1])

    def test_random_texts_answer_as_their_cases(self):
        rng = random.Random(7)
        alphabet = "0123456789ABCDEFabcdef +-_x\u00e9\u00ff\0\t"
        texts = ["".join(rng.choice(alphabet) for _ in range(rng.choice((2, 4, 4, 4, 8, 9))))
                 for _ in range(300)]
        digits = [rng.choice((4, 4, 4, 8, 2, 3)) for _ in texts]
        for mode in ("strict", "lowercase"):
            self.assertSameAsRun("codec.py", [mode], h2v_batch(1, texts, digits))
            self.assertSameAsRun("codec.py", [mode], h2v_batch(2, texts, [4] * len(texts)))

    def test_value_to_hex_texts_and_values_wider_than_the_width(self):
        batch = v2h_batch(13, [23181, 0, 0x12345678, 1 << 32, 5, 0xFFFFFFFF], [4, 4, 4, 8, 2, 8])
        self.assertEqual(self.assertSameAsRun("codec.py", ["strict"], batch), [
            "5A8D", "0000", "5678",
            {"unsupported": "4294967296 is wider than 32 bits"},
            {"unsupported": "value-to-hex with 2 digits is not implemented"},
            "FFFFFFFF",
        ])

    def test_an_unmapped_exception_ends_the_process_with_no_converted_line(self):
        for texts in (["5A8D", "DEAD", "BEEF"], ["DEAD"], ["5a8D", "0001", "DEAD", "BEEF"]):
            answers, stderr, status = drive("codec.py", ["crash"], [HELLO_5, h2v_batch(1, texts, [4] * len(texts)), SHUTDOWN])
            self.assertNotEqual(status, 0)
            self.assertEqual([a["type"] for a in answers], ["hello"], texts)
            self.assertIn("Traceback", stderr)
            self.assertIn("deliberate crash on DEAD", stderr)

    def test_run_still_answers_one_case_at_a_time_after_convert(self):
        answers, stderr, status = drive("codec.py", ["strict"], [
            HELLO_5, h2v_batch(1, ["5A8D"], [4]),
            {"type": "run", "cases": [{"id": 2, "case": "x", "operation": "hex-to-value", "text": list(b"5A8D"), "digits": 4}]},
            SHUTDOWN])
        self.assertEqual(status, 0, stderr)
        self.assertEqual(answers[1:], [{"type": "converted", "id": 1, "answers": [0x5A8D]},
                                       {"type": "result", "id": 2, "value": 0x5A8D}])


class ConvertInProcess(unittest.TestCase):
    def test_texts_arrive_as_their_bytes_one_per_character(self):
        answers = serve([HELLO_5, h2v_batch(1, ["5A\u00e9D", "\u00ff", "\0A", ""], [4, 4, 4, 4]), SHUTDOWN],
                        decode=lambda t, d: int.from_bytes(t, "big") | len(t) << 40, name="x", version="1")
        self.assertEqual(answers[1]["answers"], [0x3541E944 | 4 << 40, 0xFF | 1 << 40, 0x41 | 2 << 40, 0])
        # With no 00H among them the texts take the one-encode path: the same bytes.
        answers = serve([HELLO_5, h2v_batch(1, ["5A\u00e9D", "\u00ff"], [4, 4]), SHUTDOWN],
                        decode=lambda t, d: int.from_bytes(t, "big") | len(t) << 40, name="x", version="1")
        self.assertEqual(answers[1]["answers"], [0x3541E944 | 4 << 40, 0xFF | 1 << 40])

    def test_texts_arrive_as_their_bytes_among_counts_not_declared(self):
        answers = serve([HELLO_5, h2v_batch(1, ["5A\u00e9D", "\u00ff", "5A\u00e9D"], [4, 2, 4]), SHUTDOWN],
                        decode=lambda t, d: int.from_bytes(t, "big") | len(t) << 40, name="x", version="1",
                        decode_digits=[4])
        self.assertEqual(answers[1]["answers"], [0x3541E944 | 4 << 40,
                                                 {"unsupported": "hex-to-value with 2 digits is not implemented"},
                                                 0x3541E944 | 4 << 40])

    def test_each_codec_error_answers_its_own_class(self):
        classes = {b"CNT!": "invalid-count", b"DIG!": "invalid-digit", b"RNG!": "device-range"}

        def decode(text, digits):
            if text in classes:
                raise plc_adapter.CodecError(classes[text])
            return 1

        texts = ["DIG!", "CNT!", "AAAA", "RNG!", "DIG!", "CNT!"]
        answers = serve([HELLO_5, h2v_batch(1, texts, [4] * len(texts)), SHUTDOWN], decode=decode, name="x", version="1")
        self.assertEqual(answers[1]["answers"], [{"error": "invalid-digit"}, {"error": "invalid-count"}, 1,
                                                 {"error": "device-range"}, {"error": "invalid-digit"},
                                                 {"error": "invalid-count"}])

    def test_what_encode_returns_after_an_error_is_converted_as_before_it(self):
        returns = {2: b"\xe9A", 3: "\u00e9", 4: "0A", 5: [0x80], 6: 7}

        def encode(value, digits):
            if value == 1:
                raise ValueError("first")
            return returns[value]

        answers = serve([HELLO_5, v2h_batch(1, [1, 2, 3, 4, 5, 6], [4] * 6), SHUTDOWN], encode=encode,
                        name="x", version="1", errors={ValueError: "error", TypeError: "invalid-count"})
        self.assertEqual(answers[1]["answers"], [{"error": "error"}, "\u00e9A", "\u00c3\u00a9", "0A", "\x80",
                                                 {"error": "invalid-count"}])

    def test_written_bytes_come_back_one_character_per_byte(self):
        texts = {1: b"\xe9A", 2: "\u00e9", 3: bytearray(b"\x00\x7f"), 4: [0x80, 0x41], 5: "0ABC", 6: memoryview(b"12")}
        answers = serve([HELLO_5, v2h_batch(1, list(texts), [4] * len(texts)), SHUTDOWN],
                        encode=lambda v, d: texts[v], name="x", version="1")
        # A str is written as its UTF-8 bytes, as the run path writes it: "\u00e9" is C3H A9H.
        self.assertEqual(answers[1]["answers"], ["\u00e9A", "\u00c3\u00a9", "\0\x7f", "\x80A", "0ABC", "12"])
        answers = serve([HELLO_5, v2h_batch(1, [1, 1], [4, 4]), SHUTDOWN],
                        encode=lambda v, d: b"\xe9\xe9", name="x", version="1")
        self.assertEqual(answers[1]["answers"], ["\u00e9\u00e9", "\u00e9\u00e9"])
        # Only strings: "\u00e9" is still written as its UTF-8 bytes.
        answers = serve([HELLO_5, v2h_batch(1, [1, 2], [4, 4]), SHUTDOWN],
                        encode=lambda v, d: ["0A", "\u00e9"][v - 1], name="x", version="1")
        self.assertEqual(answers[1]["answers"], ["0A", "\u00c3\u00a9"])

    def test_a_value_wider_than_its_width_is_not_asked(self):
        asked = []

        def encode(value, digits):
            asked.append(value)
            return "%0*X" % (digits, value)

        answers = serve([HELLO_5, v2h_batch(1, [0x7F, 0x100, 0xFFFF, 0x10000], [2, 2, 4, 4]), SHUTDOWN],
                        encode=encode, name="x", version="1", field={"widths": {2: 8, 4: 16}})
        self.assertEqual(answers[1]["answers"], ["7F", {"unsupported": "256 is wider than 8 bits"}, "FFFF",
                                                 {"unsupported": "65536 is wider than 16 bits"}])
        self.assertEqual(asked, [0x7F, 0xFFFF])

    def test_codec_error_unsupported_and_what_decode_returns_answer_as_in_run(self):
        def decode(text, digits):
            return {b"AAAA": 1, b"BOOL": True, b"STR!": "12", b"FLT!": 1.0, b"DICT": {"error": "x"}}.get(text) \
                if text != b"CNT!" and text != b"UNS!" else \
                (_ for _ in ()).throw(plc_adapter.CodecError("invalid-count") if text == b"CNT!"
                                      else plc_adapter.Unsupported("not this one"))

        texts = ["AAAA", "CNT!", "UNS!", "AAAA", "BOOL", "STR!", "FLT!", "DICT", "AAAA"]
        batch = h2v_batch(1, texts, [4] * len(texts))
        options = dict(decode=decode, name="x", version="1", errors={TypeError: "error"})
        converted = serve([HELLO_5, batch, SHUTDOWN], **options)
        run = serve([HELLO_2, {"type": "run", "cases": as_cases(batch, 1)}, SHUTDOWN], **options)
        self.assertEqual(converted[1]["answers"], [as_item(a) for a in run[1:]])
        self.assertEqual(converted[1]["answers"], [
            1, {"error": "invalid-count"}, {"unsupported": "not this one"}, 1,
            {"error": "error"}, {"error": "error"}, {"error": "error"}, {"error": "error"}, 1])
        # Not mapped, a return that is not an int ends the process (here: serve_codec raises).
        for text in ("STR!", "BOOL"):
            with self.assertRaisesRegex(TypeError, "decode must return an int"):
                serve([HELLO_5, h2v_batch(1, ["AAAA", text], [4, 4]), SHUTDOWN], decode=decode, name="x", version="1")

    def test_what_encode_returns_answers_as_in_run(self):
        returns = {1: "0001", 2: 7, 3: [300], 4: b"0004"}
        batch = v2h_batch(1, [1, 2, 3, 4], [4] * 4)
        options = dict(encode=lambda v, d: returns[v], name="x", version="1", errors={TypeError: "error"})
        converted = serve([HELLO_5, batch, SHUTDOWN], **options)
        run = serve([HELLO_2, {"type": "run", "cases": as_cases(batch, 1)}, SHUTDOWN], **options)
        self.assertEqual(converted[1]["answers"], [as_item(a) for a in run[1:]])
        self.assertEqual(converted[1]["answers"], ["0001", {"error": "error"}, {"error": "error"}, "0004"])
        with self.assertRaisesRegex(TypeError, "encode must return bytes or str"):
            serve([HELLO_5, batch, SHUTDOWN], encode=lambda v, d: returns[v], name="x", version="1")

    def test_each_direction_maps_its_own_errors_in_a_batch(self):
        def fail(*_):
            raise ValueError("no")

        answers = serve([HELLO_5, h2v_batch(1, ["5A8D"], [4]), v2h_batch(2, [1], [4]), SHUTDOWN],
                        decode=fail, encode=fail, name="x", version="1",
                        errors={ValueError: "error"}, decode_errors={ValueError: "invalid-digit"})
        self.assertEqual([a["answers"] for a in answers[1:]], [[{"error": "invalid-digit"}], [{"error": "error"}]])

    def test_an_operation_not_implemented_is_unsupported_for_every_item(self):
        answers = serve([HELLO_5, v2h_batch(7, [1, 2], [4, 4]), SHUTDOWN], decode=lambda t, d: 0, name="x", version="1")
        self.assertEqual(answers[1], {"type": "converted", "id": 7, "answers": [
            {"unsupported": "value-to-hex is not implemented by x"}] * 2})

    def test_the_answer_is_one_compact_line(self):
        out = io.StringIO()
        plc_adapter.serve_codec(stdin=io.StringIO(json.dumps(HELLO_5) + "\n" + json.dumps(h2v_batch(3, ["01", "0G"], [2, 2])) + "\n"),
                                stdout=out, decode=lambda t, d: int(t, 16), name="x", version="1",
                                errors={ValueError: "invalid-digit"})
        self.assertEqual(out.getvalue().splitlines()[1],
                         '{"type":"converted","id":3,"answers":[1,{"error":"invalid-digit"}]}')


class FieldShapes(unittest.TestCase):
    def hello(self, **options):
        return serve([HELLO_5, SHUTDOWN], name="x", version="1", **options)[0]["capabilities"]["codec"]

    def test_each_direction_declares_its_own_field(self):
        codec = self.hello(decode=lambda t, d: 0, encode=lambda v, d: "0",
                           field={"whole_frame": True},
                           decode_field={"byte_order": "low-first", "blanks_between_pairs": True},
                           encode_field={"leading_zeros": False})
        self.assertEqual(codec, {
            "hex-to-value": {"width": 16, "byte-order": "low-first", "blanks-between-pairs": True},
            "value-to-hex": {"width": 16, "leading-zeros": False},
        })
        # `field` still serves a direction that gives no field of its own.
        codec = self.hello(decode=lambda t, d: 0, encode=lambda v, d: "0",
                           field={"whole_frame": True}, decode_field={"byte_order": "low-first"})
        self.assertEqual(codec["value-to-hex"], {"width": 16, "whole-frame": True})
        self.assertEqual(codec["hex-to-value"], {"width": 16, "byte-order": "low-first"})

    def test_blanks_between_pairs_is_a_shape_of_hex_to_value(self):
        self.assertEqual(self.hello(decode=lambda t, d: 0, field={"blanks_between_pairs": True}),
                         {"hex-to-value": {"width": 16, "blanks-between-pairs": True}})
        for options in ({"encode_field": {"blanks_between_pairs": True}},
                        {"field": {"blanks_between_pairs": True}}):
            with self.assertRaisesRegex(ValueError, "blanks_between_pairs.*hex-to-value only"):
                plc_adapter.serve_codec(decode=lambda t, d: 0, encode=lambda v, d: "0", name="x",
                                        version="1", **options)

    def test_a_field_is_checked_as_field_is(self):
        for options in ({"decode_field": {"order": "low"}}, {"encode_field": {"byte_order": "middle"}},
                        {"decode_field": {"widths": {2: 12}}}):
            with self.assertRaises(ValueError):
                plc_adapter.serve_codec(decode=lambda t, d: 0, encode=lambda v, d: "0", name="x",
                                        version="1", **options)
        with self.assertRaisesRegex(TypeError, "decode_field"):
            plc_adapter.serve_codec(encode=lambda v, d: "0", name="x", version="1",
                                    decode_field={"byte_order": "low-first"})


if __name__ == "__main__":
    unittest.main()
