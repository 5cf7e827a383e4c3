#!/usr/bin/env node
'use strict';
// plc-conformance codec-level backend: the npm package modbus-serial's Modbus ASCII port
// (ports/asciiport.js), judged by the Modbus ASCII corpus (vectors/protocols/modbus-ascii.yaml).
//
// modbus-serial converts a whole frame in two module-private functions of ports/asciiport.js,
// reached with privateFunctions (a separate copy of the module's source):
// - _asciiEncodeRequestBuffer(buf) (asciiport.js:22-41): replaces the request's 2 CRC bytes with
//   the LRC (utils/lrc.js) and writes ':' + `buf.toString("hex", ...).toUpperCase()` + CR LF;
// - _asciiDecodeResponseBuffer(bufAscii) (asciiport.js:50-74): writes each character pair into a
//   byte with `bufDecoded.write(pair, i, 1, "hex")` (line 57), compares the LRC (lines 61-62) and
//   answers null on a mismatch, else the bytes with the LRC replaced by a CRC16.
// The wiring:
// - value-to-hex (byte, register): the value's bytes, most significant first, as a request
//   encoded by _asciiEncodeRequestBuffer; the field is the characters after ':'.
// - hex-to-value: the field as the body of a response frame followed by an LRC pair. The library
//   only hands on a frame whose LRC it accepts, and the LRC depends on what it decoded, so the
//   pair is the one of 00-FF that _asciiDecodeResponseBuffer accepts (at most one; none: the
//   library never hands the field on, answered as an error); the value is the decoded bytes
//   before the LRC, most significant first (no byte at all: unsupported, no value to give).
//   Nothing else is checked here.
// - check: the LRC characters _asciiEncodeRequestBuffer writes for the span's bytes (decoded as
//   hex-to-value decodes them). verify: whether _asciiDecodeResponseBuffer answers non-null.
// The module requires serialport (an optional dependency of modbus-serial, installed); no port is
// opened. Known differences: modbus-serial.known.yaml.
const { serveCodec, privateFunctions, CodecError, Unsupported } = require('plc-conformance-adapter');
const { valueOf, bytesOf } = require('./field_bytes');

const { _asciiEncodeRequestBuffer, _asciiDecodeResponseBuffer } = privateFunctions(
  require.resolve('modbus-serial/ports/asciiport.js'),
  ['_asciiEncodeRequestBuffer', '_asciiDecodeResponseBuffer'],
);

const frame = (body) => Buffer.concat([Buffer.from(':'), body, Buffer.from('\r\n')]);
const HEX = (n) => n.toString(16).toUpperCase().padStart(2, '0');

// The bytes _asciiDecodeResponseBuffer decodes from a body followed by the LRC it accepts.
function decodeBytes(text) {
  for (let lrc = 0; lrc < 256; lrc++) {
    const decoded = _asciiDecodeResponseBuffer(frame(Buffer.concat([text, Buffer.from(HEX(lrc))])));
    if (decoded !== null) return decoded.subarray(0, decoded.length - 2);
  }
  throw new CodecError('error', 'no LRC pair makes _asciiDecodeResponseBuffer hand the frame on');
}
// The characters _asciiEncodeRequestBuffer writes for these bytes: ':' + bytes + LRC + CR LF.
const encodeRequest = (bytes) => _asciiEncodeRequestBuffer(Buffer.concat([bytes, Buffer.alloc(2)]));

serveCodec({
  name: 'modbus-serial', version: require('modbus-serial/package.json').version,
  decodeDigits: [2, 4], encodeDigits: [2, 4],
  decode(text) {
    const bytes = decodeBytes(text);
    // An empty body with the LRC 00 is a frame of no byte: the library gives no value to answer.
    if (bytes.length === 0) throw new Unsupported('_asciiDecodeResponseBuffer decoded no byte for the field');
    return valueOf(bytes);
  },
  encode(value, digits) {
    const bytes = bytesOf(value, digits);
    return encodeRequest(bytes).subarray(1, 1 + digits);
  },
  check(span) {
    const out = encodeRequest(decodeBytes(span));
    return out.subarray(out.length - 4, out.length - 2);
  },
  verify: (text) => _asciiDecodeResponseBuffer(frame(text)) !== null,
  errors: { RangeError: 'error' },
  protocol: 'modbus-ascii',
  fields: ['byte', 'register', 'lrc'],
  // The cross-vendor corpus too: a 2-digit field is a byte, a 4-digit one a 16-bit register.
  field: { widths: { 2: 8, 4: 16 } },
  crossVendor: true,
});
