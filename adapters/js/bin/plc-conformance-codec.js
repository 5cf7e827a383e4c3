#!/usr/bin/env node
'use strict';
// `npx plc-conformance-codec TEST_FILE [--codec NAME] COMMAND [ARGS...]`: the plc-conformance
// command on the codec a Node test file declares with codecCases, so that `sweep`, `record`,
// `list`, `diff` and `run` need no entry point beside the test file. `--codec NAME` picks one
// when the file declares several; ARGS are the command's own.
const { spawnSync } = require('node:child_process');
const { findBinary } = require('../binary');
const { codecCommand } = require('../testing');

const USAGE = 'usage: plc-conformance-codec TEST_FILE [--codec NAME] COMMAND [ARGS...]\n';

function main(argv) {
  if (argv.length < 2 || argv[0] === '-h' || argv[0] === '--help') {
    process.stderr.write(USAGE);
    return argv[0] === '-h' || argv[0] === '--help' ? 0 : 2;
  }
  let [file, ...rest] = argv;
  let name;
  if (rest[0] === '--codec') {
    [, name, ...rest] = rest;
  }
  if (!rest.length) {
    process.stderr.write(USAGE);
    return 2;
  }
  let line;
  try {
    line = codecCommand(file, rest[0], rest.slice(1), name);
  } catch (e) {
    process.stderr.write(`error: ${e.message}\n`);
    return 2;
  }
  const binary = findBinary();
  if (!binary) {
    process.stderr.write('plc-conformance-codec: no plc-conformance command (this package carries '
      + `none for ${process.platform}-${process.arch}, PLC_CONFORMANCE is not set, none on PATH)\n`);
    return 2;
  }
  const done = spawnSync(binary, line, { stdio: 'inherit' });
  if (done.error) {
    process.stderr.write(`plc-conformance-codec: cannot run ${binary}: ${done.error.message}\n`);
    return 2;
  }
  return done.status === null ? 2 : done.status;
}

process.exit(main(process.argv.slice(2)));
