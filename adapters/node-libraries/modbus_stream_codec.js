#!/usr/bin/env node
'use strict';
// plc-conformance codec-level backend: the npm package modbus-stream's Modbus ASCII transport
// (lib/transport/ascii.js), judged by the Modbus ASCII corpus (vectors/protocols/modbus-ascii.yaml).
//
// modbus-stream reads an ASCII frame in Transport.prototype.unwrap: everything between ':' and
// CR LF goes through one `buffer.from(text.toString(), "hex")` (ascii.js:57), the first byte is
// the slave id, the last the LRC, the bytes between them the PDU (ascii.js:58-64). It writes
// every byte, the LRC included, with the module-private writeAscii (ascii.js:98-109).
// - hex-to-value (byte, register): the field is handed to unwrap as the body of a frame followed
//   by an LRC pair "00" (which unwrap never compares); the field's bytes are what unwrap decoded
//   before that LRC, slave id then PDU, read most significant byte first (mbap §4.2). Nothing is
//   checked here: an empty body throws unwrap's own RangeError (ascii.js:59 temp.readUInt8(0)).
// - value-to-hex: the value's bytes, most significant first, written by writeAscii.
// - check: unwrap's own expected_crc over the span (ascii.js:61 Transport.lrc), written by writeAscii.
// - verify: whether unwrap hands the frame on (it returns the unwrapped object, or throws).
// unwrap is called on a plain object holding the fields it uses (buffer, callback, stream), so no
// stream or timer is created. Known differences: modbus-stream.known.yaml.
const { serveCodec, privateFunctions } = require('plc-conformance-adapter');
const { valueOf, bytesOf } = require('./field_bytes');

const asciiFile = require.resolve('modbus-stream/lib/transport/ascii.js');
const Transport = require(asciiFile);
const { writeAscii } = privateFunctions(asciiFile, ['writeAscii']);

const latin1 = (bytes) => Buffer.from(bytes);
// unwrap(":" + body + CR LF), on a fresh transport state.
function unwrap(body) {
  const state = { buffer: null, callback: null, callbackSlaveId: null, stream: null };
  return Transport.prototype.unwrap.call(state, Buffer.concat([Buffer.from(':'), latin1(body), Buffer.from('\r\n')]));
}
function ascii(bytes) {
  const out = Buffer.alloc(bytes.length * 2);
  writeAscii(out, bytes, 0);
  return out;
}

serveCodec({
  name: 'modbus-stream', version: require('modbus-stream/package.json').version,
  decodeDigits: [2, 4], encodeDigits: [2, 4],
  decode(text, digits) {
    const frame = unwrap(Buffer.concat([text, Buffer.from('00')]));
    const bytes = Buffer.concat([Buffer.from([frame.slaveId]), frame.pdu]);
    return valueOf(bytes);
  },
  encode(value, digits) {
    const bytes = bytesOf(value, digits);
    return ascii(bytes);
  },
  check: (span) => ascii(Buffer.from([unwrap(Buffer.concat([span, Buffer.from('00')])).expected_crc])),
  verify: (frame) => Boolean(unwrap(frame)),
  errors: { RangeError: 'error' },
  protocol: 'modbus-ascii',
  fields: ['byte', 'register', 'lrc'],
  // The cross-vendor corpus too: a 2-digit field is a byte, a 4-digit one a 16-bit register.
  field: { widths: { 2: 8, 4: 16 } },
  crossVendor: true,
});
