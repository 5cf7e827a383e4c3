/** One `node --test` test per cross-vendor case for a codec adapter script (testing.js). */
export function codecCases(options: {
  /** The backend's name in the harness's trial names. */
  name: string;
  /** The adapter script that calls serveCodec. */
  adapter: string;
  /** A known-differences file. */
  knownDifferences?: string;
  /** The plc-conformance command [default: $PLC_CONFORMANCE, else the one on PATH]. */
  binary?: string;
  /** Seconds the adapter may take to answer one case [default 5]. */
  timeout?: number;
}): Array<{ row: string; status: string; label: string; detail: string; shown: string }>;

/**
 * The plc-conformance command line that runs `subcommand` on the codec a test file declares with
 * codecCases (what `npx plc-conformance-codec` runs).
 */
export function codecCommand(
  testFile: string,
  subcommand: string,
  args: string[],
  name?: string,
): string[];
