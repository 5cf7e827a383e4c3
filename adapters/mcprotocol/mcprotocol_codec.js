#!/usr/bin/env node
'use strict';
// plc-conformance codec-level backend: the npm package mcprotocol's MC-protocol ASCII words.
//
// In ASCII mode mcprotocol builds each frame in binary and turns it into text with
// asciize(buffer), two hex characters per byte; a reply goes back through binarize(text). A word
// is its two bytes high byte first (bufferizeMCItem: writeUInt16BE, processMCReadItem:
// readUInt16BE), so the 4-character field of one word is exactly what these two functions
// convert. Both are private to mcprotocol.js: privateFunctions loads a separate copy of its
// source to reach them. Known differences: mcprotocol.known.yaml.
const { serveCodec, privateFunctions, CodecError } = require('plc-conformance-adapter');
const { binarize, asciize } = privateFunctions(require.resolve('mcprotocol'), ['binarize', 'asciize']);

serveCodec({
  name: 'mcprotocol', version: require('mcprotocol/package.json').version,
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
