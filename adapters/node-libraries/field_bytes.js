'use strict';
// How the Modbus adapters here turn a field's bytes, the most significant first, into its value
// and back: the field's arithmetic, not the library's (each library reads and writes the bytes).

// The value of `bytes`, the most significant first.
function valueOf(bytes) {
  let value = 0;
  for (const b of bytes) value = value * 256 + b;
  return value;
}

// The `digits / 2` bytes of `value`, the most significant first.
function bytesOf(value, digits) {
  const bytes = Buffer.alloc(digits / 2);
  bytes.writeUIntBE(value, 0, digits / 2);
  return bytes;
}

module.exports = { valueOf, bytesOf };
