#!/usr/bin/env node
'use strict';
// plc-conformance codec-level backend: the npm package node-fxplc's word conversion (the
// Mitsubishi FX programming-port protocol: STX, command, hex-ASCII data, ETX, sum).
//
// node-fxplc reads a device through FXPLCClient.readNumber -> readBytes -> _sendCommand ->
// _readResponse (dist/cjs/FXPLCClient.js:346-390): the characters between STX and ETX are checked
// against the sum (:365), then `Buffer.from(hexBuf.toString('ascii'), 'hex')` (:369), and the
// word is read `b.readUInt16LE(o)` (number-types.js:23) after a length check (FXPLCClient.js:224).
// It writes one through writeNumber -> writeBytes -> _sendCommand:
// `data.toString('hex').toUpperCase()` (:335), the word's bytes `b.writeUInt16LE(v, o)`.
// The wiring drives those public methods through an in-process transport (no port, no network):
// - hex-to-value: readNumber('D0', WordUnsigned) answered with STX + the text + ETX + the sum the
//   library's own calcChecksum (protocol-utils.js:8-13) gives for it, so its sum check passes and
//   only the text is judged; its own errors (ResponseMalformedError) answer as errors.
// - value-to-hex: writeNumber('D0', value, WordUnsigned); the field is the last 4 characters
//   before ETX of the frame it writes (then answered ACK).
// Which corpus: the programming port is not the FX computer link. Its word is low byte first
// (number-types.js:23 readUInt16LE), where fx-computer-link/F1 sends the higher digit first, and
// its sum covers ETX (FXPLCClient.js:338, :365), so neither field is the computer link's: this is
// a codec of no protocol, run on the cross-vendor corpus with a low-byte-first field (the
// harness compares the expected value's bytes in that order). Known differences: node-fxplc.known.yaml.
const { serveCodec } = require('plc-conformance-adapter');
const { FXPLCClient, NumberType } = require('node-fxplc');
// protocol-utils.js and package.json are not in the package's exports: reached by path.
const path = require('node:path');
const root = path.join(path.dirname(require.resolve('node-fxplc')), '..', '..');
const { calcChecksum } = require(path.join(root, 'dist', 'cjs', 'protocol-utils.js'));

const STX = Buffer.from([0x02]);
const ETX = Buffer.from([0x03]);
const ACK = Buffer.from([0x06]);

// A transport that records what the client writes and answers its reads from a script.
function scripted(reply) {
  const written = [];
  let pending = Buffer.from(reply);
  return {
    written,
    async write(data) { written.push(Buffer.from(data)); },
    async read(size) {
      const out = pending.subarray(0, size);
      pending = pending.subarray(size);
      return out;
    },
  };
}
const client = (transport) => new FXPLCClient(transport, { retry: { count: 1, delayMs: 0 }, timeoutMs: 60000 });

serveCodec({
  name: 'node-fxplc', version: require(path.join(root, 'package.json')).version,
  decodeDigits: [4], encodeDigits: [4],
  field: { byteOrder: 'low-first' },
  async decode(text) {
    const body = Buffer.from(text);
    const reply = Buffer.concat([STX, body, ETX, calcChecksum(Buffer.concat([body, ETX]))]);
    return client(scripted(reply)).readNumber('D0', NumberType.WordUnsigned);
  },
  async encode(value) {
    const transport = scripted(ACK);
    await client(transport).writeNumber('D0', value, NumberType.WordUnsigned);
    const frame = transport.written[0];
    const etx = frame.indexOf(0x03);
    return frame.subarray(etx - 4, etx);
  },
  errors: { FXPLCError: 'error' },
});
