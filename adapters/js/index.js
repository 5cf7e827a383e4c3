'use strict';
/**
 * Turn JavaScript functions into a plc-conformance external backend.
 *
 * The harness starts the adapter as a child process and speaks the JSON-lines protocol of
 * docs/protocol.md on its stdin and stdout. This module does the protocol; the adapter supplies
 * the conversion, at one of two levels:
 *
 * - codec level (protocol version 2, and 5 for batched conversions): `serveCodec({decode,
 *   encode, ...})`, text to value and value to text, run against the cross-vendor corpus with
 *   no memory, devices or fill, and by `plc-conformance sweep` over millions of texts (version
 *   5: one `convert` message of many texts, answered by one `converted` line);
 * - instruction level (protocol version 1 or 2): `serve(run, {profile, instructions, ...})`,
 *   one function executing one case of a vendor's instruction on a CPU's memory.
 *
 * Throw `new Unsupported('why')` for a case the adapter cannot execute, and
 * `new CodecError('invalid-count')` for an error a codec signals itself. Any other exception
 * (one that `errors` does not map) ends the process with its stack on stderr, which the harness
 * shows with the case ("crashed") before starting the adapter again.
 *
 * No dependencies, Node 18 or later. stdout is the protocol channel: while serving, the module
 * sends console.log and console.info to stderr, so that a library's logging stays out of it.
 */

const readline = require('node:readline');

// The package's version, one with the plc-conformance crate and wheel (tests/versions.rs).
const VERSION = require('./package.json').version;
/**
 * The protocol versions this module speaks: 1 (instruction level), 2 (adds codec level), 3
 * (byte-addressed families), 4 (families whose unit is a 32-bit word) and 5 (adds `convert`:
 * many conversions of a codec in one message, answered by one `converted` line).
 */
const PROTOCOL_VERSIONS = Object.freeze([1, 2, 3, 4, 5]);
const PROTOCOL_VERSION = 2;
/** The first version that carries `convert`: a codec answers a hello of 5 or later with 5, an older one with 2. */
const CONVERT_VERSION = 5;
/** The error classes a codec answers with. */
const ERROR_CLASSES = Object.freeze(['invalid-digit', 'invalid-count', 'device-range', 'error', 'bad-check']);
const HEX_TO_VALUE = 'hex-to-value';
const VALUE_TO_HEX = 'value-to-hex';
const CHECK = 'check';
const VERIFY = 'verify';

/** The case cannot be executed by this backend (answered as "unsupported"). */
class Unsupported extends Error {
  constructor(reason) {
    super(reason);
    this.name = 'Unsupported';
  }
}

/** A codec's refusal of its input, answered as an error of the given class. */
class CodecError extends Error {
  constructor(errorClass, detail) {
    if (!ERROR_CLASSES.includes(errorClass)) {
      throw new TypeError(`error class ${JSON.stringify(errorClass)} is not one of ${ERROR_CLASSES.join(', ')}`);
    }
    super(detail === undefined ? errorClass : `${errorClass}: ${detail}`);
    this.name = 'CodecError';
    this.errorClass = errorClass;
  }
}

/** A word device such as D100: its letter code and number. */
class Device {
  /** `hexadecimal`: the number is written in hexadecimal, as MELSEC numbers W and SW. */
  constructor(code, index, hexadecimal = false) {
    this.code = code;
    this.index = index;
    this.hexadecimal = hexadecimal;
    Object.freeze(this);
  }

  /**
   * A code and the number after it: D100, MB20, DB1.DBB10, U1\G10; for a code in
   * `hexadecimal` (the case's `hexadecimal` list), a hexadecimal number: W1A is index 26.
   */
  static parse(text, hexadecimal = []) {
    const s = String(text);
    for (let split = s.length - 1; split > 0; split -= 1) {
      const code = s.slice(0, split);
      const digits = s.slice(split);
      if (hexadecimal.includes(code) && /^[0-9A-F]+$/.test(digits)) {
        return new Device(code, parseInt(digits, 16), true);
      }
    }
    const m = /^([A-Z](?:[A-Z0-9.\\]*[A-Z])?)([0-9]+)$/.exec(s);
    if (!m) throw new TypeError(`not a device name: ${JSON.stringify(text)}`);
    return new Device(m[1], Number(m[2]));
  }

