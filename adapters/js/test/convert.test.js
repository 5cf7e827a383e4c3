'use strict';
// Protocol version 5 in the JavaScript helper: the `convert` message (many conversions of one
// operation, answered by one `converted` line), and the field shapes per direction
// (decodeField, encodeField, blanksBetweenPairs).
//
// Each batch is also asked as `run` cases, one by one, and every item must answer what its case
// answers: the batch is a faster path to the same answers, never other ones.
const test = require('node:test');
const assert = require('node:assert/strict');
const { PassThrough } = require('node:stream');

const helper = require('..');

const { EXAMPLES, drive } = require('../test-support/drive');
const HELLO_2 = { type: 'hello', protocol: 2, harness: 'plc-conformance 0.2.0' };
const HELLO_5 = { type: 'hello', protocol: 5, harness: 'plc-conformance 0.5.0' };
const SHUTDOWN = { type: 'shutdown' };


/** Runs serveCodec in process over the messages; resolves with the lines written. */
async function inProcess(options, messages) {
  const input = new PassThrough();
  const output = new PassThrough();
  let text = '';
  output.on('data', (d) => { text += d; });
  const served = helper.serveCodec({ ...options, input, output, stderr: new PassThrough(), exit: false });
  for (const m of messages) input.write(`${JSON.stringify(m)}\n`);
  input.end();
  await served;
  return text.split('\n').filter(Boolean);
}
/** Streams already at their end, so that a serveCodec that does not throw ends instead of serving stdin. */
function idle() {
  const input = new PassThrough();
  input.end();
  return { input, output: new PassThrough(), stderr: new PassThrough(), exit: false };
}
const answersOf = async (options, messages) => (await inProcess(options, messages)).map((l) => JSON.parse(l));

const h2vBatch = (id, texts, digits) => ({ type: 'convert', id, operation: 'hex-to-value', digits, texts });
const v2hBatch = (id, values, digits) => ({ type: 'convert', id, operation: 'value-to-hex', digits, values });

/** The batch's items as `run` cases. */
function asCases(batch) {
  return batch.digits.map((digits, k) => (batch.operation === 'hex-to-value'
    ? { id: k + 1, case: `c${k}`, operation: batch.operation, digits, text: [...Buffer.from(batch.texts[k], 'latin1')] }
    : { id: k + 1, case: `c${k}`, operation: batch.operation, digits, value: batch.values[k] }));
}

/** A `run` answer as the item of a `converted` line says the same. */
function asItem(answer) {
  if (answer.type === 'unsupported') return { unsupported: answer.reason };
  if (answer.error !== undefined) return { error: answer.error };
  if (answer.value !== undefined) return answer.value;
  return Buffer.from(answer.text).toString('latin1');
}

/** The batch's answers, checked to be the `run` answers of its items. */
async function sameAsRun(fixture, args, batch) {
  const converted = await drive(fixture, args, [HELLO_5, batch, SHUTDOWN]);
  assert.equal(converted.code, 0, converted.stderr);
  assert.equal(converted.answers.length, 2);
  assert.deepEqual(Object.keys(converted.answers[1]).sort(), ['answers', 'id', 'type']);
  assert.equal(converted.answers[1].type, 'converted');
  assert.equal(converted.answers[1].id, batch.id);
  const run = await drive(fixture, args, [HELLO_2, { type: 'run', cases: asCases(batch) }, SHUTDOWN]);
  assert.equal(run.code, 0, run.stderr);
  assert.deepEqual(converted.answers[1].answers, run.answers.slice(1).map(asItem));
  return converted.answers[1].answers;
}

test('a codec answers 5 to a harness of 5 (or newer) and 2 to older ones', async () => {
  assert.ok(helper.PROTOCOL_VERSIONS.includes(5));
  for (const [asked, answered] of [[5, 5], [9, 5], [4, 2], [3, 2], [2, 2]]) {
    const { answers, code } = await drive('codec.js', ['strict'], [{ ...HELLO_5, protocol: asked }, SHUTDOWN]);
    assert.equal(code, 0);
    assert.equal(answers[0].protocol, answered, `asked ${asked}`);
  }
});

