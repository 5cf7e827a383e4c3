#!/usr/bin/env bash
# What a test runner that starts one process per trial (cargo nextest) pays: the time to run one
# trial alone in a fresh process (the conformance binary of a debug build, as nextest runs it,
# with `--exact NAME`), and the wall time of `cargo nextest run` against `cargo test` over the
# whole suite. Figures: docs/performance.md. Usage: benches/per-trial.sh [ROUNDS]
set -euo pipefail
cd "$(dirname "$0")/.."
rounds=${1:-31}
cargo test --no-run --quiet
bin=$(cargo test --no-run --message-format=json --test conformance 2>/dev/null \
  | python3 -c 'import json,sys
for l in sys.stdin:
    m=json.loads(l)
    if m.get("reason")=="compiler-artifact" and m["target"]["name"]=="conformance" and m.get("executable"):
        print(m["executable"])')
echo "conformance binary: $bin"
python3 - "$bin" "$rounds" <<'PY'
import statistics, subprocess, sys, time
binary, rounds = sys.argv[1], int(sys.argv[2])
for name in [
    "iqr::habin::habin-fixed-4-digits-example::rcpu",
    "fx5::asci::asci-16bit-sm701-on-k1::fx5u",
    "cross-vendor::fc4a::atoh::xv-h2v-4-digits::c10r2",
]:
    times = []
    for _ in range(rounds):
        start = time.perf_counter()
        out = subprocess.run([binary, "--exact", name], capture_output=True, text=True)
        times.append(time.perf_counter() - start)
        if "1 passed" not in out.stdout:
            sys.exit(f"{name} did not pass alone:\n{out.stdout}{out.stderr}")
    print(f"one trial alone: {name}: median {statistics.median(times)*1000:.1f} ms, "
          f"min {min(times)*1000:.1f} ms over {rounds} runs")
PY
if command -v cargo-nextest >/dev/null 2>&1; then
  cargo nextest run --no-run >/dev/null 2>&1 || true
  t0=$(date +%s.%N); cargo test --quiet >/dev/null 2>&1; t1=$(date +%s.%N)
  cargo nextest run >/dev/null 2>&1; t2=$(date +%s.%N)
  python3 -c "t,n=$t1-$t0,$t2-$t1; print(f'cargo test: {t:.1f} s; cargo nextest run: {n:.1f} s; ratio {n/t:.1f}x')"
else
  echo "cargo-nextest is not installed: the suite comparison is left out"
fi
