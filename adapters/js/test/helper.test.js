'use strict';
// The JavaScript helper driven as the harness drives it: each backend runs as a child process,
// is sent scripted protocol lines (hello, run, shutdown) and its answers are checked.
const test = require('node:test');
const assert = require('node:assert/strict');
const path = require('node:path');
const { PassThrough } = require('node:stream');
const fs = require('node:fs');
const os = require('node:os');

const helper = require('..');

const { EXAMPLES: FIXTURES, drive } = require('../test-support/drive');


const HELLO_2 = { type: 'hello', protocol: 2, harness: 'plc-conformance 0.2.0' };
const HELLO_1 = { type: 'hello', protocol: 1, harness: 'plc-conformance 0.1.0' };
const HELLO_3 = { type: 'hello', protocol: 3, harness: 'plc-conformance 0.3.0' };
const SHUTDOWN = { type: 'shutdown' };
const bytes = (s) => [...Buffer.from(s, 'latin1')];
const h2v = (id, text, digits) => ({ id, case: `h2v-${id}`, operation: 'hex-to-value', text: bytes(text), digits });
const v2h = (id, value, digits) => ({ id, case: `v2h-${id}`, operation: 'value-to-hex', value, digits });

const CODEC_CASES = [
  h2v(1, '5A8D', 4),
  h2v(2, '5a8D', 4),
  h2v(3, '12345678', 8),
  h2v(4, '12', 4),
  h2v(5, '7F', 2),
  v2h(6, 2748, 4),
  v2h(7, 0x12345678, 4),
  v2h(8, 0x10000, 8),
  v2h(9, 0x1_0000_0000, 8),
];

test('a codec answers hello with protocol 2 and its codec capabilities', async () => {
  const { answers, code } = await drive('codec.js', ['strict'], [HELLO_2, SHUTDOWN]);
  assert.equal(code, 0);
  assert.deepEqual(answers, [{
    type: 'hello',
    protocol: 2,
    backend: { name: 'codec-strict', version: '1' },
    capabilities: { codec: {
      'hex-to-value': { width: 32, reading: 'fx5/hexa-16bit', digits: [4, 8] },
      'value-to-hex': { width: 32, reading: 'fx5/asci-16bit', digits: [4, 8] },
    } },
  }]);
});

test('a codec answers each case in order: values, mapped errors, text bytes, unsupported', async () => {
  const { answers, code, stderr } = await drive('codec.js', ['strict'], [HELLO_2, { type: 'run', cases: CODEC_CASES }, SHUTDOWN]);
  assert.equal(code, 0, stderr);
  assert.deepEqual(answers.slice(1), [
    { type: 'result', id: 1, value: 0x5a8d },
    { type: 'result', id: 2, error: 'invalid-digit' },
    { type: 'result', id: 3, value: 0x12345678 },
    { type: 'result', id: 4, error: 'invalid-digit' },
    { type: 'unsupported', id: 5, reason: 'hex-to-value with 2 digits is not implemented' },
    { type: 'result', id: 6, text: bytes('0ABC') },
    { type: 'result', id: 7, text: bytes('5678') },
    { type: 'result', id: 8, text: bytes('00010000') },
    { type: 'unsupported', id: 9, reason: '4294967296 is wider than 32 bits' },
  ]);
});

test('a deliberately wrong codec (accepts lowercase) answers differently from the strict one', async () => {
  const script = [HELLO_2, { type: 'run', cases: [h2v(1, '5a8D', 4), h2v(2, '1a34', 4), h2v(3, '5A8D', 4)] }, SHUTDOWN];
  const strict = await drive('codec.js', ['strict'], script);
  const wrong = await drive('codec.js', ['lowercase'], script);
  assert.deepEqual(strict.answers.slice(1).map((a) => a.error ?? a.value), ['invalid-digit', 'invalid-digit', 0x5a8d]);
  assert.deepEqual(wrong.answers.slice(1).map((a) => a.error ?? a.value), [0x5a8d, 0x1a34, 0x5a8d]);
  // The difference the harness reports: an error class expected, a value answered.
  assert.notDeepEqual(wrong.answers[1], strict.answers[1]);
  assert.deepEqual(wrong.answers[3], strict.answers[3]);
});

