'use strict';
// One `node --test` test per cross-vendor case for a codec adapter script:
//
//   // test/conformance.test.js
//   const path = require('node:path');
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
//
// The same test file gives the codec every other command, with no second entry point:
// `npx plc-conformance-codec test/conformance.test.js sweep --operation hex-to-value ...` (also
// `record`, `list`, `diff`, `run`), with the name, timeout and known differences codecCases got.
const assert = require('node:assert');
const { spawnSync } = require('node:child_process');
const fs = require('node:fs');
const os = require('node:os');
const path = require('node:path');
const { findBinary } = require('./binary');

// Set by plc-conformance-codec: the test file is loaded for its codecs only, and codecCases
// records each instead of running the corpus.
const DESCRIBING = 'PLC_CONFORMANCE_DESCRIBING_CODEC';
const described = [];
// The commands that take each option, as `plc-conformance COMMAND --help` lists them.
const TAKES_TIMEOUT = new Set(['run', 'diff', 'sweep', 'record']);
const TAKES_KNOWN_DIFFERENCES = new Set(['run', 'diff', 'sweep']);

/** A word for `sh -c`, whatever it holds. */
function quote(word) {
  return `'${String(word).replace(/'/g, "'\\''")}'`;
}

/**
 * @param {{name: string, adapter: string, knownDifferences?: string, binary?: string,
 *          timeout?: number}} options
 */
function codecCases({ name, adapter, knownDifferences, binary, timeout = 5 }) {
  if (!name || !adapter) throw new TypeError('codecCases: give name and adapter (a script path)');
  const command = [process.execPath, path.resolve(adapter)].map(quote).join(' ');
  const codec = {
    name,
    backend: `external:${name}=${command}`,
    timeout,
    knownDifferences: knownDifferences ? path.resolve(knownDifferences) : null,
  };
  if (process.env[DESCRIBING]) {
    described.push(codec);
    return [];
  }
  const { test } = require('node:test');
  const bin = binary || findBinary();
  if (!bin) {
    throw new Error('codecCases: no plc-conformance command: this package carries none for '
      + `${process.platform}-${process.arch}, PLC_CONFORMANCE is not set and none is on PATH`);
  }
  const folder = fs.mkdtempSync(path.join(os.tmpdir(), 'plc-conformance-'));
  let records;
  try {
    const output = path.join(folder, 'results.json');
    const args = commandLine(codec, 'run', ['--format', 'json', '--output', output]);
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

/**
 * The plc-conformance command line that runs `subcommand` (with its own `args`) on the codec the
 * test file declares with codecCases (`name` picks one when it declares several); throws an
 * Error saying what is wrong otherwise.
 */
function codecCommand(testFile, subcommand, args, name) {
  if (!fs.existsSync(testFile)) throw new Error(`no test file ${testFile}`);
  process.env[DESCRIBING] = '1';
  described.length = 0;
  const file = path.resolve(testFile);
  delete require.cache[file];
  require(file);
  const codecs = [...described];
  if (codecs.length === 0) throw new Error(`${testFile} declares no codec: call codecCases(...)`);
  let codec;
  if (name) {
    codec = codecs.find((c) => c.name === name);
    if (!codec) throw new Error(`${testFile} has no codec ${name}; its codecs: ${codecs.map((c) => c.name).join(', ')}`);
  } else if (codecs.length === 1) {
    [codec] = codecs;
  } else {
    throw new Error(`${testFile} declares ${codecs.length} codecs: name one with --codec NAME (${codecs.map((c) => c.name).join(', ')})`);
  }
  return commandLine(codec, subcommand, args);
}

/** The arguments that run `subcommand` (with its own `args`) on `codec` as codecCases describes
 * it: the codec as the backend, its timeout and known differences where the command takes them. */
function commandLine(codec, subcommand, args) {
  const line = [subcommand, ...args, '--backend', codec.backend];
  if (TAKES_TIMEOUT.has(subcommand)) line.push('--timeout', String(codec.timeout));
  if (TAKES_KNOWN_DIFFERENCES.has(subcommand) && codec.knownDifferences) {
    line.push('--known-differences', `${codec.name}=${codec.knownDifferences}`);
  }
  return line;
}

module.exports = { codecCases, codecCommand };