  /**
   * Device numbers one word spans: 1, or 16 for a digit designation such as K4M (K4M0 is the
   * 16 points M0-M15, and the next word is K4M16).
   */
  points() {
    const m = /^K([1-8])[A-Z]+$/.exec(this.code);
    return m ? 4 * Number(m[1]) : 1;
  }

  /** The device n words after this one, like (s)+n in the manuals (W9, WA, ... in hexadecimal). */
  offset(n) {
    return new Device(this.code, this.index + n * this.points(), this.hexadecimal);
  }

  toString() {
    return `${this.code}${this.hexadecimal ? this.index.toString(16).toUpperCase() : this.index}`;
  }

  /** The device's name, as the protocol writes it: the key of memory and writes. */
  get key() {
    return this.toString();
  }
}

function asDevice(device) {
  return device instanceof Device ? device : Device.parse(device);
}

const DIGITS = '0123456789ABCDEF';

/**
 * The word a device holds when the case does not set it (docs/protocol.md, "Memory"): fill A
 * is 0xA5A5 XOR ((i mod 6) x 0x0101), fill B has "0123456789ABCDEF"[i] in the low byte and
 * [15 - i] in the high byte, with i = word number mod 16 (the device number, or for a digit
 * designation the number divided by 16: K4M32 is word 2).
 * @param {'A'|'B'} fill
 * @param {Device|string|number} device a device, a device name or a device number
 */
function fillWord(fill, device, unit = 'word') {
  const d = typeof device === 'number' ? null : asDevice(device);
  const index = d === null ? device : Math.floor(d.index / d.points());
  const word = (i) => (fill === 'A'
    ? 0xa5a5 ^ ((i % 6) * 0x0101)
    : DIGITS.charCodeAt(i) | (DIGITS.charCodeAt(15 - i) << 8));
  const i = index % 16;
  if (unit === 'byte') return word(i) & 0xff;
  // A 32-bit unit: the word of its position low, that of the position eight on high.
  if (unit === 'dword') return word(i) + word((i + 8) % 16) * 0x10000;
  return word(i);
}

/** The unit a range field carries, and the largest value it holds. */
const UNITS = Object.freeze({ words: ['word', 0xffff], bytes: ['byte', 0xff], dwords: ['dword', 0xffffffff] });

/** One case to execute: its setting, the memory before, and what it did. */
class Case {
  constructor(message) {
    this.id = message.id;
    this.case = message.case;
    this.instruction = message.instruction;
    this.profile = message.profile;
    this.variant = message.variant;
    this.flags = message.flags || {};
    this.ignoredFlags = message.ignored_flags || {};
    this.operands = message.operands || {};
    this.fill = message.fill || 'A';
    // The codes whose numbers are hexadecimal (W1A is the word after W19).
    this.hexadecimal = message.hexadecimal || [];
    // Indirect specification: each pointer's key with the device whose address it holds.
    this.addresses = new Map(Object.entries(message.addresses || {}).map(([pointer, target]) =>
      [Device.parse(pointer, this.hexadecimal).key, Device.parse(target, this.hexadecimal)]));
    this.memory = new Map();
    // A byte-addressed family's ranges carry bytes (protocol version 3), a family whose unit is
    // a 32-bit word dwords (version 4).
    this.unit = 'word';
    for (const block of message.memory || []) {
      const start = Device.parse(block.start, this.hexadecimal);
      const field = Object.keys(UNITS).find((f) => block[f]) || 'words';
      [this.unit] = UNITS[field];
      (block[field] || []).forEach((value, i) => this.memory.set(start.offset(i).key, value));
    }
    this.writes = new Map();
    this.error = null;
  }

  /** A device, or a device name read with the case's numbering. */
  asDevice(device) {
    return device instanceof Device ? device : Device.parse(device, this.hexadecimal);
  }

  /** The flag as this variant's CPU sees it: `ignored_flags` wins over `flags`. */
  flag(name) {
    if (Object.prototype.hasOwnProperty.call(this.ignoredFlags, name)) return Boolean(this.ignoredFlags[name]);
    return Boolean(this.flags[name]);
  }

