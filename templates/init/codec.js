#!/usr/bin/env node
// {{name}} as a codec-level backend of plc-conformance: the corpus asks it "this text, this many
// digits: what value?" and "this value, this many digits: what text?" and compares each answer
// with what the vendors' manuals give.
//
// Written by `plc-conformance init codec --js`; it runs green as written. Run it:
//
//     npx plc-conformance run --backend 'external:{{name}}=node {{name}}_adapter.js' \
//         --known-differences {{name}}={{name}}.known.yaml
//
// The helper and the command come in one npm package, pinned (no dependencies, Node 18+):
// npm install --save-dev plc-conformance-adapter@{{version}}
// Guide: docs/check-your-library.md in plc-conformance.
'use strict';
const { serveCodec, CodecError } = require('plc-conformance-adapter');

// 1. Require your library's conversions here, e.g.:
//    const { decodeWord, encodeWord } = require('mylib');

serveCodec({
  name: '{{name}}',
  version: '0.0.0', // 2. your library's version, e.g. require('mylib/package.json').version
  // 3. The digit counts it converts, and the width of its values (16 or 32 bits).
  decodeDigits: [4],
  encodeDigits: [4],
  width: 16,
  // 4. Text -> value: `text` is a Buffer of any byte values (the corpus sends lowercase letters,
  //    blanks, 00H and bytes above 7FH on purpose). Replace this stand-in with your library's
  //    call; return a number or a bigint, or throw. The stand-in reads as the manuals do
  //    (exactly the digits asked, each 0-9 or A-F), which is why the scaffold runs green as
  //    written.
  decode(text, digits) {
    {{field_js}}
    if (!/^[0-9A-F]+$/.test(field)) throw new CodecError('invalid-digit', field);
    return parseInt(field, 16);
  },
  // 5. Value -> text: return a Buffer, a byte array or a string. Replace this stand-in.
  encode: (value, digits) => value.toString(16).toUpperCase().padStart(digits, '0'),
  // 6. Its errors, by constructor name, as the shared error classes: invalid-digit,
  //    invalid-count, device-range, or error.
  errors: { RangeError: 'invalid-digit' },
  // 7. The protocol it speaks, whose own manual then judges it, each difference naming the rule
  //    and its page: mc-ascii, modbus-ascii, fx-computer-link, mewtocol-com, omron-host-link or
  //    keyence-kv-l2 (leave it out for a codec of no protocol). fields: [...] names the
  //    protocol's fields it implements, check and verify its check character.
  {{protocol_js}}
  // 8. Optional: the field's shape, e.g. field: { widths: { 2: 8 }, wholeFrame: true }, and
  //    the built-in reading it follows, e.g. decodeReading: 'fx5/hexa-16bit'.
});
