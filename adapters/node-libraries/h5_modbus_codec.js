#!/usr/bin/env node
'use strict';
// plc-conformance codec-level backend: the npm package h5.modbus's Modbus ASCII transport
// (lib/transports/AsciiTransport.js), judged by the Modbus ASCII corpus
// (vectors/protocols/modbus-ascii.yaml) and the cross-vendor corpus.
//
// h5.modbus converts a whole frame in methods of AsciiTransport.prototype:
// - frame(unit, pdu) (AsciiTransport.js:152-174): ':' then each byte as encodeNibble(high),
//   encodeNibble(low) (`nibble + (nibble < 10 ? 48 : 55)`, :222), the LRC of lrc(unit, pdu)
//   (:183-193), CR LF;
// - onData(chunk) (:289-312) -> handleFrameData() (:347-374): the characters between ':' and
//   CR LF go through decodeBytes (:252-262, decodeByte/decodeNibble `nibble - (nibble < 65 ? 48 :
//   55)`, :230-245), the last byte is the LRC, validate (:385-408) compares lrc(0, frame) with it
//   (InvalidChecksumError) and the unit, and the rest is handed on as `new Buffer(frame)` (:370)
//   to the request's createResponse.
// The wiring (no Master, no connection opened: a transport over an in-process connection, an
// EventEmitter the transport listens to):
// - hex-to-value: the smallest frame that holds the field, ':' + '01' (the unit) + the field +
//   an LRC pair + CR LF, given to onData. The LRC depends on what the library decodes, so the
//   pair is the one of 00-FF whose frame the library hands on (none: answered as an error). The
//   transaction is a stub set as the transport's current one (transport.transaction, what
//   sendRequest sets at :96): unit 1, and a request whose createResponse gives back the Buffer
//   the library built, so the value is that Buffer's bytes, most significant first (no byte:
//   unsupported, no value to give). The frame is given as two chunks, the text up to CR and then
//   LF, because endsWithCrLf (:330-342) sees a frame's end only when LF comes alone (for a chunk
//   of 2 or more bytes it compares the last byte, LF, with CR: :339-341); a serial port may
//   deliver any chunking, this one is the one the library reads.
// - value-to-hex (byte, register): frame(1, the value's bytes most significant first); the
//   field is the characters after ':' and the unit.
// - check: the LRC characters frame(first byte, the other bytes) writes, the span's bytes read by
//   the library's own decodeBytes. verify: whether onData of ':' + the frame + CR LF ends in any
//   other way than InvalidChecksumError (the stub's unit matches no byte, so the unit check after
//   the LRC fails on an accepted LRC).
// Nothing else is checked here. Known differences: h5.modbus.known.yaml.
require('./ascii_transport').serveAsciiTransport('h5.modbus', { lfAlone: true });