  /**
   * A device operand as a Device, a constant as a number. An operand given by indirect
   * specification (`@D10`) is the device its pointer addresses (`addresses`), as the CPU
   * resolves it; an emulator with indirect specification of its own reads `operands` and
   * `addresses` as they came, and stores the address in the pointer itself.
   */
  operand(name) {
    if (!Object.prototype.hasOwnProperty.call(this.operands, name)) {
      throw new Unsupported(`${this.instruction} needs operand ${JSON.stringify(name)}`);
    }
    const value = this.operands[name];
    if (typeof value !== 'string') return value;
    const pointer = this.pointer(name);
    if (pointer === null) return Device.parse(value, this.hexadecimal);
    const target = this.addresses.get(pointer.key);
    if (!target) throw new Error(`${value} is indirect and \`addresses\` says nothing of ${pointer}`);
    return target;
  }

  /** The device holding the address of an operand given by indirect specification, else null. */
  pointer(name) {
    const value = this.operands[name];
    return typeof value === 'string' && value.startsWith('@')
      ? Device.parse(value.slice(1), this.hexadecimal)
      : null;
  }

  /** An operand that must be a device. */
  device(name) {
    const value = this.operand(name);
    if (!(value instanceof Device)) {
      throw new Unsupported(`operand ${JSON.stringify(name)} as a constant (K${value}) is not implemented`);
    }
    return value;
  }

  /** A word as the instruction reads it: its latest write, else the window, else the fill. */
  read(device) {
    const d = this.asDevice(device);
    if (this.writes.has(d.key)) return this.writes.get(d.key);
    if (this.memory.has(d.key)) return this.memory.get(d.key);
    return fillWord(this.fill, d, this.unit);
  }

  /**
   * Whether the word exists on the case's variant, for words within 64 of a device operand:
   * the window covers that span and is cut to the words that exist.
   */
  exists(device) {
    return this.memory.has(this.asDevice(device).key);
  }

  /** A write of one unit (a word, a byte or a 32-bit word, as the case's memory is). */
  write(device, value) {
    const d = this.asDevice(device);
    const most = Object.values(UNITS).find(([unit]) => unit === this.unit)[1];
    if (!Number.isInteger(value) || value < 0 || value > most) {
      throw new RangeError(`${d}: ${value} does not fit a ${this.unit}`);
    }
    this.writes.set(d.key, value);
  }

  /** Signal an operation error: `{code: 0x3401}` or `{flag: 'M8004'}`. */
  fail({ code, flag } = {}) {
    if (flag !== undefined) this.error = { flag: String(flag) };
    else if (Number.isInteger(code)) this.error = { code };
    else throw new TypeError('fail needs {code} or {flag}');
  }

  answer() {
    return { type: 'result', id: this.id, writes: Object.fromEntries(this.writes), error: this.error };
  }
}

/** The version to answer a harness hello with. */
function negotiate(message, log) {
  const asked = message.protocol === undefined ? 1 : message.protocol;
  if (PROTOCOL_VERSIONS.includes(asked)) return asked;
  // A newer harness accepts the versions before its own: answer the newest this module speaks.
  if (asked > Math.max(...PROTOCOL_VERSIONS)) return Math.max(...PROTOCOL_VERSIONS);
  log(`plc-conformance-adapter: the harness speaks protocol ${asked}; this adapter speaks ${PROTOCOL_VERSIONS.join(' or ')}\n`);
  return PROTOCOL_VERSION;
}

/** JSON with bigint values written as plain integers. */
function encodeLine(message) {
  return JSON.stringify(message, (_, v) => (typeof v === 'bigint' ? `\u0000big${v}` : v))
    .replace(/"\\u0000big(-?[0-9]+)"/g, '$1') + '\n';
}

/**
 * The JSON-lines loop: reads the harness's messages one line at a time and answers each in
 * order, awaiting an answer that is a promise before reading on. Resolves on shutdown or at the
 * end of input; by default the process then exits once stdout is flushed.
 */
