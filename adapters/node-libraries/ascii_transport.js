#!/usr/bin/env node
'use strict';
// The codec both h5.modbus and its fork @csllc/cs-modbus serve, through their own AsciiTransport
// (lib/transports/AsciiTransport.js): h5_modbus_codec.js and cs_modbus_codec.js say what each
// wires and why; this module only drives the package it is given.
const { EventEmitter } = require('events');
const { serveCodec, CodecError, Unsupported } = require('plc-conformance-adapter');
const { valueOf, bytesOf } = require('./field_bytes');

const HEX = (n) => n.toString(16).toUpperCase().padStart(2, '0');

/// Serves `pkg`'s AsciiTransport as a codec; `lfAlone`: give a frame's LF as a chunk of its own
/// (what h5.modbus's endsWithCrLf needs to see a frame's end).
function serveAsciiTransport(pkg, { lfAlone }) {
  const AsciiTransport = require(`${pkg}/lib/transports/AsciiTransport`);
  const { InvalidChecksumError } = require(`${pkg}/lib/errors`);

  // Give one frame to a fresh transport; answer the Buffer it hands on or the error it raises.
  function receive(body, unit) {
    const transport = new AsciiTransport(new EventEmitter());
    let outcome = null;
    transport.transaction = {
      getUnit: () => unit,
      getRequest: () => ({ createResponse: (buffer) => buffer }),
      handleResponse: (buffer) => { outcome = { buffer }; },
      handleError: (error) => { outcome = { error }; },
    };
    const frame = Buffer.concat([Buffer.from(':'), body, Buffer.from('\r')]);
    if (lfAlone) {
      transport.onData(frame);
      transport.onData(Buffer.from('\n'));
    } else {
      transport.onData(Buffer.concat([frame, Buffer.from('\n')]));
    }
    if (outcome === null) throw new CodecError('error', 'the transport did not finish the frame');
    return outcome;
  }

  function decodeBytes(text) {
    for (let lrc = 0; lrc < 256; lrc++) {
      const out = receive(Buffer.concat([Buffer.from('01'), text, Buffer.from(HEX(lrc))]), 1);
      if (out.buffer) return out.buffer;
    }
    throw new CodecError('error', 'no LRC pair makes AsciiTransport hand the frame on');
  }

  const transport = new AsciiTransport(new EventEmitter());

  serveCodec({
    name: pkg, version: require(`${pkg}/package.json`).version,
    decodeDigits: [2, 4], encodeDigits: [2, 4],
    decode(text) {
      const bytes = decodeBytes(text);
      if (bytes.length === 0) throw new Unsupported('AsciiTransport handed on no byte for the field');
      return valueOf(bytes);
    },
    encode(value, digits) {
      const bytes = bytesOf(value, digits);
      return transport.frame(1, bytes).subarray(3, 3 + digits);
    },
    check(span) {
      const bytes = transport.decodeBytes([...span]);
      const out = transport.frame(bytes[0], Buffer.from(bytes.slice(1)));
      return out.subarray(out.length - 4, out.length - 2);
    },
    verify: (text) => !(receive(text, NaN).error instanceof InvalidChecksumError),
    protocol: 'modbus-ascii',
    fields: ['byte', 'register', 'lrc'],
    // The cross-vendor corpus too: a 2-digit field is a byte, a 4-digit one a 16-bit register.
    field: { widths: { 2: 8, 4: 16 } },
    crossVendor: true,
  });
}

module.exports = { serveAsciiTransport };
