// Types of plc-conformance-adapter (index.js). The protocol: docs/protocol.md.
/// <reference types="node" />
import type { Readable, Writable } from 'node:stream';

export const VERSION: string;
/** The version a codec answers a harness older than version 5 with (and the fallback). */
export const PROTOCOL_VERSION: 2;
/**
 * The protocol versions this module speaks: 1 (instruction level), 2 (codec level), 3
 * (byte-addressed families), 4 (32-bit units) and 5 (`convert`: many conversions of a codec in
 * one message, answered by one `converted` line).
 */
export const PROTOCOL_VERSIONS: readonly [1, 2, 3, 4, 5];
/** The first version that carries `convert`: a codec answers a hello of 5 or later with 5, an older one with 2. */
export const CONVERT_VERSION: 5;
export type ErrorClass = 'invalid-digit' | 'invalid-count' | 'device-range' | 'error';
export const ERROR_CLASSES: readonly ErrorClass[];

/** Thrown by an adapter for a case it cannot execute: answered as "unsupported". */
export class Unsupported extends Error {
  constructor(reason: string);
}

/** Thrown by a codec to answer an error of the given class. */
export class CodecError extends Error {
  constructor(errorClass: ErrorClass, detail?: unknown);
  readonly errorClass: ErrorClass;
}

/** A word device such as D100. */
export class Device {
  constructor(code: string, index: number);
  static parse(text: string): Device;
  readonly code: string;
  readonly index: number;
  /** The device n words after this one, like (s)+n in the manuals. */
  offset(n: number): Device;
  toString(): string;
}

/** The word a device holds when the case does not set it. */
export function fillWord(fill: 'A' | 'B', device: Device | string | number): number;

/** One case of an instruction-level run. */
export class Case {
  readonly id: number;
  readonly case: string;
  readonly instruction: string;
  readonly profile: string;
  readonly variant: string;
  readonly flags: Record<string, boolean>;
  readonly ignoredFlags: Record<string, boolean>;
  readonly operands: Record<string, string | number>;
  readonly fill: 'A' | 'B';
  /** Indirect specification: a pointer's key ("D10") -> the device whose address it holds. */
  readonly addresses: Map<string, Device>;
  /** The window: "D100" -> word. */
  readonly memory: Map<string, number>;
  readonly writes: Map<string, number>;
  error: { code: number } | { flag: string } | null;
  /** The flag as this variant's CPU sees it (ignored_flags wins). */
  flag(name: string): boolean;
  /** A device operand as a Device, a constant as a number; `@D10` is the device D10 addresses. */
  operand(name: string): Device | number;
  /** The pointer of an operand given by indirect specification (`@D10`: D10), else null. */
  pointer(name: string): Device | null;
  /** An operand that must be a device (else Unsupported). */
  device(name: string): Device;
  /** The word: its latest write, else the window, else the fill. */
  read(device: Device | string): number;
  /** Whether the word is in the window (exists on the variant, near an operand). */
  exists(device: Device | string): boolean;
  write(device: Device | string, value: number): void;
  fail(error: { code: number } | { flag: string }): void;
}

/** Streams and exit behaviour, for running a backend in process (tests). */
export interface LoopOptions {
  input?: Readable;
  output?: Writable;
  stderr?: Writable;
  /** Exit the process at shutdown (default: true when serving the process's own stdout). */
  exit?: boolean;
}

export interface InstructionOptions extends LoopOptions {
  name: string;
  version: string;
  /** The vendor profile implemented, e.g. "mitsubishi-iqr". */
  profile: string;
  instructions: string[];
  /** The profile variants implemented (all when absent). */
  variants?: string[];
  /** For a flag implemented in one setting only, the settings implemented. */
  flags?: Record<string, boolean[]>;
}

export function serve(run: (c: Case) => void | Promise<void>, options: InstructionOptions): Promise<number>;