async function loop(hello, answer, options, convert) {
  const input = options.input || process.stdin;
  const output = options.output || process.stdout;
  const stderr = options.stderr || process.stderr;
  const ownProcess = !options.output;
  const exit = options.exit !== undefined ? options.exit : ownProcess;
  const write = (message) => output.write(encodeLine(message));
  const log = (text) => stderr.write(text);

  const saved = { log: console.log, info: console.info };
  if (ownProcess) {
    console.log = console.info = (...args) => console.error(...args);
  }
  const done = (code) => new Promise((resolve) => {
    if (ownProcess) Object.assign(console, saved);
    if (!exit) return resolve(code);
    // Exit once every answer has left: a write callback runs after the earlier ones.
    output.write('', () => process.exit(code));
  });

  const lines = readline.createInterface({ input, crlfDelay: Infinity, terminal: false });
  try {
    for await (const line of lines) {
      if (!line.trim()) continue;
      const message = JSON.parse(line);
      if (message.type === 'hello') {
        write(await hello(message, log));
      } else if (message.type === 'convert' && convert) {
        // One line for the whole message, written once: an exception that ends the process
        // leaves none of its answers, and the harness asks the items again one by one.
        const line = convert(message);
        output.write(typeof line === 'string' ? line : await line);
      } else if (message.type === 'run') {
        // Each answer goes out at once: the harness's time limit for a case runs from the
        // previous answer.
        for (const request of message.cases) write(await answer(request));
      } else if (message.type === 'shutdown') {
        lines.close();
        return done(0);
      } else {
        throw new Error(`unknown message type ${JSON.stringify(message.type)}`);
      }
    }
    return done(0);
  } catch (error) {
    lines.close();
    log(`${error && error.stack ? error.stack : error}\n`);
    if (!exit) {
      if (ownProcess) Object.assign(console, saved);
      throw error;
    }
    return done(1);
  }
}

/**
 * Answers the harness as an instruction-level backend until shutdown or the end of input.
 * @param {(c: Case) => void | Promise<void>} run executes one case
 * @param {object} options name, version, profile, instructions, variants, flags; and for
 *   tests: input, output, stderr (streams) and exit (false: resolve instead of exiting)
 */
function serve(run, options) {
  const { name, version, profile, instructions, variants, flags } = options || {};
  if (!name || !version || !profile || !instructions) {
    throw new TypeError('serve needs name, version, profile and instructions');
  }
  const capabilities = { profile, instructions: [...instructions] };
  if (variants) capabilities.variants = [...variants];
  if (flags && Object.keys(flags).length) {
    capabilities.flags = Object.fromEntries(Object.entries(flags).map(([k, vs]) => [k, vs.map(Boolean)]));
  }
  const hello = (message, log) => ({
    type: 'hello', protocol: negotiate(message, log), backend: { name, version }, capabilities,
  });
  const answer = async (request) => {
    if (request.instruction === undefined) {
      return { type: 'unsupported', id: request.id, reason: `${name} is an instruction-level backend` };
    }
    const c = new Case(request);
    try {
      await run(c);
    } catch (error) {
      if (error instanceof Unsupported) return { type: 'unsupported', id: c.id, reason: error.message };
      throw error;
    }
    return c.answer();
  };
  return loop(hello, answer, options);
}

const FIELD_KEYS = {
  widths: 'widths',
  variable: 'variable',
  leadingZeros: 'leading-zeros',
  byteOrder: 'byte-order',
  wholeFrame: 'whole-frame',
  blanksBetweenPairs: 'blanks-between-pairs',
};

function codecCapability(digits, width, reading, field, operation = HEX_TO_VALUE, label = 'field') {
  if (width !== 16 && width !== 32) throw new TypeError(`width must be 16 or 32, not ${width}`);
  const capability = { width };
  if (reading !== undefined && reading !== null) capability.reading = String(reading);
  if (digits !== undefined && digits !== null) {
    const counts = [...new Set(digits)].sort((a, b) => a - b);
    if (!counts.length || !counts.every((d) => Number.isInteger(d) && d >= 1 && d <= 8)) {
      throw new TypeError(`digits must be counts from 1 to 8, not ${JSON.stringify(digits)}`);
    }
    capability.digits = counts;
  }
  for (const [key, value] of Object.entries(field || {})) {
    const wire = FIELD_KEYS[key];
    if (!wire) throw new TypeError(`${label}: ${key} is not one of ${Object.keys(FIELD_KEYS).join(', ')}`);
    if (key === 'widths') {
      const widths = {};
      for (const [d, w] of Object.entries(value)) {
        if (!(Number(d) >= 1) || ![8, 16, 32].includes(w)) {
          throw new TypeError(`${label} widths: digit counts to 8, 16 or 32 bits, not ${JSON.stringify(value)}`);
        }
        widths[String(Number(d))] = w;
      }
      capability.widths = widths;
    } else if (key === 'byteOrder') {
      if (value !== 'high-first' && value !== 'low-first') {
        throw new TypeError(`${label} byteOrder: 'high-first' or 'low-first', not ${JSON.stringify(value)}`);
      }
      capability[wire] = value;
    } else if (key === 'blanksBetweenPairs' && operation !== HEX_TO_VALUE) {
      // Only a text is read: value -> text has no blanks to skip (the harness refuses it).
      throw new TypeError(`${label} blanksBetweenPairs: a shape of hex-to-value only (text -> value skips blanks between byte pairs); give it in decodeField, not for value-to-hex`);
    } else {
      capability[wire] = Boolean(value);
    }
  }
  return capability;
}