test('an exception the codec does not map crashes the backend after the answers before it', async () => {
  const cases = [h2v(1, '5A8D', 4), h2v(2, 'DEAD', 4), h2v(3, 'BEEF', 4)];
  const { answers, code, stderr } = await drive('codec.js', ['crash'], [HELLO_2, { type: 'run', cases }], { closeStdin: false });
  assert.notEqual(code, 0);
  assert.deepEqual(answers.slice(1), [{ type: 'result', id: 1, value: 0x5a8d }]);
  assert.match(stderr, /deliberate crash on DEAD/);
  assert.match(stderr, /at strictDecode/);
});

test("a library's console.log goes to stderr, never into the protocol", async () => {
  const { lines, stderr, code } = await drive('codec.js', ['noisy'], [HELLO_2, { type: 'run', cases: [h2v(1, '5A8D', 4), v2h(2, 5, 4)] }, SHUTDOWN]);
  assert.equal(code, 0);
  assert.equal(lines.length, 3);
  for (const line of lines) JSON.parse(line);
  assert.match(stderr, /decoding/);
  assert.match(stderr, /encoding 5/);
});

test('a codec told protocol 1 still answers 2 and says why on stderr', async () => {
  const { answers, stderr } = await drive('codec.js', ['strict'], [HELLO_1, SHUTDOWN]);
  assert.equal(answers[0].protocol, 2);
  assert.match(stderr, /needs protocol version 2/);
});

test('a backend exits at the end of input without a shutdown', async () => {
  const { code, answers } = await drive('codec.js', ['strict'], [HELLO_2]);
  assert.equal(code, 0);
  assert.equal(answers.length, 1);
});

// --- instruction level ------------------------------------------------------------------------

function habinCase(id, overrides = {}) {
  return {
    id,
    case: `habin-${id}`,
    instruction: 'HABIN',
    profile: 'mitsubishi-iqr',
    variant: 'rcpu',
    flags: { SM705: false },
    operands: { s: 'D100', d: 'D200' },
    fill: 'A',
    memory: [
      { start: 'D100', words: [0x4135, 0x4438, 0xa5a5] },
      { start: 'D200', words: [0xa7a7] },
    ],
    ...overrides,
  };
}

test('an instruction-level backend answers hello with the version the harness speaks', async () => {
  const hello4 = { ...HELLO_3, protocol: 4 };
  const hello5 = { ...HELLO_3, protocol: 5 };
  const hello9 = { ...HELLO_3, protocol: 9 };
  for (const [hello, version] of [[HELLO_1, 1], [HELLO_2, 2], [HELLO_3, 3], [hello4, 4], [hello5, 5], [hello9, 5], [{ type: 'hello' }, 1]]) {
    const { answers } = await drive('habin.js', [], [hello, SHUTDOWN]);
    assert.deepEqual(answers[0], {
      type: 'hello',
      protocol: version,
      backend: { name: 'habin-js', version: '1' },
      capabilities: { profile: 'mitsubishi-iqr', instructions: ['HABIN', 'HABINP'], flags: { SM705: [false] } },
    });
  }
});

test('an instruction-level backend executes cases on the window, the fill and the flags', async () => {
  const cases = [
    habinCase(1), // "5A8D" -> 5A8DH (p.478 example)
    habinCase(2, { memory: [{ start: 'D100', words: [0x6135, 0x4438] }, { start: 'D200', words: [0] }] }), // "5a8D"
    habinCase(3, { flags: { SM705: true } }), // SM705 on: not implemented
    habinCase(4, { variant: 'rcpu-no-sm705', flags: { SM705: true }, ignored_flags: { SM705: false } }),
    habinCase(5, { memory: [{ start: 'D100', words: [0x4135] }, { start: 'D200', words: [0] }] }), // (s)+1 missing
    habinCase(6, { operands: { s: 'D100', d: 200 } }), // d as a constant
  ];
  const { answers, code, stderr } = await drive('habin.js', [], [HELLO_1, { type: 'run', cases }, SHUTDOWN]);
  assert.equal(code, 0, stderr);
  assert.deepEqual(answers.slice(1), [
    { type: 'result', id: 1, writes: { D200: 0x5a8d }, error: null },
    { type: 'result', id: 2, writes: {}, error: { code: 0x3401 } },
    { type: 'unsupported', id: 3, reason: 'SM705 on' },
    { type: 'result', id: 4, writes: { D200: 0x5a8d }, error: null },
    { type: 'result', id: 5, writes: {}, error: { code: 0x2820 } },
    { type: 'unsupported', id: 6, reason: 'operand "d" as a constant (K200) is not implemented' },
  ]);
});

