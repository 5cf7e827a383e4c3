#!/usr/bin/env python3
"""A codec whose decode is one line, `int(text, 16)`: what the harness costs a Python codec is
measured against it. Run as a script it serves the codec; `--bare FILE` instead times the bare
loop over the texts in FILE (one `HEX DIGITS` line each: the text's bytes in hex) and prints the
seconds."""

import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "adapters", "python"))


def decode(text, digits):
    return int(text, 16)


def bare(path):
    with open(path) as f:
        items = [(bytes.fromhex(h), int(d)) for h, d in (line.split() for line in f)]
    answers = []
    started = time.perf_counter()
    for text, digits in items:
        try:
            answers.append(decode(text, digits))
        except ValueError:
            answers.append("invalid-digit")
    print("%.6f" % (time.perf_counter() - started))


if __name__ == "__main__":
    if sys.argv[1:2] == ["--bare"]:
        bare(sys.argv[2])
    else:
        import plc_adapter  # noqa: E402
        plc_adapter.serve_codec(decode=decode, name="int", version="1", width=32,
                                errors={ValueError: "invalid-digit"})