/** Whether a declared operation takes a digit count: its digits, or its field's widths. */
function takes(declared, digits) {
  if (declared.digits) return declared.digits.includes(digits);
  if (declared.widths) return String(digits) in declared.widths;
  return digits >= 1 && digits <= 8;
}

function widthOf(declared, digits) {
  return (declared.widths && declared.widths[String(digits)]) || declared.width;
}

/** The error class `errors` gives an exception (its nearest listed class), or undefined. */
function errorClassOf(error, errors) {
  if (error instanceof CodecError) return error.errorClass;
  if (error === null || typeof error !== 'object') return undefined;
  for (let p = Object.getPrototypeOf(error); p && p !== Object.prototype; p = Object.getPrototypeOf(p)) {
    const ctor = p.constructor;
    if (errors.byClass.has(ctor)) return errors.byClass.get(ctor);
    if (ctor && errors.byName.has(ctor.name)) return errors.byName.get(ctor.name);
  }
  if (errors.byName.has(error.name)) return errors.byName.get(error.name);
  return undefined;
}

/** errors as a Map or [[class, errorClass]] (by class) or {Name: errorClass} (by name). */
function errorTable(errors) {
  const byClass = new Map();
  const byName = new Map();
  const entries = errors instanceof Map || Array.isArray(errors) ? [...errors] : Object.entries(errors || {});
  for (const [key, errorClass] of entries) {
    if (!ERROR_CLASSES.includes(errorClass)) {
      throw new TypeError(`errors: ${JSON.stringify(errorClass)} is not one of ${ERROR_CLASSES.join(', ')}`);
    }
    if (typeof key === 'function') byClass.set(key, errorClass);
    else byName.set(String(key), errorClass);
  }
  return { byClass, byName };
}

function textBytes(text) {
  if (typeof text === 'string') return [...Buffer.from(text, 'utf8')];
  if (text instanceof Uint8Array || Array.isArray(text)) {
    const bytes = [...text];
    if (bytes.every((b) => Number.isInteger(b) && b >= 0 && b <= 255)) return bytes;
  }
  throw new TypeError(`encode must return a Buffer, Uint8Array, byte array or string, not ${typeof text}`);
}

// --- protocol version 5: `convert`, many conversions of one operation in one message ----------
//
// A sweep sends millions of texts; the loop below is what a conversion costs beyond the
// library's own call. Each item answers exactly what a `run` case with the same text (or value)
// and digit count answers; the library is called synchronously, and a promise it returns is
// awaited (the rest of the message then goes on after it). Plain answers are the library's
// numbers and strings themselves; the line is one JSON.stringify and one write.

function isThenable(value) {
  return value !== null && (typeof value === 'object' || typeof value === 'function')
    && typeof value.then === 'function';
}

/** The answers that are no plain value or text, shared: one object per error class. */
const ERROR_ANSWERS = Object.freeze(Object.fromEntries(ERROR_CLASSES.map((c) => [c, Object.freeze({ error: c })])));

/** The answer to an exception, as the per-case path answers it; one that is not mapped is thrown on. */
function failed(error, classify) {
  if (error instanceof Unsupported) return { unsupported: error.message };
  const errorClass = classify(error);
  if (errorClass === undefined) throw error;
  return ERROR_ANSWERS[errorClass];
}

/**
 * out[i] = item(i) for each item from `from` on, an exception as failed() answers it. Returns
 * out, or, once an item returns a promise, a promise of out that goes on after it settles.
 */
function runItems(out, from, item, classify) {
  const n = out.length;
  for (let i = from; i < n; i += 1) {
    let answer;
    try {
      answer = item(i);
    } catch (error) {
      out[i] = failed(error, classify);
      continue;
    }
    if (isThenable(answer)) {
      return Promise.resolve(answer).then((a) => a, (error) => failed(error, classify)).then((a) => {
        out[i] = a;
        return runItems(out, i + 1, item, classify);
      });
    }
    out[i] = answer;
  }
  return out;
}

