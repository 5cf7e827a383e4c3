#!/usr/bin/env node
'use strict';
// `npx plc-conformance ...`: runs the command this package carries (or $PLC_CONFORMANCE, or one
// on PATH), with this process's arguments, standard streams and exit status.
const { spawnSync } = require('node:child_process');
const { findBinary } = require('../binary');

const binary = findBinary();
if (!binary) {
  process.stderr.write(
    'plc-conformance: this package carries no command for '
      + `${process.platform}-${process.arch} and none is on PATH; set PLC_CONFORMANCE to one `
      + '(the Python wheel and `cargo install plc-conformance` install it)\n',
  );
  process.exit(2);
}
const done = spawnSync(binary, process.argv.slice(2), { stdio: 'inherit' });
if (done.error) {
  process.stderr.write(`plc-conformance: cannot run ${binary}: ${done.error.message}\n`);
  process.exit(2);
}
if (done.signal) process.kill(process.pid, done.signal);
process.exit(done.status === null ? 2 : done.status);
