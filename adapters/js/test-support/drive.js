'use strict';
// Runs an example of the helper as the harness runs a backend: the one driver of test/ (kept out
// of test/, which node --test runs whole).
const path = require('node:path');
const { spawn } = require('node:child_process');

const EXAMPLES = path.join(__dirname, '..', 'examples');

/** Runs a fixture with the given protocol messages on stdin; resolves with what it did. */
function drive(fixture, args, messages, { closeStdin = true } = {}) {
  return new Promise((resolve, reject) => {
    const child = spawn(process.execPath, [path.join(EXAMPLES, fixture), ...args], { stdio: ['pipe', 'pipe', 'pipe'] });
    let stdout = '';
    let stderr = '';
    child.stdout.on('data', (d) => { stdout += d; });
    child.stderr.on('data', (d) => { stderr += d; });
    const timer = setTimeout(() => { child.kill('SIGKILL'); reject(new Error(`${fixture} hung; stderr: ${stderr}`)); }, 10000);
    child.on('error', reject);
    child.on('close', (code, signal) => {
      clearTimeout(timer);
      const lines = stdout.split('\n').filter((l) => l !== '');
      resolve({ lines, answers: lines.map((l) => JSON.parse(l)), stderr, code, signal });
    });
    child.stdin.on('error', () => {}); // a crashed backend closes its end early
    for (const m of messages) child.stdin.write(`${JSON.stringify(m)}\n`);
    if (closeStdin) child.stdin.end();
  });
}

module.exports = { EXAMPLES, drive };
