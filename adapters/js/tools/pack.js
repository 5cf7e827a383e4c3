#!/usr/bin/env node
'use strict';
// Makes the npm package with the plc-conformance command in it, so that `npm install` of it
// gives the helper, `npx plc-conformance` and the Node test runner entry with no Rust toolchain:
//
//   cargo build --release
//   node adapters/js/tools/pack.js --binary target/release/plc-conformance --out dist
//
// `--binary` may be given once per platform, as PLATFORM-ARCH=PATH (`linux-arm64=...`, the
// names of Node's process.platform and process.arch); a bare PATH is this machine's platform.
// Prints the tarball's path. Without a binary the package is the helper alone (npm install of
// this folder), which finds the command in $PLC_CONFORMANCE or on PATH.
const { spawnSync } = require('node:child_process');
const fs = require('node:fs');
const os = require('node:os');
const path = require('node:path');
const { EXE } = require('../binary');

function fail(message) {
  process.stderr.write(`pack: ${message}\n`);
  process.exit(2);
}

const binaries = [];
let out = process.cwd();
const args = process.argv.slice(2);
for (let i = 0; i < args.length; i += 1) {
  const value = args[i + 1];
  if (args[i] === '--binary' && value) {
    const m = /^([a-z0-9]+-[a-z0-9]+)=(.+)$/.exec(value);
    binaries.push(m ? [m[1], m[2]] : [`${process.platform}-${process.arch}`, value]);
    i += 1;
  } else if (args[i] === '--out' && value) {
    out = value;
    i += 1;
  } else {
    fail(`unknown argument ${args[i]}; usage: pack.js --binary [PLATFORM-ARCH=]PATH ... [--out DIR]`);
  }
}
if (binaries.length === 0) fail('give the command to carry: --binary target/release/plc-conformance');

const source = path.join(__dirname, '..');
const manifest = JSON.parse(fs.readFileSync(path.join(source, 'package.json'), 'utf8'));
const stage = fs.mkdtempSync(path.join(os.tmpdir(), 'plc-conformance-pack-'));
try {
  for (const file of [...manifest.files, 'package.json']) {
    fs.cpSync(path.join(source, file), path.join(stage, file), { recursive: true });
  }
  for (const [platform, file] of binaries) {
    if (!fs.statSync(file, { throwIfNoEntry: false })?.isFile()) fail(`no such file: ${file}`);
    const target = path.join(stage, 'vendor', platform, platform.startsWith('win32') ? 'plc-conformance.exe' : EXE);
    fs.mkdirSync(path.dirname(target), { recursive: true });
    fs.copyFileSync(file, target);
    fs.chmodSync(target, 0o755);
  }
  manifest.files = [...manifest.files, 'vendor'];
  fs.writeFileSync(path.join(stage, 'package.json'), `${JSON.stringify(manifest, null, 2)}\n`);
  fs.mkdirSync(out, { recursive: true });
  const npm = process.platform === 'win32' ? 'npm.cmd' : 'npm';
  const done = spawnSync(npm, ['pack', '--silent', '--pack-destination', path.resolve(out)],
    { cwd: stage, encoding: 'utf8' });
  if (done.status !== 0) fail(`npm pack failed: ${done.error ? done.error.message : done.stderr}`);
  process.stdout.write(`${path.resolve(out, done.stdout.trim().split('\n').pop())}\n`);
} finally {
  fs.rmSync(stage, { recursive: true, force: true });
}
