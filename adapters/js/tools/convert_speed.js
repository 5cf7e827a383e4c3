#!/usr/bin/env node
'use strict';
// How fast the JavaScript helper answers protocol version 5 `convert` messages, against the
// bare conversion: a timing script, not a test.
//
//   node adapters/js/tools/convert_speed.js [--texts 100000] [--batch 4096] [--alphabet hex|bytes] [--repeat 5]
//
// It starts a codec in a child process through serveCodec, decode = parseInt(text, 16) after a
// check that every character is a hex digit (else a RangeError, mapped to 'invalid-digit'),
// digits [4], sends it the texts in `convert` messages of --batch texts each, all written at
// once as the harness keeps the next one queued, and times from the first message written to
// the last answer read. The bare loop calls the same decode on the same texts, as Buffers, in a
// plain loop (catching the RangeError). Both are the best of --repeat runs.
//
// --alphabet hex (the default): random texts of the 16 uppercase hex digits (every text
// decodes); bytes: random bytes 00H-FFH (almost every text is refused: an exception per item,
// on both sides).
const path = require('node:path');
const { spawn } = require('node:child_process');

const HEX = /^[0-9A-Fa-f]+$/;
function decode(text) {
  const s = text.toString('latin1');
  if (!HEX.test(s)) throw new RangeError(`not a hex digit in ${JSON.stringify(s)}`);
  return parseInt(s, 16);
}

function option(name, fallback) {
  const at = process.argv.indexOf(`--${name}`);
  return at >= 0 ? process.argv[at + 1] : fallback;
}

function bare(texts) {
  const out = new Array(texts.length);
  for (let i = 0; i < texts.length; i += 1) {
    try {
      out[i] = decode(texts[i], 4);
    } catch (error) {
      if (!(error instanceof RangeError)) throw error;
      out[i] = null;
    }
  }
  return out;
}

/** Writes the messages, reads as many answer lines; resolves with [seconds, lines]. */
function roundTrip(child, lines) {
  return new Promise((resolve) => {
    let text = '';
    let seen = 0;
    const start = process.hrtime.bigint();
    const onData = (chunk) => {
      text += chunk;
      for (let at = text.indexOf('\n', text.length - chunk.length); at >= 0; at = text.indexOf('\n', at + 1)) seen += 1;
      if (seen === lines.length) {
        const seconds = Number(process.hrtime.bigint() - start) / 1e9;
        child.stdout.off('data', onData);
        resolve([seconds, text.split('\n').filter(Boolean)]);
      }
    };
    child.stdout.on('data', onData);
    child.stdin.write(lines.join(''));
  });
}

async function main() {
  if (process.argv.includes('--serve')) {
    const { serveCodec } = require('..');
    serveCodec({ name: 'parseint16', version: '1', decode, decodeDigits: [4], errors: { RangeError: 'invalid-digit' } });
    return;
  }
  const n = Number(option('texts', 100000));
  const batch = Number(option('batch', 4096));
  const alphabet = option('alphabet', 'hex');
  const repeat = Number(option('repeat', 5));
  let seed = 5;
  const random = () => { seed = (seed * 1103515245 + 12345) % 2147483648; return seed / 2147483648; };
  const chars = alphabet === 'hex' ? '0123456789ABCDEF' : String.fromCharCode(...Array.from({ length: 256 }, (_, i) => i));
  const strings = Array.from({ length: n }, () => Array.from({ length: 4 }, () => chars[Math.floor(random() * chars.length)]).join(''));
  const buffers = strings.map((s) => Buffer.from(s, 'latin1'));
  const lines = [];
  for (let at = 0, id = 0; at < n; at += batch, id += 1) {
    const texts = strings.slice(at, at + batch);
    lines.push(`${JSON.stringify({ type: 'convert', id, operation: 'hex-to-value', digits: texts.map(() => 4), texts })}\n`);
  }

  const child = spawn(process.execPath, [__filename, '--serve'], { stdio: ['pipe', 'pipe', 'inherit'] });
  child.stdout.setEncoding('utf8');
  const [, [hello]] = await roundTrip(child, [`${JSON.stringify({ type: 'hello', protocol: 5, harness: 'convert_speed' })}\n`]);
  if (JSON.parse(hello).protocol !== 5) throw new Error(`hello: ${hello}`);

  const expected = JSON.stringify(bare(buffers).map((v) => (v === null ? { error: 'invalid-digit' } : v)));
  let bestHelper = Infinity;
  let bestBare = Infinity;
  for (let r = 0; r < repeat; r += 1) {
    const [seconds, answers] = await roundTrip(child, lines);
    bestHelper = Math.min(bestHelper, seconds);
    const got = JSON.stringify(answers.flatMap((l) => JSON.parse(l).answers));
    if (got !== expected) throw new Error("the helper's answers are not the bare decode's");
    const start = process.hrtime.bigint();
    bare(buffers);
    bestBare = Math.min(bestBare, Number(process.hrtime.bigint() - start) / 1e9);
  }
  child.stdin.end(`${JSON.stringify({ type: 'shutdown' })}\n`);
  await new Promise((resolve) => child.on('close', resolve));

  const row = (label, s) => `${label}${(s * 1e3).toFixed(1).padStart(8)} ms  ${(s / n * 1e9).toFixed(0).padStart(6)} ns/text`;
  console.log(`${n} texts (${alphabet}), convert messages of ${batch}, best of ${repeat}`);
  console.log(row('helper (round trip, child process): ', bestHelper));
  console.log(row('bare loop decode (parseInt):        ', bestBare));
  console.log(`ratio helper / bare: ${(bestHelper / bestBare).toFixed(2)}`);
}

main().catch((error) => { console.error(error); process.exit(1); });
