'use strict';
// mcprotocol's adapter checked by the Node test runner, one test per cross-vendor case (run with
// the plc-conformance command on PATH or in $PLC_CONFORMANCE: `node --test conformance/`).
const path = require('node:path');
const { codecCases } = require('plc-conformance-adapter/testing');

codecCases({
  name: 'mcprotocol',
  adapter: path.join(__dirname, '..', 'mcprotocol_codec.js'),
  knownDifferences: path.join(__dirname, '..', 'mcprotocol.known.yaml'),
});