// --- in process: the Case, the fill and the error table -----------------------------------------

test('a byte-addressed case reads bytes', () => {
  const device = helper.Device.parse('DB1.DBB10');
  assert.equal(device.code, 'DB1.DBB');
  assert.equal(device.offset(1).toString(), 'DB1.DBB11');
  for (const bad of ['DB1.10', 'db1.DBB10', 'DB1.DBB']) {
    assert.throws(() => helper.Device.parse(bad), TypeError);
  }
  const c = new helper.Case({
    id: 1, case: 'x', instruction: 'ATH', profile: 'p', variant: 'v', flags: {}, operands: {},
    fill: 'B', memory: [{ start: 'MB20', bytes: [0x30, 0x41] }],
  });
  assert.equal(c.read('MB21'), 0x41);
  assert.equal(c.read('MB30'), helper.fillWord('B', 30) & 0xff);
});

test('a case of 32-bit units reads and writes dwords', () => {
  const c = new helper.Case({
    id: 1, case: 'x', instruction: 'HEX8', profile: 'p', variant: 'v', flags: {}, operands: {},
    fill: 'B', memory: [{ start: 'DW10', dwords: [0x89abcdef, 0x31] }],
  });
  assert.equal(c.read('DW10'), 0x89abcdef);
  assert.equal(c.read('DW3'), helper.fillWord('B', 3) + helper.fillWord('B', 11) * 0x10000);
  assert.equal(c.read('DW3'), helper.fillWord('B', 3, 'dword'));
  c.write('DW30', 0xffffffff);
  assert.throws(() => c.write('DW31', 0x100000000), RangeError);
});

test('fillWord gives the two fill patterns of docs/protocol.md', () => {
  assert.equal(helper.fillWord('A', 0), 0xa5a5);
  assert.equal(helper.fillWord('A', 1), 0xa4a4);
  assert.equal(helper.fillWord('A', 'D5'), 0xa5a5 ^ 0x0505);
  assert.equal(helper.fillWord('A', 6), 0xa5a5);
  assert.equal(helper.fillWord('A', helper.Device.parse('D17')), 0xa4a4);
  assert.equal(helper.fillWord('B', 0), 0x4630); // '0' low, 'F' high
  assert.equal(helper.fillWord('B', 15), 0x3046);
  assert.equal(helper.fillWord('B', 'D110'), 0x3145); // i = 14: 'E' low, '1' high
  // A digit designation's next word is 16 points on, and its word number is the head / 16.
  assert.equal(helper.Device.parse('K4M100').offset(1).toString(), 'K4M116');
  assert.equal(helper.fillWord('B', 'K4M116'), helper.fillWord('B', 7));
  assert.equal(helper.Device.parse('U1\\G10').offset(1).toString(), 'U1\\G11');
});

test('Case reads its writes, then the window, then the fill; flag() prefers ignored_flags', () => {
  const c = new helper.Case(habinCase(1, { fill: 'B', flags: { SM705: true, SM701: true }, ignored_flags: { SM705: false } }));
  assert.equal(c.read('D100'), 0x4135);
  assert.equal(c.read(helper.Device.parse('D300')), helper.fillWord('B', 300));
  c.write('D100', 7);
  assert.equal(c.read('D100'), 7);
  assert.equal(c.flag('SM705'), false);
  assert.equal(c.flag('SM701'), true);
  assert.equal(c.flag('SM999'), false);
  assert.equal(c.exists('D102'), true);
  assert.equal(c.exists('D103'), false);
  assert.equal(helper.Device.parse('D100').offset(3).toString(), 'D103');
  assert.throws(() => c.write('D1', 0x10000), RangeError);
  assert.throws(() => helper.Device.parse('d100'), TypeError);
  c.fail({ flag: 'M8004' });
  assert.deepEqual(c.answer(), { type: 'result', id: 1, writes: { D100: 7 }, error: { flag: 'M8004' } });
});