/** Characters above U+00FF: a text of a convert message is one character per byte. */
const NOT_LATIN1 = /[^\u0000-\u00ff]/;
/** A string whose UTF-8 bytes are its characters. */
const ASCII = /^[\u0000-\u007f]*$/;

/** The texts of a convert message as Buffers, one byte per character. */
function latin1Buffers(texts) {
  const joined = texts.join('');
  if (NOT_LATIN1.test(joined) || texts.some((t) => typeof t !== 'string')) {
    throw new TypeError('convert: a text that is not a string of characters U+0000-U+00FF');
  }
  // One Buffer for the whole message, and a view of it per text.
  const all = Buffer.from(joined, 'latin1');
  const buffers = new Array(texts.length);
  let at = 0;
  for (let i = 0; i < texts.length; i += 1) {
    const end = at + texts[i].length;
    buffers[i] = all.subarray(at, end);
    at = end;
  }
  return buffers;
}

/** What encode returned, as the characters of the answer: the per-case conversion and check. */
function latin1Text(text) {
  if (typeof text === 'string' && ASCII.test(text)) return text;
  return Buffer.from(textBytes(text)).toString('latin1');
}

/** The `converted` line: one JSON.stringify, bigint values written as plain integers. */
function convertedLine(id, answers, big) {
  if (!big) return `${JSON.stringify({ type: 'converted', id, answers })}\n`;
  const items = answers.map((a) => (typeof a === 'bigint' ? a.toString() : JSON.stringify(a)));
  return `{"type":"converted","id":${JSON.stringify(id)},"answers":[${items.join(',')}]}\n`;
}

/**
 * Answers the harness as a codec-level backend until shutdown or the end of input. Speaks
 * protocol version 2 (`run`: one answer line per case) and 5 (also `convert`: the texts or
 * values of one operation in one message, answered by one `converted` line, which is what makes
 * a sweep of millions of texts fast): 5 to a harness that speaks it, else 2. Each item of a
 * `convert` answers exactly what a `run` case with the same input answers; an exception
 * `errors` does not map ends the process with its stack and none of the message's answers (the
 * harness then asks its items one by one).
 * @param {object} options
 *   decode(text: Buffer, digits) -> number | bigint (hex-to-value; absent: not implemented);
 *   encode(value: number, digits) -> Buffer | Uint8Array | number[] | string (value-to-hex);
 *   name, version; decodeDigits, encodeDigits: the digit counts implemented (absent: 1-8);
 *   width: 16 (default) or 32; errors: how the library's exceptions answer, a Map of error
 *   constructors or an object keyed by error name, to 'invalid-digit', 'invalid-count',
 *   'device-range' or 'error'; decodeErrors, encodeErrors: the same for one direction, before
 *   `errors`. Either function may return a promise. decodeReading,
 *   encodeReading: the built-in reading each follows, as `plc-conformance sweep` names it
 *   ('fx5/hexa-16bit'): a sweep of the operation judges the codec against it. field: what
 *   the protocol's field is, where not a fixed run of digits (docs/protocol.md, "Field
 *   shapes"): { widths: { 2: 8, 4: 16 }, variable: true, leadingZeros: false,
 *   byteOrder: 'low-first', wholeFrame: true, blanksBetweenPairs: true }; blanksBetweenPairs
 *   (decode skips blanks between byte pairs, as Python's bytes.fromhex) is a shape of
 *   hex-to-value only, refused for value-to-hex. decodeField, encodeField: the field of one
 *   direction, used instead of `field` for it (a library that reads the low byte first but
 *   writes the high byte first: decodeField: { byteOrder: 'low-first' }). protocol: the
 *   communication protocol whose fields the library implements ('mc-ascii', 'modbus-ascii',
 *   'fx-computer-link', 'mewtocol-com', 'omron-host-link', 'keyence-kv-l2'): the codec is
 *   judged by that protocol's corpus, each difference naming its rule and page; fields: the
 *   profile's fields implemented (absent: every one); crossVendor: true to run the
 *   cross-vendor corpus too; check(span: Buffer) -> the check characters (LRC, sum check,
 *   BCC, FCS); verify(frame: Buffer) -> boolean, the span followed by its check characters
 *   accepted or not ('bad-check').
 */
