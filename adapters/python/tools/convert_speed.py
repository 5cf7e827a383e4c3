#!/usr/bin/env python3
"""How fast the Python helper answers protocol version 5 `convert` messages, against the bare
conversion: a timing script, not a test.

    python3 adapters/python/tools/convert_speed.py [--texts 100000] [--batch 4096]
                                                   [--alphabet hex|bytes] [--repeat 5]

It starts a codec in a child process through plc_adapter.serve_codec, with
decode=lambda t, d: int(t, 16), errors={ValueError: "invalid-digit"} and digits [4], sends it
the texts in `convert` messages of --batch texts each, as the harness does (the next message
written while the answers of the previous one are read), and times from the first message
written to the last answer read. The bare loop calls int(t, 16) on the same texts, as bytes, in
a plain Python loop (catching ValueError). Both are the best of --repeat runs.

--alphabet hex (the default): random texts of the 16 uppercase hex digits (every text
decodes); bytes: random bytes 00H-FFH (almost every text is refused: the cost of an exception
per item, on both sides).
"""

import argparse
import json
import os
import random
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))


def serve():
    import plc_adapter

    plc_adapter.serve_codec(decode=lambda t, d: int(t, 16), name="int16", version="1",
                            decode_digits=[4], errors={ValueError: "invalid-digit"})


def bare(texts):
    out = []
    append = out.append
    for t in texts:
        try:
            append(int(t, 16))
        except ValueError:
            append(None)
    return out


def helper(child, lines, expect):
    """Writes the messages (from a thread, as the harness keeps one queued) and reads the
    answers; returns (seconds, answers)."""
    def writer():
        for line in lines:
            child.stdin.write(line)
        child.stdin.flush()

    start = time.perf_counter()
    thread = threading.Thread(target=writer)
    thread.start()
    answers = [child.stdout.readline() for _ in range(expect)]
    seconds = time.perf_counter() - start
    thread.join()
    return seconds, answers


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--texts", type=int, default=100000)
    parser.add_argument("--batch", type=int, default=4096)
    parser.add_argument("--alphabet", choices=("hex", "bytes"), default="hex")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--serve", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.serve:
        return serve()

    rng = random.Random(5)
    alphabet = b"0123456789ABCDEF" if args.alphabet == "hex" else bytes(range(256))
    texts = [bytes(rng.choice(alphabet) for _ in range(4)) for _ in range(args.texts)]
    strings = [t.decode("latin-1") for t in texts]
    lines = []
    for ident, at in enumerate(range(0, len(strings), args.batch)):
        chunk = strings[at:at + args.batch]
        lines.append(json.dumps({"type": "convert", "id": ident, "operation": "hex-to-value",
                                 "digits": [4] * len(chunk), "texts": chunk}) + "\n")

    child = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--serve"],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                             encoding="utf-8")
    child.stdin.write(json.dumps({"type": "hello", "protocol": 5, "harness": "convert_speed"}) + "\n")
    child.stdin.flush()
    hello = json.loads(child.stdout.readline())
    assert hello["protocol"] == 5, hello

    expected = [{"error": "invalid-digit"} if v is None else v for v in bare(texts)]
    best_helper = best_bare = float("inf")
    for _ in range(args.repeat):
        seconds, answers = helper(child, lines, len(lines))
        best_helper = min(best_helper, seconds)
        got = [a for line in answers for a in json.loads(line)["answers"]]
        assert got == expected, "the helper's answers are not int(t, 16)'s"
        start = time.perf_counter()
        bare(texts)
        best_bare = min(best_bare, time.perf_counter() - start)
    child.stdin.write(json.dumps({"type": "shutdown"}) + "\n")
    child.stdin.close()
    child.wait()

    n = len(texts)
    print("%d texts (%s), convert messages of %d, best of %d" % (n, args.alphabet, args.batch, args.repeat))
    row = "%-36s %8.1f ms  %6.0f ns/text"
    print(row % ("helper (round trip, child process):", best_helper * 1e3, best_helper / n * 1e9))
    print(row % ("bare loop int(t, 16):", best_bare * 1e3, best_bare / n * 1e9))
    print("ratio helper / bare: %.2f" % (best_helper / best_bare))


if __name__ == "__main__":
    main()