test('a hexadecimal-numbered code reads, steps and answers in hexadecimal', () => {
  const c = new helper.Case(habinCase(1, {
    hexadecimal: ['W'],
    operands: { s: 'W19', d: 'W1A' },
    memory: [{ start: 'W19', words: [1, 2] }],
  }));
  assert.equal(c.device('s').offset(1).toString(), 'W1A');
  assert.equal(c.read('W1A'), 2);
  assert.equal(c.read(c.device('d')), 2);
  assert.equal(helper.Device.parse('W10', ['W']).index, 16);
  assert.equal(helper.Device.parse('W10').index, 10);
  c.write(c.device('s').offset(7), 9);
  assert.deepEqual(c.answer().writes, { W20: 9 });
});

test('an indirect operand is the device its pointer addresses', () => {
  const message = habinCase(1, {
    operands: { s: '@D10', d: 'D200' },
    memory: [{ start: 'D100', words: [7] }],
    addresses: { D10: 'D100' },
  });
  const c = new helper.Case(message);
  assert.equal(c.device('s').toString(), 'D100');
  assert.equal(c.read(c.device('s')), 7);
  assert.equal(c.pointer('s').toString(), 'D10');
  assert.equal(c.pointer('d'), null);
  assert.throws(() => new helper.Case({ ...message, addresses: {} }).operand('s'), /D10/);
});

/** Runs serveCodec in process over the given messages; resolves with the answers. */
async function inProcess(options, messages) {
  const input = new PassThrough();
  const output = new PassThrough();
  let text = '';
  output.on('data', (d) => { text += d; });
  const served = helper.serveCodec({ ...options, input, output, stderr: new PassThrough(), exit: false });
  for (const m of messages) input.write(`${JSON.stringify(m)}\n`);
  input.end();
  await served;
  return text.split('\n').filter(Boolean).map((l) => JSON.parse(l));
}

test('CodecError, errors by name, async functions and bigint values', async () => {
  class FieldError extends Error {}
  class WideError extends FieldError {}
  const answers = await inProcess({
    name: 'x',
    version: '1',
    async decode(text, digits) {
      if (digits === 3) throw new helper.CodecError('invalid-count');
      if (text[0] === 0x57) throw new WideError('W'); // "W...": a subclass maps like its base
      if (text[0] === 0x52) throw new RangeError('R');
      return 0xffffffffn;
    },
    encode: () => Buffer.from('0ABC\0junk'),
    errors: { FieldError: 'invalid-digit', RangeError: 'device-range' },
    width: 32,
  }, [HELLO_2, { type: 'run', cases: [h2v(1, 'AAA', 3), h2v(2, 'WXYZ', 4), h2v(3, 'RXYZ', 4), h2v(4, 'FFFFFFFF', 8), v2h(5, 1, 4), h2v(6, '1', 9)] }, SHUTDOWN]);
  assert.deepEqual(answers.slice(1), [
    { type: 'result', id: 1, error: 'invalid-count' },
    { type: 'result', id: 2, error: 'invalid-digit' },
    { type: 'result', id: 3, error: 'device-range' },
    { type: 'result', id: 4, value: 4294967295 },
    { type: 'result', id: 5, text: bytes('0ABC\0junk') },
    { type: 'unsupported', id: 6, reason: 'hex-to-value with 9 digits is not implemented' },
  ]);
});

test('serveCodec refuses what the protocol cannot say', () => {
  assert.throws(() => new helper.CodecError('bad-class'), TypeError);
  assert.throws(() => helper.serveCodec({ name: 'x', version: '1' }), TypeError);
  assert.throws(() => helper.serveCodec({ name: 'x', version: '1', decode: () => 0, width: 24 }), TypeError);
  assert.throws(() => helper.serveCodec({ name: 'x', version: '1', decode: () => 0, decodeDigits: [0] }), TypeError);
  assert.throws(() => helper.serveCodec({ name: 'x', version: '1', decode: () => 0, errors: { Error: 'wrong' } }), TypeError);
});