function serveCodec(options) {
  const {
    decode, encode, name, version, decodeDigits, encodeDigits, width = 16, decodeReading, encodeReading,
    field, decodeField, encodeField, protocol, fields, crossVendor = false, check, verify,
  } = options || {};
  if (!name || !version) throw new TypeError('serveCodec needs name and version');
  if (!decode && !encode && !check && !verify) throw new TypeError('serveCodec needs decode, encode, check or verify');
  if (protocol === undefined && (fields !== undefined || crossVendor || check || verify)) {
    throw new TypeError('serveCodec: fields, crossVendor, check and verify belong to a protocol: give protocol too');
  }
  if (decodeField !== undefined && !decode) throw new TypeError('serveCodec: decodeField is the field of decode, which is not given');
  if (encodeField !== undefined && !encode) throw new TypeError('serveCodec: encodeField is the field of encode, which is not given');
  // Each direction's table: its own entries (decodeErrors, encodeErrors) before the shared ones.
  const shared = errorTable(options.errors);
  const own = {
    [HEX_TO_VALUE]: errorTable(options.decodeErrors),
    [VALUE_TO_HEX]: errorTable(options.encodeErrors),
    [CHECK]: errorTable(options.decodeErrors),
    [VERIFY]: errorTable(options.decodeErrors),
  };
  const codec = {};
  if (decode) {
    codec[HEX_TO_VALUE] = decodeField === undefined
      ? codecCapability(decodeDigits, width, decodeReading, field, HEX_TO_VALUE)
      : codecCapability(decodeDigits, width, decodeReading, decodeField, HEX_TO_VALUE, 'decodeField');
  }
  if (encode) {
    codec[VALUE_TO_HEX] = encodeField === undefined
      ? codecCapability(encodeDigits, width, encodeReading, field, VALUE_TO_HEX)
      : codecCapability(encodeDigits, width, encodeReading, encodeField, VALUE_TO_HEX, 'encodeField');
  }

  // A protocol's codec: judged by that protocol's corpus (docs/protocol.md, "A protocol's fields").
  if (check) codec[CHECK] = {};
  if (verify) codec[VERIFY] = {};
  if (protocol !== undefined) {
    codec.protocol = protocol;
    if (fields !== undefined) codec.fields = [...fields];
    if (crossVendor) codec['cross-vendor'] = true;
  }

  const hello = (message, log) => {
    if (!(message.protocol >= 2)) {
      log(`plc-conformance-adapter: ${name} is a codec-level backend, which needs protocol version 2; the harness speaks ${message.protocol}\n`);
    }
    // 5 (convert) to a harness that speaks it (or a newer one), else 2 as before.
    const protocol = message.protocol >= CONVERT_VERSION ? CONVERT_VERSION : 2;
    return { type: 'hello', protocol, backend: { name, version }, capabilities: { codec } };
  };
  const answer = async (request) => {
    const { id, operation, digits } = request;
    try {
      // A check character's length is its protocol's.
      const declared = operation === CHECK || operation === VERIFY ? undefined : codec[operation];
      if (declared && !takes(declared, digits)) {
        // Outside the declared capabilities: the harness skips such cases.
        throw new Unsupported(`${operation} with ${digits} digits is not implemented`);
      }
      if (operation === HEX_TO_VALUE && decode) {
        const value = await decode(Buffer.from(request.text), digits);
        if (typeof value !== 'bigint' && !Number.isInteger(value)) {
          throw new TypeError(`decode must return an integer, not ${JSON.stringify(value)}`);
        }
        return { type: 'result', id, value };
      }
      if (operation === VALUE_TO_HEX && encode) {
        if (!(request.value >= 0 && request.value < 2 ** widthOf(declared, digits))) {
          throw new Unsupported(`${request.value} is wider than ${widthOf(declared, digits)} bits`);
        }
        return { type: 'result', id, text: textBytes(await encode(request.value, digits)) };
      }
      if (operation === CHECK && check) {
        return { type: 'result', id, text: textBytes(await check(Buffer.from(request.text))) };
      }
      if (operation === VERIFY && verify) {
        if (await verify(Buffer.from(request.text))) return { type: 'result', id, accepted: true };
        return { type: 'result', id, error: 'bad-check' };
      }
      const what = operation !== undefined ? operation : `instruction ${request.instruction}`;
      throw new Unsupported(`${what} is not implemented by ${name}`);
    } catch (error) {
      if (error instanceof Unsupported) return { type: 'unsupported', id, reason: error.message };
      const errorClass = (own[operation] && errorClassOf(error, own[operation])) || errorClassOf(error, shared);
      if (errorClass === undefined) throw error;
      return { type: 'result', id, error: errorClass };
    }
  };

  // Version 5: everything that does not depend on the item is resolved once per message.
  const convert = (message) => {
    const { id, operation, digits } = message;
    let items;
    if (operation === HEX_TO_VALUE) items = message.texts;
    else if (operation === VALUE_TO_HEX) items = message.values;
    else items = message.texts || message.values || [];
    if (!Array.isArray(items) || !Array.isArray(digits) || items.length !== digits.length) {
      throw new TypeError(`convert ${JSON.stringify(id)}: one digit count per item is needed`);
    }
    const declared = codec[operation];
    const table = own[operation];
    const classify = (error) => (table && errorClassOf(error, table)) || errorClassOf(error, shared);
    const out = new Array(items.length);
    let big = false;
    let item;
    if (!declared) {
      const reason = { unsupported: `${operation} is not implemented by ${name}` };
      out.fill(reason);
      return convertedLine(id, out, false);
    }
    if (operation === HEX_TO_VALUE) {
      const texts = latin1Buffers(items);
      const checked = (value) => {
        if (typeof value === 'bigint') big = true;
        else if (!Number.isInteger(value)) throw new TypeError(`decode must return an integer, not ${JSON.stringify(value)}`);
        return value;
      };
      item = (i) => {
        const d = digits[i];
        if (!takes(declared, d)) throw new Unsupported(`${HEX_TO_VALUE} with ${d} digits is not implemented`);
        const value = decode(texts[i], d);
        if (typeof value === 'number' && Number.isInteger(value)) return value;
        return isThenable(value) ? Promise.resolve(value).then(checked) : checked(value);
      };
    } else {
      item = (i) => {
        const d = digits[i];
        if (!takes(declared, d)) throw new Unsupported(`${VALUE_TO_HEX} with ${d} digits is not implemented`);
        const value = items[i];
        if (!(value >= 0 && value < 2 ** widthOf(declared, d))) {
          throw new Unsupported(`${value} is wider than ${widthOf(declared, d)} bits`);
        }
        const text = encode(value, d);
        return isThenable(text) ? Promise.resolve(text).then(latin1Text) : latin1Text(text);
      };
    }
    const answers = runItems(out, 0, item, classify);
    return isThenable(answers) ? answers.then((a) => convertedLine(id, a, big)) : convertedLine(id, answers, big);
  };
  return loop(hello, answer, options, convert);
}