test('hex-to-value: values, mapped errors and unsupported, in order, as run answers them', async () => {
  const batch = h2vBatch(12, ['5A8D', '5a8D', '5A\u00e9D', '7F', '12345678', 'DEAD', '\u00e9\u00e9\u00e9\u00e9'], [4, 4, 4, 2, 8, 4, 4]);
  assert.deepEqual(await sameAsRun('codec.js', ['strict'], batch), [
    0x5a8d,
    { error: 'invalid-digit' }, // lowercase: BadDigit, mapped
    { error: 'invalid-digit' }, // E9H
    { unsupported: 'hex-to-value with 2 digits is not implemented' },
    0x12345678,
    0xdead,
    { error: 'invalid-digit' },
  ]);
  // The deliberately wrong codec: parseInt takes lowercase and stops at E9H.
  assert.deepEqual(await sameAsRun('codec.js', ['lowercase'], h2vBatch(4, ['5a8D', '5A\u00e9D', '0001'], [4, 4, 4])), [0x5a8d, 0x5a, 1]);
});

test('random texts answer as their cases', async () => {
  let seed = 7;
  const random = (n) => { seed = (seed * 1103515245 + 12345) % 2147483648; return Math.floor((seed / 2147483648) * n); };
  const alphabet = '0123456789ABCDEFabcdef +-_x\u00e9\u00ff\u0000\t';
  const texts = Array.from({ length: 300 }, () => Array.from({ length: [2, 4, 4, 4, 8, 9][random(6)] }, () => alphabet[random(alphabet.length)]).join(''));
  const digits = texts.map(() => [4, 4, 4, 8, 2, 3][random(6)]);
  for (const mode of ['strict', 'lowercase']) {
    await sameAsRun('codec.js', [mode], h2vBatch(1, texts, digits));
    await sameAsRun('codec.js', [mode], h2vBatch(2, texts, texts.map(() => 4)));
  }
});

test('value-to-hex: texts, and values wider than the width unsupported', async () => {
  const batch = v2hBatch(13, [23181, 0, 0x12345678, 2 ** 32, 5, 0xffffffff], [4, 4, 4, 8, 2, 8]);
  assert.deepEqual(await sameAsRun('codec.js', ['strict'], batch), [
    '5A8D', '0000', '5678',
    { unsupported: '4294967296 is wider than 32 bits' },
    { unsupported: 'value-to-hex with 2 digits is not implemented' },
    'FFFFFFFF',
  ]);
});

test('an unmapped exception ends the process with its stack and no converted line', async () => {
  for (const texts of [['5A8D', 'DEAD', 'BEEF'], ['DEAD'], ['5a8D', '0001', 'DEAD']]) {
    const { answers, code, stderr } = await drive('codec.js', ['crash'], [HELLO_5, h2vBatch(1, texts, texts.map(() => 4))], { closeStdin: false });
    assert.notEqual(code, 0);
    assert.deepEqual(answers.map((a) => a.type), ['hello'], texts.join());
    assert.match(stderr, /deliberate crash on DEAD/);
    assert.match(stderr, /at strictDecode/);
  }
});

test('run still answers one case at a time after a convert', async () => {
  const { answers, code, stderr } = await drive('codec.js', ['strict'], [
    HELLO_5, h2vBatch(1, ['5A8D'], [4]),
    { type: 'run', cases: [{ id: 2, case: 'x', operation: 'hex-to-value', text: [...Buffer.from('5A8D')], digits: 4 }] },
    SHUTDOWN,
  ]);
  assert.equal(code, 0, stderr);
  assert.deepEqual(answers.slice(1), [{ type: 'converted', id: 1, answers: [0x5a8d] }, { type: 'result', id: 2, value: 0x5a8d }]);
});

// --- in process --------------------------------------------------------------------------------

const asNumber = (text) => text.reduce((v, b) => v * 256 + b, 0) + text.length * 2 ** 40;

test('texts arrive as their bytes, one per character', async () => {
  const answers = await answersOf({ name: 'x', version: '1', decode: (text) => asNumber(text) },
    [HELLO_5, h2vBatch(1, ['5A\u00e9D', '\u00ff', '\u0000A', ''], [4, 4, 4, 4]), SHUTDOWN]);
  assert.deepEqual(answers[1].answers, [0x3541e944 + 4 * 2 ** 40, 0xff + 2 ** 40, 0x41 + 2 * 2 ** 40, 0]);
  // Each text is a Buffer of its own length, whatever the library does with it.
  const seen = [];
  await answersOf({ name: 'x', version: '1', decode: (text) => { seen.push(Buffer.isBuffer(text), text.length); text.fill(0x30); return 0; } },
    [HELLO_5, h2vBatch(1, ['AB', 'CDE'], [4, 4]), SHUTDOWN]);
  assert.deepEqual(seen, [true, 2, true, 3]);
});