test('privateFunctions reaches a module\'s unexported functions without changing the module', () => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plc-private-'));
  const file = path.join(dir, 'lib.js');
  fs.writeFileSync(file, [
    "var util = require('util');",
    'module.exports = function Client() {};',
    'function hidden(x) { return util.format("%s!", x); }',
    'var notAFunction = 1;',
  ].join('\n'));
  try {
    const { hidden } = helper.privateFunctions(file, ['hidden']);
    assert.equal(hidden('ok'), 'ok!');
    assert.equal(typeof require(file), 'function'); // the module itself is as it was
    assert.throws(() => helper.privateFunctions(file, ['missing']), /no top-level function missing/);
    assert.throws(() => helper.privateFunctions(file, ['notAFunction']), /no top-level function notAFunction/);
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});

test('each direction maps its own errors before the shared ones', async () => {
  const answers = await inProcess({
    name: 'x',
    version: '1',
    decode() { throw new RangeError('not a digit'); },
    encode() { throw new RangeError('too wide'); },
    errors: { RangeError: 'error' },
    decodeErrors: { RangeError: 'invalid-digit' },
  }, [HELLO_2, { type: 'run', cases: [h2v(1, '5a8D', 4), v2h(2, 0x1234, 4)] }, SHUTDOWN]);
  assert.deepEqual(answers.slice(1), [
    { type: 'result', id: 1, error: 'invalid-digit' },
    { type: 'result', id: 2, error: 'error' },
  ]);
  assert.throws(() => helper.serveCodec({ name: 'x', version: '1', decode: () => 0, encodeErrors: { Error: 'wrong' } }), TypeError);
});

test('a codec declares its field shape; a count or value outside its widths is unsupported', async () => {
  const answers = await inProcess({
    name: 'byte-field',
    version: '1',
    decode: (text) => parseInt(text.toString('latin1'), 16),
    encode: (value) => value.toString(16).toUpperCase().padStart(2, '0'),
    field: { widths: { 2: 8 }, wholeFrame: true, byteOrder: 'low-first', leadingZeros: true, variable: false },
  }, [HELLO_2, { type: 'run', cases: [h2v(1, '7F', 2), h2v(2, '5A8D', 4), v2h(3, 0x7f, 2), v2h(4, 0x1ff, 2)] }, SHUTDOWN]);
  assert.deepEqual(answers[0].capabilities.codec['hex-to-value'], {
    width: 16, widths: { 2: 8 }, 'whole-frame': true, 'byte-order': 'low-first', 'leading-zeros': true, variable: false,
  });
  assert.deepEqual(answers[1], { type: 'result', id: 1, value: 0x7f });
  assert.equal(answers[2].type, 'unsupported');
  assert.deepEqual(answers[3], { type: 'result', id: 3, text: [...Buffer.from('7F')] });
  assert.equal(answers[4].type, 'unsupported');
  assert.throws(() => helper.serveCodec({ name: 'x', version: '1', decode: () => 0, field: { widths: { 2: 12 } } }), TypeError);
  assert.throws(() => helper.serveCodec({ name: 'x', version: '1', decode: () => 0, field: { order: 'low' } }), TypeError);
});

test("a protocol's codec names its protocol and answers check and verify", async () => {
  const lrc = (span) => {
    const bytes = Buffer.from(span.toString('latin1'), 'hex');
    return ((-bytes.reduce((a, b) => a + b, 0)) & 0xff).toString(16).toUpperCase().padStart(2, '0');
  };
  const check = (id, operation, text) => ({ id, case: `c${id}`, operation, text: bytes(text), digits: 2, field: 'lrc' });
  const answers = await inProcess({
    name: 'mb',
    version: '1',
    protocol: 'modbus-ascii',
    fields: ['lrc'],
    check: lrc,
    verify: (frame) => lrc(frame.subarray(0, -2)) === frame.subarray(-2).toString('latin1'),
  }, [HELLO_2, { type: 'run', cases: [check(1, 'check', '010304010001'), check(2, 'verify', '010304010001F6'), check(3, 'verify', '010304010001F7')] }, SHUTDOWN]);
  assert.deepEqual(answers[0].capabilities.codec, { check: {}, verify: {}, protocol: 'modbus-ascii', fields: ['lrc'] });
  assert.deepEqual(answers.slice(1), [
    { type: 'result', id: 1, text: bytes('F6') },
    { type: 'result', id: 2, accepted: true },
    { type: 'result', id: 3, error: 'bad-check' },
  ]);
  assert.throws(() => helper.serveCodec({ name: 'x', version: '1', check: lrc }), TypeError);
});