/**
 * The named top-level functions of a CommonJS module file, including ones it does not export.
 *
 * Many protocol libraries keep their codec functions private. This loads a separate copy of
 * the module's source (the package's files are not changed, and the copy `require` returns
 * is not touched) and hands back the functions asked for.
 * @param {string} file the module's path, e.g. require.resolve('mcprotocol') from the adapter
 * @param {string[]} names
 */
function privateFunctions(file, names) {
  const fs = require('node:fs');
  const path = require('node:path');
  const vm = require('node:vm');
  const Module = require('node:module');
  const pick = names.map((n) => `${JSON.stringify(n)}: typeof ${n} === 'undefined' ? undefined : ${n}`).join(', ');
  const source = `${fs.readFileSync(file, 'utf8')}\n;module.exports = {${pick}};`;
  const wrapper = vm.runInThisContext(Module.wrap(source), { filename: file });
  const module = { exports: {} };
  wrapper.call(module.exports, module.exports, Module.createRequire(file), module, file, path.dirname(file));
  for (const n of names) {
    if (typeof module.exports[n] !== 'function') throw new TypeError(`${file} has no top-level function ${n}`);
  }
  return module.exports;
}

module.exports = {
  VERSION,
  PROTOCOL_VERSION,
  PROTOCOL_VERSIONS,
  CONVERT_VERSION,
  ERROR_CLASSES,
  Case,
  CodecError,
  Device,
  Unsupported,
  fillWord,
  privateFunctions,
  serve,
  serveCodec,
};