test('written bytes come back one character per byte; a string as its UTF-8 bytes', async () => {
  const returns = { 1: Buffer.from([0xe9, 0x41]), 2: '\u00e9', 3: new Uint8Array([0, 0x7f]), 4: [0x80, 0x41], 5: '0ABC' };
  const answers = await answersOf({ name: 'x', version: '1', encode: (value) => returns[value] },
    [HELLO_5, v2hBatch(1, [1, 2, 3, 4, 5], [4, 4, 4, 4, 4]), SHUTDOWN]);
  assert.deepEqual(answers[1].answers, ['\u00e9A', '\u00c3\u00a9', '\u0000\u007f', '\u0080A', '0ABC']);
});

test('a value wider than its width is not asked', async () => {
  const asked = [];
  const answers = await answersOf({
    name: 'x',
    version: '1',
    encode: (value, digits) => { asked.push(value); return value.toString(16).toUpperCase().padStart(digits, '0'); },
    field: { widths: { 2: 8, 4: 16 } },
  }, [HELLO_5, v2hBatch(1, [0x7f, 0x100, 0xffff, 0x10000], [2, 2, 4, 4]), SHUTDOWN]);
  assert.deepEqual(answers[1].answers, ['7F', { unsupported: '256 is wider than 8 bits' }, 'FFFF', { unsupported: '65536 is wider than 16 bits' }]);
  assert.deepEqual(asked, [0x7f, 0xffff]);
});

test('CodecError, Unsupported, what decode returns and promises answer as in run', async () => {
  const returns = { AAAA: 1, BIG1: 0xffffffffn, BIG2: 2n ** 53n + 1n, FLT1: 1.5, STR1: '12', NUL1: null };
  const options = {
    name: 'x',
    version: '1',
    width: 32,
    errors: { TypeError: 'error', RangeError: 'device-range' },
    decode(text) {
      const s = text.toString('latin1');
      if (s === 'CNT1') throw new helper.CodecError('invalid-count');
      if (s === 'DIG1') throw new helper.CodecError('invalid-digit');
      if (s === 'UNS1') throw new helper.Unsupported('not this one');
      if (s === 'ASY1') return Promise.resolve(7);
      if (s === 'REJ1') return Promise.reject(new RangeError('later'));
      if (s === 'ASF1') return Promise.resolve(2.5);
      return returns[s];
    },
  };
  const texts = ['AAAA', 'CNT1', 'DIG1', 'UNS1', 'BIG1', 'FLT1', 'STR1', 'NUL1', 'ASY1', 'REJ1', 'ASF1', 'AAAA', 'BIG2'];
  const batch = h2vBatch(1, texts, texts.map(() => 4));
  const lines = await inProcess(options, [HELLO_5, batch, SHUTDOWN]);
  const run = await answersOf(options, [HELLO_2, { type: 'run', cases: asCases(batch) }, SHUTDOWN]);
  const converted = JSON.parse(lines[1]);
  assert.deepEqual(converted.answers, run.slice(1).map(asItem));
  assert.deepEqual(converted.answers, [
    1, { error: 'invalid-count' }, { error: 'invalid-digit' }, { unsupported: 'not this one' }, 4294967295,
    { error: 'error' }, { error: 'error' }, { error: 'error' }, 7, { error: 'device-range' }, { error: 'error' }, 1,
    Number(2n ** 53n), // 2**53 + 1 as JSON.parse reads it; the line has it exactly:
  ]);
  // A bigint is written as a plain integer, exactly, in one compact line.
  assert.match(lines[1], /^\{"type":"converted","id":1,"answers":\[1,\{"error":"invalid-count"\},.*,4294967295,.*,9007199254740993\]\}$/);
  // Not mapped, a return that is not an integer ends the process (here: serveCodec rejects).
  for (const text of ['STR1', 'ASF1']) {
    await assert.rejects(inProcess({ ...options, errors: {} }, [HELLO_5, h2vBatch(1, ['AAAA', text], [4, 4]), SHUTDOWN]),
      /decode must return an integer/);
  }
});

test('an unmapped exception in process writes no line for its message', async () => {
  const input = new PassThrough();
  const output = new PassThrough();
  let text = '';
  output.on('data', (d) => { text += d; });
  const served = helper.serveCodec({
    name: 'x',
    version: '1',
    decode: (t) => { if (t.toString() === 'DEAD') throw new Error('boom'); return 1; },
    errors: { RangeError: 'invalid-digit' },
    input,
    output,
    stderr: new PassThrough(),
    exit: false,
  });
  for (const m of [HELLO_5, h2vBatch(1, ['AAAA'], [4]), h2vBatch(2, ['AAAA', 'DEAD'], [4, 4])]) input.write(`${JSON.stringify(m)}\n`);
  input.end();
  await assert.rejects(served, /boom/);
  assert.deepEqual(text.split('\n').filter(Boolean).map((l) => JSON.parse(l).type), ['hello', 'converted']);
});

