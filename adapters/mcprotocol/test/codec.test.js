'use strict';
// The mcprotocol codec adapter driven as the harness drives it, on a few cases whose answers
// its known-differences file records (mcprotocol.known.yaml). Needs `npm ci` in this folder.
const test = require('node:test');
const assert = require('node:assert/strict');
const path = require('node:path');
const { spawnSync } = require('node:child_process');

const bytes = (s) => [...Buffer.from(s, 'latin1')];

test('mcprotocol through its private binarize/asciize', () => {
  const cases = [
    { id: 1, case: 'a', operation: 'hex-to-value', text: bytes('5A8D'), digits: 4 },
    { id: 2, case: 'b', operation: 'hex-to-value', text: bytes('5a8D'), digits: 4 },
    { id: 3, case: 'c', operation: 'hex-to-value', text: bytes('123G'), digits: 4 },
    { id: 4, case: 'd', operation: 'hex-to-value', text: bytes('/234'), digits: 4 },
    { id: 5, case: 'e', operation: 'hex-to-value', text: bytes('12'), digits: 4 },
    { id: 6, case: 'f', operation: 'value-to-hex', value: 0x0abc, digits: 4 },
  ];
  const input = [
    { type: 'hello', protocol: 2, harness: 'test' },
    { type: 'run', cases },
    { type: 'shutdown' },
  ].map((m) => `${JSON.stringify(m)}\n`).join('');
  const run = spawnSync(process.execPath, [path.join(__dirname, '..', 'mcprotocol_codec.js')], { input, encoding: 'utf8', timeout: 20000 });
  assert.equal(run.status, 0, run.stderr);
  const [hello, ...answers] = run.stdout.trim().split('\n').map((l) => JSON.parse(l));
  assert.deepEqual(hello.backend, { name: 'mcprotocol', version: '0.1.2' });
  assert.deepEqual(hello.capabilities, { codec: {
    'hex-to-value': { width: 16, digits: [4] },
    'value-to-hex': { width: 16, digits: [4] },
    protocol: 'mc-ascii',
    fields: ['word'],
    'cross-vendor': true,
  } });
  assert.deepEqual(answers, [
    { type: 'result', id: 1, value: 0x5a8d },
    { type: 'result', id: 2, value: 0x5a8d }, // lowercase accepted
    { type: 'result', id: 3, value: 0x1203 }, // parseInt("0x3G") is 3
    { type: 'result', id: 4, value: 0x0034 }, // NaN stored into a Buffer is 0
    { type: 'result', id: 5, error: 'invalid-digit' }, // one byte: no word to read
    { type: 'result', id: 6, text: bytes('0abc') }, // lowercase written
  ]);
});
