#!/usr/bin/env node
'use strict';
// A 4- and 8-digit codec written with serveCodec(). MODE (argv[2]):
//   strict     decodes 0-9 and A-F only, encodes uppercase with the lowest `digits` digits
//   lowercase  a deliberately wrong codec: parseInt(text, 16) also takes a-f (and stops at
//              the first character that is not a digit)
//   crash      throws an error that `errors` does not map on the text "DEAD"
//   noisy      logs with console.log on every call (the log must not reach stdout)
const { serveCodec } = require('..');

class BadDigit extends Error {}
const mode = process.argv[2] || 'strict';

function strictDecode(text, digits) {
  const field = text.toString('latin1').slice(0, digits);
  if (mode === 'crash' && field === 'DEAD') throw new Error('deliberate crash on DEAD');
  if (!/^[0-9A-F]*$/.test(field)) throw new BadDigit(field);
  if (field.length < digits) throw new BadDigit('text ends inside the field');
  return parseInt(field, 16);
}

function wrongDecode(text, digits) {
  const value = parseInt(text.toString('latin1').slice(0, digits), 16);
  if (Number.isNaN(value)) throw new BadDigit('no digits');
  return value;
}

serveCodec({
  decode(text, digits) {
    if (mode === 'noisy') console.log('decoding', text);
    return (mode === 'lowercase' ? wrongDecode : strictDecode)(text, digits);
  },
  encode(value, digits) {
    if (mode === 'noisy') console.info('encoding', value);
    return (value % 16 ** digits).toString(16).toUpperCase().padStart(digits, '0');
  },
  name: `codec-${mode}`,
  version: '1',
  decodeDigits: [4, 8],
  encodeDigits: [4, 8],
  width: 32,
  errors: new Map([[BadDigit, 'invalid-digit']]),
  // What it means to follow: `plc-conformance sweep --operation` judges it against these.
  decodeReading: 'fx5/hexa-16bit',
  encodeReading: 'fx5/asci-16bit',
});