test('what encode returns after an error is converted as before it, and checked as in run', async () => {
  const returns = { 2: Buffer.from([0xe9, 0x41]), 3: '\u00e9', 4: '0A', 5: [0x80], 6: 7, 7: [300] };
  const options = {
    name: 'x',
    version: '1',
    encode: (value) => { if (value === 1) throw new RangeError('first'); return returns[value]; },
    errors: { RangeError: 'error', TypeError: 'invalid-count' },
  };
  const batch = v2hBatch(1, [1, 2, 3, 4, 5, 6, 7], [4, 4, 4, 4, 4, 4, 4]);
  const answers = await answersOf(options, [HELLO_5, batch, SHUTDOWN]);
  const run = await answersOf(options, [HELLO_2, { type: 'run', cases: asCases(batch) }, SHUTDOWN]);
  assert.deepEqual(answers[1].answers, run.slice(1).map(asItem));
  assert.deepEqual(answers[1].answers, [{ error: 'error' }, '\u00e9A', '\u00c3\u00a9', '0A', '\u0080', { error: 'invalid-count' }, { error: 'invalid-count' }]);
});

test('each direction maps its own errors in a batch; an operation not implemented is unsupported', async () => {
  const fail = () => { throw new RangeError('no'); };
  const answers = await answersOf({
    name: 'x', version: '1', decode: fail, encode: fail, errors: { RangeError: 'error' }, decodeErrors: { RangeError: 'invalid-digit' },
  }, [HELLO_5, h2vBatch(1, ['5A8D'], [4]), v2hBatch(2, [1], [4]), SHUTDOWN]);
  assert.deepEqual(answers.slice(1).map((a) => a.answers), [[{ error: 'invalid-digit' }], [{ error: 'error' }]]);
  const only = await answersOf({ name: 'x', version: '1', decode: () => 0 }, [HELLO_5, v2hBatch(7, [1, 2], [4, 4]), SHUTDOWN]);
  assert.deepEqual(only[1], { type: 'converted', id: 7, answers: [{ unsupported: 'value-to-hex is not implemented by x' }, { unsupported: 'value-to-hex is not implemented by x' }] });
});

// --- field shapes per direction ------------------------------------------------------------------

const codecOf = async (options) => (await answersOf({ name: 'x', version: '1', ...options }, [HELLO_5, SHUTDOWN]))[0].capabilities.codec;

test('each direction declares its own field; field serves one that gives none', async () => {
  assert.deepEqual(await codecOf({
    decode: () => 0,
    encode: () => '0',
    field: { wholeFrame: true },
    decodeField: { byteOrder: 'low-first', blanksBetweenPairs: true },
    encodeField: { leadingZeros: false },
  }), {
    'hex-to-value': { width: 16, 'byte-order': 'low-first', 'blanks-between-pairs': true },
    'value-to-hex': { width: 16, 'leading-zeros': false },
  });
  assert.deepEqual(await codecOf({ decode: () => 0, encode: () => '0', field: { wholeFrame: true }, decodeField: { byteOrder: 'low-first' } }), {
    'hex-to-value': { width: 16, 'byte-order': 'low-first' },
    'value-to-hex': { width: 16, 'whole-frame': true },
  });
});

test('blanksBetweenPairs is a shape of hex-to-value only', async () => {
  assert.deepEqual(await codecOf({ decode: () => 0, field: { blanksBetweenPairs: true } }), {
    'hex-to-value': { width: 16, 'blanks-between-pairs': true },
  });
  for (const options of [{ encodeField: { blanksBetweenPairs: true } }, { field: { blanksBetweenPairs: true } }]) {
    assert.throws(() => helper.serveCodec({ name: 'x', version: '1', decode: () => 0, encode: () => '0', ...options, ...idle() }),
      /blanksBetweenPairs.*hex-to-value only/);
  }
});

test('a direction\'s field is checked as field is', () => {
  for (const options of [{ decodeField: { order: 'low' } }, { encodeField: { byteOrder: 'middle' } }, { decodeField: { widths: { 2: 12 } } }]) {
    assert.throws(() => helper.serveCodec({ name: 'x', version: '1', decode: () => 0, encode: () => '0', ...options, ...idle() }), TypeError);
  }
  assert.throws(() => helper.serveCodec({ name: 'x', version: '1', encode: () => '0', decodeField: { byteOrder: 'low-first' }, ...idle() }), /decodeField/);
});
