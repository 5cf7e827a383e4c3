'use strict';
// Where the helper and `npx plc-conformance` find the command: $PLC_CONFORMANCE, the one the
// package carries for this platform, then PATH without the package's own script.
const assert = require('node:assert');
const fs = require('node:fs');
const os = require('node:os');
const path = require('node:path');
const { test } = require('node:test');

const source = path.join(__dirname, '..');

/** A copy of the package, optionally carrying a command for this platform. */
function copy(carrying) {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plc-binary-'));
  for (const f of ['binary.js', 'bin']) fs.cpSync(path.join(source, f), path.join(dir, f), { recursive: true });
  if (carrying) {
    const vendor = path.join(dir, 'vendor', `${process.platform}-${process.arch}`);
    fs.mkdirSync(vendor, { recursive: true });
    fs.writeFileSync(path.join(vendor, 'plc-conformance'), '#!/bin/sh\n', { mode: 0o755 });
  }
  return dir;
}

function withEnv(env, body) {
  const saved = { PATH: process.env.PATH, PLC_CONFORMANCE: process.env.PLC_CONFORMANCE };
  try {
    for (const [k, v] of Object.entries(env)) {
      if (v === undefined) delete process.env[k];
      else process.env[k] = v;
    }
    return body();
  } finally {
    for (const [k, v] of Object.entries(saved)) {
      if (v === undefined) delete process.env[k];
      else process.env[k] = v;
    }
  }
}

test('$PLC_CONFORMANCE comes first', () => {
  const dir = copy(true);
  const { findBinary } = require(path.join(dir, 'binary.js'));
  assert.strictEqual(withEnv({ PLC_CONFORMANCE: '/opt/x/plc-conformance' }, findBinary), '/opt/x/plc-conformance');
});

test('the command the package carries comes before PATH', () => {
  const dir = copy(true);
  const { findBinary } = require(path.join(dir, 'binary.js'));
  const found = withEnv({ PLC_CONFORMANCE: undefined, PATH: '/usr/bin:/bin' }, findBinary);
  assert.strictEqual(found, path.join(dir, 'vendor', `${process.platform}-${process.arch}`, 'plc-conformance'));
});

test('on PATH, the package\'s own script is passed over', () => {
  const dir = copy(false);
  const { findBinary } = require(path.join(dir, 'binary.js'));
  const shims = fs.mkdtempSync(path.join(os.tmpdir(), 'plc-bin-'));
  fs.symlinkSync(path.join(dir, 'bin', 'plc-conformance.js'), path.join(shims, 'plc-conformance'));
  const real = fs.mkdtempSync(path.join(os.tmpdir(), 'plc-real-'));
  fs.writeFileSync(path.join(real, 'plc-conformance'), '#!/bin/sh\n', { mode: 0o755 });
  const env = { PLC_CONFORMANCE: undefined };
  assert.strictEqual(withEnv({ ...env, PATH: `${shims}:${real}` }, findBinary), path.join(real, 'plc-conformance'));
  assert.strictEqual(withEnv({ ...env, PATH: shims }, findBinary), null);
});
