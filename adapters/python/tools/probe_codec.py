#!/usr/bin/env python3
"""Runs a codec-level backend over the cross-vendor corpus and prints what it answers.

    python3 adapters/python/tools/probe_codec.py [--vectors DIR] [--all] -- COMMAND...

COMMAND is the backend, e.g. `.venv-adapters/bin/python adapters/python/aslmp_codec.py` or
`node adapters/mcprotocol/mcprotocol_codec.js`. The probe speaks protocol version 2 to it,
sends every case of vectors/cross-vendor/*.yaml that its capabilities cover (digit counts and
width) and prints one line per case: the input, the backend's answer, the case's plain
expectation and, where the iQ-R manual rule gives another answer, what HABIN/BINHA with SM705
off gives. A line starts with "differs" when the answer is not the plain expectation. With
--all, cases outside the capabilities are sent too.

This is a look at the raw answers for writing a known-differences file; `plc-conformance run`
is the judge. Needs PyYAML (`pip install pyyaml`).
"""

import argparse
import json
import os
import subprocess
import sys

import yaml

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", ".."))
FIXED = {"hex-to-value": "iqr/habin-fixed", "value-to-hex": "iqr/binha-fixed"}


def number(v):
    """A corpus number: an int, or hex text ending in H."""
    if isinstance(v, int):
        return v
    return int(v[:-1], 16) if v.upper().endswith("H") else int(v)


def outcome(spec):
    """A corpus expectation as ("value", n) / ("text", bytes) / ("error", class)."""
    if spec is None:
        return None
    if "value" in spec:
        return ("value", number(spec["value"]))
    if "text" in spec:
        return ("text", spec["text"].encode("latin-1"))
    return ("error", spec["error"])


def shown(o):
    if o is None:
        return "(unspecified)"
    kind, v = o
    if kind == "value":
        return "%XH" % v if v >= 0 else "%d" % v
    if kind == "text":
        return json.dumps(v.decode("latin-1"))
    if kind == "unsupported":
        return "unsupported"
    return "error " + v


def answered(msg):
    if msg.get("type") == "unsupported":
        return ("unsupported", msg.get("reason"))
    if msg.get("error") is not None:
        return ("error", msg["error"])
    if "value" in msg:
        return ("value", msg["value"])
    text = bytes(msg["text"])
    return ("text", text.split(b"\0", 1)[0])


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--vectors", default=os.path.join(ROOT, "vectors", "cross-vendor"))
    p.add_argument("--all", action="store_true")
    p.add_argument("command", nargs="+")
    args = p.parse_args()

    backend = subprocess.Popen(args.command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)

    def send(msg):
        backend.stdin.write(json.dumps(msg) + "\n")
        backend.stdin.flush()

    send({"type": "hello", "protocol": 2, "harness": "probe_codec"})
    hello = json.loads(backend.stdout.readline())
    codec = hello["capabilities"]["codec"]
    print("# %s %s: %s" % (hello["backend"]["name"], hello["backend"]["version"], json.dumps(codec)))

    requests, rows = [], []
    for name in ("hex-to-value.yaml", "value-to-hex.yaml"):
        with open(os.path.join(args.vectors, name), encoding="utf-8") as f:
            doc = yaml.safe_load(f)
        op = doc["operation"]
        for case in doc["cases"]:
            expect = outcome(case.get("expect"))
            fixed = outcome((case.get("except") or {}).get(FIXED[op]))
            cap = codec.get(op)
            digits = case["digits"]
            skip = None
            if cap is None:
                skip = "%s not implemented" % op
            elif "digits" in cap and digits not in cap["digits"]:
                skip = "digits %d not implemented" % digits
            else:
                limit = 1 << cap.get("width", 16)
                if op == "hex-to-value" and expect and expect[0] == "value" and expect[1] >= limit:
                    skip = "expected value wider than %d bits" % cap.get("width", 16)
                if op == "value-to-hex" and number(case["value"]) >= limit:
                    skip = "value wider than %d bits" % cap.get("width", 16)
            req = {"id": len(rows) + 1, "case": case["id"], "operation": op, "digits": digits}
            if op == "hex-to-value":
                req["text"] = list(case["text"].encode("latin-1"))
                given = json.dumps(case["text"])
            else:
                req["value"] = number(case["value"])
                given = "%XH" % req["value"]
            rows.append((case["id"], digits, given, expect, fixed, skip, req["id"]))
            if skip is None or args.all:
                requests.append(req)

    send({"type": "run", "cases": requests})
    answers = {}
    for req in requests:
        line = backend.stdout.readline()
        if not line:
            print("backend ended (status %s) at case %s" % (backend.wait(), req["case"]))
            return 1
        answers[req["id"]] = answered(json.loads(line))
    send({"type": "shutdown"})
    backend.stdin.close()
    backend.wait(timeout=5)

    for case_id, digits, given, expect, fixed, skip, ident in rows:
        got = answers.get(ident)
        if got is None:
            print("skipped  %-28s %-2d %-20s (%s)" % (case_id, digits, given, skip))
            continue
        mark = "ok" if got == expect else ("unspec" if expect is None else "differs")
        extra = "" if fixed is None else "  [SM705-off rule: %s%s]" % (
            shown(fixed), ", matches" if got == fixed else "")
        print("%-8s %-28s %-2d %-20s -> %-18s expected %s%s%s" % (
            mark, case_id, digits, given, shown(got), shown(expect), extra,
            "  (outside capabilities: %s)" % skip if skip else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
