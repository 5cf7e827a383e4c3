#!/usr/bin/env node
'use strict';
// plc-conformance codec-level backend: the npm package melsec-connect's MC-protocol ASCII words.
//
// melsec-connect carries a fork of mcprotocol's conversion (src/mcprotocol/mcprotocol.js). In
// ASCII mode it builds each frame in binary and turns it into text with asciize(buffer), two hex
// characters per byte (zeroPad, mcprotocol.js:3930-3945); a reply goes back through
// binarize(text) (mcprotocol.js:3915-3928, called at :1532). A word is its two bytes high byte
// first in ASCII mode (writeUInt16BE at :3720, readUInt16BE at :2282), so the 4-character field of
// one word is exactly what these two functions convert. Both are private to the module:
// privateFunctions loads a separate copy of its source to reach them. Nothing is checked here:
// binarize's own `undefined` ("Failed ASCII conversion", :1533) is its error, and a reply too
// short for the word is the RangeError of readUInt16BE, as in processMCReadItem.
// Known differences: melsec-connect.known.yaml.
const { serveCodec, privateFunctions, CodecError } = require('plc-conformance-adapter');
const { binarize, asciize } = privateFunctions(
  require.resolve('melsec-connect/src/mcprotocol/mcprotocol.js'), ['binarize', 'asciize'],
);

serveCodec({
  name: 'melsec-connect', version: require('melsec-connect/package.json').version,
  decodeDigits: [4], encodeDigits: [4],
  decode(text, digits) {
    const bytes = binarize(text.subarray(0, digits)); // undefined: "Failed ASCII conversion"
    if (bytes === undefined) throw new CodecError('invalid-digit');
    return bytes.readUInt16BE(0); // one byte (a text that ends early): RangeError
  },
  encode: (value) => asciize(Buffer.from([value >> 8, value & 0xff])),
  errors: { RangeError: 'invalid-digit' },
  // Judged by the MC protocol's own manual (its word field), and by the cross-vendor corpus too.
  protocol: 'mc-ascii',
  fields: ['word'],
  crossVendor: true,
});
