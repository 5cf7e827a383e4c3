"""`python -m plc_conformance.codec`: the command line it builds from a pytest module's
codec_cases, without running the corpus (the wheel's check runs it for real)."""

import os
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "..", "python"))

from plc_conformance import codec as entry  # noqa: E402
from plc_conformance import pytest_cases  # noqa: E402

MODULE = '''
from plc_conformance.pytest_cases import codec_cases


def decode(text, digits):
    return int(text[:digits], 16)


def encode(value, digits):
    return "%0*X" % (digits, value)


test_strict = codec_cases(decode, encode, name="strict", digits=[4], timeout=2.5,
                          errors={ValueError: "invalid-digit"},
                          known_differences="strict.known.yaml")
'''


class CodecEntry(unittest.TestCase):
    def setUp(self):
        self.folder = tempfile.TemporaryDirectory(prefix="plc-conformance-")
        self.addCleanup(self.folder.cleanup)
        self.tests = os.path.join(self.folder.name, "test_strict.py")
        with open(self.tests, "w") as f:
            f.write(MODULE)
        pytest_cases.binary = lambda: "plc-conformance"

    def test_a_sweep_gets_the_codec_its_timeout_and_known_differences(self):
        line = entry.command(self.tests, "sweep", ["--generator", "full"])
        self.assertEqual(line[:4], ["plc-conformance", "sweep", "--generator", "full"])
        backend = line[line.index("--backend") + 1]
        self.assertTrue(backend.startswith("external:strict="), backend)
        self.assertIn("plc_conformance.serve", backend)
        self.assertEqual(line[line.index("--timeout") + 1], "2.5")
        known = line[line.index("--known-differences") + 1]
        self.assertEqual(known, "strict=" + os.path.join(self.folder.name, "strict.known.yaml"))

    def test_list_gets_the_codec_alone(self):
        line = entry.command(self.tests + ":test_strict", "list", [])
        self.assertIn("--backend", line)
        self.assertNotIn("--timeout", line)
        self.assertNotIn("--known-differences", line)

    def test_a_name_the_module_does_not_declare_is_refused_with_its_codecs(self):
        with self.assertRaises(entry.UsageError) as refused:
            entry.command(self.tests + ":test_other", "list", [])
        self.assertIn("its codecs: test_strict", str(refused.exception))

    def test_a_module_without_a_codec_is_refused(self):
        empty = os.path.join(self.folder.name, "test_empty.py")
        with open(empty, "w") as f:
            f.write("X = 1\n")
        with self.assertRaises(entry.UsageError) as refused:
            entry.command(empty, "list", [])
        self.assertIn("declares no codec", str(refused.exception))


if __name__ == "__main__":
    unittest.main()
