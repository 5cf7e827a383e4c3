#!/usr/bin/env node
// A codec whose decode is one line, parseInt(text, 16) once the characters are checked: what the
// harness costs a JavaScript codec is measured against it. Run as a script it serves the codec;
// `--bare FILE` instead times the bare loop over the texts in FILE (one `HEX DIGITS` line each:
// the text's bytes in hex) and prints the seconds.
'use strict';

const path = require('path');

const HEX = /^[0-9A-Fa-f]+$/;

function decode(text, digits) {
  const s = text.toString('latin1');
  if (!HEX.test(s)) throw new RangeError('not a hex number');
  return parseInt(s, 16);
}

function bare(file) {
  const items = require('fs').readFileSync(file, 'utf8').split('\n').filter(Boolean).map((line) => {
    const [hex, digits] = line.split(' ');
    return [Buffer.from(hex, 'hex'), Number(digits)];
  });
  const answers = [];
  const started = process.hrtime.bigint();
  for (const [text, digits] of items) {
    try {
      answers.push(decode(text, digits));
    } catch (e) {
      if (!(e instanceof RangeError)) throw e;
      answers.push('invalid-digit');
    }
  }
  console.log((Number(process.hrtime.bigint() - started) / 1e9).toFixed(6));
}

if (process.argv[2] === '--bare') {
  bare(process.argv[3]);
} else {
  const { serveCodec } = require(path.join(__dirname, '..', 'adapters', 'js'));
  serveCodec({ decode, name: 'int', version: '1', width: 32, errors: { RangeError: 'invalid-digit' } });
}
