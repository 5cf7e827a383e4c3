'use strict';
// plc-conformance-codec: the command line it builds from a Node test file's codecCases, without
// running the corpus (.ci/check-npm runs it from the packed package for real).
const assert = require('node:assert');
const fs = require('node:fs');
const os = require('node:os');
const path = require('node:path');
const { test } = require('node:test');

const testing = path.join(__dirname, '..', 'testing.js');
const { codecCommand } = require(testing);

function testFile(body) {
  const folder = fs.mkdtempSync(path.join(os.tmpdir(), 'plc-conformance-'));
  const file = path.join(folder, 'conformance.test.js');
  fs.writeFileSync(file, `const { codecCases } = require(${JSON.stringify(testing)});\n${body}`);
  return { folder, file };
}

test('a sweep gets the codec, its timeout and its known differences', () => {
  const { folder, file } = testFile(
    "codecCases({ name: 'strict', adapter: 'strict_codec.js', knownDifferences: 'strict.known.yaml', timeout: 2 });\n",
  );
  try {
    const line = codecCommand(file, 'sweep', ['--generator', 'full']);
    assert.deepStrictEqual(line.slice(0, 3), ['sweep', '--generator', 'full']);
    const backend = line[line.indexOf('--backend') + 1];
    assert.match(backend, /^external:strict=/);
    assert.match(backend, /strict_codec\.js/);
    assert.strictEqual(line[line.indexOf('--timeout') + 1], '2');
    assert.match(line[line.indexOf('--known-differences') + 1], /^strict=.*strict\.known\.yaml$/);
  } finally {
    fs.rmSync(folder, { recursive: true, force: true });
  }
});

test('list gets the codec alone, and a name picks one of several', () => {
  const { folder, file } = testFile(
    "codecCases({ name: 'a', adapter: 'a.js' });\ncodecCases({ name: 'b', adapter: 'b.js' });\n",
  );
  try {
    assert.throws(() => codecCommand(file, 'list', []), /declares 2 codecs: name one with --codec NAME \(a, b\)/);
    const line = codecCommand(file, 'list', [], 'b');
    assert.match(line[line.indexOf('--backend') + 1], /^external:b=/);
    assert.ok(!line.includes('--timeout') && !line.includes('--known-differences'), line.join(' '));
    assert.throws(() => codecCommand(file, 'list', [], 'c'), /has no codec c; its codecs: a, b/);
  } finally {
    fs.rmSync(folder, { recursive: true, force: true });
  }
});
