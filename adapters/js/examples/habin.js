#!/usr/bin/env node
'use strict';
// HABIN/HABINP with SM705 off, written with serve(): reads 4 characters two per word, low
// byte first (past the window it reads the fill), signals 2820H when (s), (s)+1 or (d) lie
// past the device range and 3401H for a character that is not 0-9 or A-F.
const { serve, Unsupported } = require('..');

const DIGITS = '0123456789ABCDEF';

serve((c) => {
  if (c.flag('SM705')) throw new Unsupported('SM705 on');
  const s = c.device('s');
  const d = c.device('d');
  if (![s, s.offset(1), d].every((x) => c.exists(x))) return c.fail({ code: 0x2820 });
  let value = 0;
  for (let k = 0; k < 4; k++) {
    const word = c.read(s.offset(k >> 1));
    const digit = DIGITS.indexOf(String.fromCharCode(k % 2 ? word >> 8 : word & 0xff));
    if (digit < 0) return c.fail({ code: 0x3401 });
    value = (value << 4) | digit;
  }
  c.write(d, value);
}, { name: 'habin-js', version: '1', profile: 'mitsubishi-iqr', instructions: ['HABIN', 'HABINP'], flags: { SM705: [false] } });
