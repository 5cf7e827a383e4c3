'use strict';
// Where the plc-conformance command is: $PLC_CONFORMANCE; else the one this package carries for
// this platform (a package made by tools/pack.js holds vendor/<platform>-<arch>/plc-conformance);
// else the first on PATH that is not this package's own `plc-conformance` script (npm links it
// into node_modules/.bin, which `npm test` and npx put on PATH). null when there is none.
const fs = require('node:fs');
const path = require('node:path');

const EXE = process.platform === 'win32' ? 'plc-conformance.exe' : 'plc-conformance';

/** The command this package carries for `platform`-`arch`, if it carries one. */
function carried(platform = process.platform, arch = process.arch) {
  const file = path.join(__dirname, 'vendor', `${platform}-${arch}`, EXE);
  return fs.existsSync(file) ? file : null;
}

function isOwnScript(file) {
  try {
    return fs.realpathSync(file) === fs.realpathSync(path.join(__dirname, 'bin', 'plc-conformance.js'));
  } catch {
    return false;
  }
}

/** @returns {string | null} */
function findBinary() {
  if (process.env.PLC_CONFORMANCE) return process.env.PLC_CONFORMANCE;
  const own = carried();
  if (own) return own;
  for (const dir of (process.env.PATH || '').split(path.delimiter)) {
    if (!dir) continue;
    const file = path.join(dir, EXE);
    try {
      fs.accessSync(file, fs.constants.X_OK);
    } catch {
      continue;
    }
    if (!isOwnScript(file)) return file;
  }
  return null;
}

module.exports = { findBinary, carried, EXE };
