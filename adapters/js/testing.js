'use strict';
// One `node --test` test per cross-vendor case for a codec adapter script:
//
//   // test/conformance.test.js
//   const path = require('node:path');
const { findBinary } = require('./binary');
//   const { codecCases } = require('plc-conformance-adapter/testing');
//   codecCases({ name: 'mylib', adapter: path.join(__dirname, '../mylib_codec.js'),
//                knownDifferences: path.join(__dirname, '../mylib.known.yaml') });
//
// The adapter is the script serveCodec runs (docs/check-your-library.md). The `plc-conformance`
// command — $PLC_CONFORMANCE, else the one this package carries (a package made by
// tools/pack.js), else the one on PATH (the Python wheel installs one) — runs the
// cross-vendor corpus against it once, when the test file loads; each case is then a test:
// passing, failing with the harness's diff, skipped with the reason, or a todo where the
// known-differences file names the case. A harness that cannot run the adapter at all is an
// error when the file loads, never a pass.
const assert = require('node:assert');
const { spawnSync } = require('node:child_process');
const fs = require('node:fs');
const os = require('node:os');
const path = require('node:path');

/** A word for `sh -c`, whatever it holds. */
function quote(word) {
  return `'${String(word).replace(/'/g, "'\\''")}'`;
}

/**
 * @param {{name: string, adapter: string, knownDifferences?: string, binary?: string,
 *          timeout?: number}} options
 */
function codecCases({ name, adapter, knownDifferences, binary, timeout = 5 }) {
  const { test } = require('node:test');
  if (!name || !adapter) throw new TypeError('codecCases: give name and adapter (a script path)');
  const command = [process.execPath, path.resolve(adapter)].map(quote).join(' ');
  const bin = binary || findBinary();
  if (!bin) {
    throw new Error('codecCases: no plc-conformance command: this package carries none for '
      + `${process.platform}-${process.arch}, PLC_CONFORMANCE is not set and none is on PATH`);
  }
  const folder = fs.mkdtempSync(path.join(os.tmpdir(), 'plc-conformance-'));
  let records;
  try {
    const output = path.join(folder, 'results.json');
    const args = ['run', '--backend', `external:${name}=${command}`, '--timeout', String(timeout),
      '--format', 'json', '--output', output];
    if (knownDifferences) args.push('--known-differences', `${name}=${path.resolve(knownDifferences)}`);
    // Away from any project folder: the corpus is the one built into the command.
    const done = spawnSync(bin, args, { cwd: folder, encoding: 'utf8' });
    if (done.error || ![0, 1].includes(done.status) || !fs.existsSync(output)) {
      throw new Error(`plc-conformance (${bin}) could not run ${name} (exit status ${done.status}): `
        + `${done.error ? done.error.message : done.stderr.trim()}`);
    }
    records = JSON.parse(fs.readFileSync(output, 'utf8')).records
      .filter((r) => r.column.split('/')[0] === name);
  } finally {
    fs.rmSync(folder, { recursive: true, force: true });
  }
  if (records.length === 0) throw new Error(`plc-conformance ran no case of ${name}`);
  for (const record of records) {
    test(record.row, (t) => {
      if (record.status === 'fail') assert.fail(record.detail);
      if (record.label === 'known-difference') return t.todo(record.detail);
      if (record.status === 'skipped') return t.skip(record.detail);
      if (record.status === 'ignored') return t.skip(`not judged (the manuals leave it open): ${record.shown}`);
      return undefined;
    });
  }
  return records;
}

module.exports = { codecCases };