export type ErrorMap =
  | Map<new (...args: any[]) => Error, ErrorClass>
  | Array<[new (...args: any[]) => Error, ErrorClass]>
  | Record<string, ErrorClass>;

/**
 * What the protocol's field is, where it is not a fixed run of digits, most significant first
 * (docs/protocol.md, "Field shapes"). The harness decides which cases each shape skips or reads
 * otherwise; the helper only declares the shape in its hello.
 */
export interface FieldShape {
  /** The value width in bits for each digit count taken: { 2: 8, 4: 16 }. */
  widths?: Record<number, 8 | 16 | 32>;
  /** A token of whatever length: decode reads the characters it is given. */
  variable?: boolean;
  /** Whether encode writes the field's leading zeros (true when absent). */
  leadingZeros?: boolean;
  /** 'low-first': the first character pair is the low byte (the MEWTOCOL order). */
  byteOrder?: 'high-first' | 'low-first';
  /** The field is checked with the frame around it: a text with characters after it is not asked. */
  wholeFrame?: boolean;
  /**
   * Hex-to-value only: decode skips blanks (20H) between byte pairs, as Python's
   * `bytes.fromhex`. Given for value-to-hex (in `encodeField`, or in `field` with an `encode`),
   * serveCodec throws a TypeError at start-up.
   */
  blanksBetweenPairs?: boolean;
}

/**
 * A codec-level backend. It answers protocol version 2 (`run`, one case per answer line) and 5
 * (also `convert`: the texts or values of one operation in one message, answered by one
 * `converted` line; what a sweep of millions of texts uses). Each item of a `convert` answers
 * exactly what a `run` case with the same input answers: the value (or the written bytes, as a
 * latin-1 string), `{error: class}`, or `{unsupported: reason}`; an exception `errors` does not
 * map ends the process with its stack and none of the message's answers.
 */
export interface CodecOptions extends LoopOptions {
  /** hex-to-value: the characters (any byte values) and the digit count -> the value. */
  decode?: (text: Buffer, digits: number) => number | bigint | Promise<number | bigint>;
  /** value-to-hex: the value and the digit count -> the text (read up to its first 00H). */
  encode?: (value: number, digits: number) => Uint8Array | number[] | string | Promise<Uint8Array | number[] | string>;
  name: string;
  version: string;
  /** The digit counts decode implements (any count 1-8 when absent). */
  decodeDigits?: number[];
  /** The digit counts encode implements (any count 1-8 when absent). */
  encodeDigits?: number[];
  /** The value width in bits (default 16). */
  width?: 16 | 32;
  /** The built-in reading decode follows, as `plc-conformance sweep` names it ('fx5/hexa-16bit'). */
  decodeReading?: string;
  /** The built-in reading encode follows ('fx5/asci-16bit'). */
  encodeReading?: string;
  /** What the protocol's field is, in both directions (unless decodeField or encodeField says otherwise). */
  field?: FieldShape;
  /**
   * The field of hex-to-value, used instead of `field`: a library that reads the low byte first
   * but writes the high byte first gives `decodeField: { byteOrder: 'low-first' }`.
   */
  decodeField?: FieldShape;
  /** The field of value-to-hex, used instead of `field` (no `blanksBetweenPairs`). */
  encodeField?: Omit<FieldShape, 'blanksBetweenPairs'>;
  /** How the library's exceptions answer: by constructor, or by error name. */
  errors?: ErrorMap;
  /** The same for decode alone, before `errors`. */
  decodeErrors?: ErrorMap;
  /** The same for encode alone, before `errors`. */
  encodeErrors?: ErrorMap;
}

export function serveCodec(options: CodecOptions): Promise<number>;

/**
 * The named top-level functions of a CommonJS module file, exported or not, from a separate
 * copy of its source (the package is not changed). file: e.g. require.resolve('mcprotocol').
 */
export function privateFunctions(file: string, names: string[]): Record<string, (...args: any[]) => any>;
