//! The generated program as a rung list (for WindLDR) and its setup checklist, for the IDEC
//! MicroSmart CPUs (FC4A, FC6A).
//!
//! WindLDR edits ladder only and imports no program text, so the program cannot be pasted as
//! the MELSEC one is (`program.rs`): a bench user enters it by hand, rung by rung, from
//! this list. Each rung is written as IDEC's manuals write an instruction list (`LOD`, `AND`,
//! `ANDN`, `OR`, `OUT`, `RST`, `SOTU`, then advanced instructions with their operand fields
//! `S1=... S2=... D1=... REP=...`), one numbered line per rung, so that every line is one rung
//! to draw: its contacts, then its one output. The program is the MELSEC one rung for rung: the
//! same mailbox offsets, the same states, the same proof of execution. What ladder cannot say
//! the way structured text does is carried by eight internal relays ([`RELAYS`]): the state the
//! scan started in is compared once at the top, so no transition made further down takes
//! effect before the next scan, as with a CASE. Every instruction form no quoted manual page
//! prints is marked *check* in the setup checklist, for the bench user to confirm in WindLDR's
//! instruction dialogs before the first run.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::backend::bench::error::{refused, LiveError};
use crate::backend::bench::mailbox::{self, off, state};
use crate::backend::bench::manifest::{parse_operand, Manifest, Rung};
use crate::backend::modbus::Map;
use crate::device::Device;
use crate::model::profile::Profile;
use crate::model::Operand;

/// The file the rung list is written to.
pub(crate) const PROGRAM_FILE: &str = "executive.txt";

const NEW: &str = "M1270";
const IDLE: &str = "M1271";
const RESETTING: &str = "M1272";
const EXECUTING: &str = "M1273";
const DONE: &str = "M1274";
const FAILED: &str = "M1275";
const SELECTED: &str = "M1276";
const PULSE: &str = "M1277";

/// The internal relays the program owns, with what each holds. They are M1270-M1277, the upper
/// half of M1260-M1277, the last word of internal relays every FC4A has: the Modbus map the
/// link uses reaches no internal relay below M8000, so a case with an M operand cannot be set
/// up and never runs, and no case window can hold these; [`ladder`] refuses a rung whose
/// operand reaches them all the same. Every one is written in every scan before it is read.
pub(crate) const RELAYS: [(&str, &str); 8] = [
    (NEW, "a new trigger: TRIGGER <> ACK at the top of the scan"),
    (IDLE, "the scan started in state 0, idle"),
    (RESETTING, "the scan started in state 1, resetting errors"),
    (EXECUTING, "the scan started in state 2, executing"),
    (DONE, "the scan started in state 3, done"),
    (FAILED, "the scan started in state 8, reset failed"),
    (SELECTED, "RUNG = this rung's number (each rung's own)"),
    (PULSE, "this rung's one-scan enable, from SOTU"),
];

/// The FC4A's in-operation output: on while the CPU runs, the contact of every rung that runs
/// in every scan.
const ALWAYS_ON: &str = "M8125";

/// The operands of every instruction under test, in the order the FC4A manual prints them
/// (`ATOH(W) S1 S2 D1`, fc4a-user p.14-5). The profile's operand table is a map sorted by name
/// (D1, S1, S2), so the order is fixed here and a rung with other names is refused.
const OPERANDS: [&str; 3] = ["S1", "S2", "D1"];

/// The instructions whose ladder form a quoted manual page prints, with the page.
const QUOTED: [(&str, &str); 1] = [("ATOH", "fc4a-user p.14-5")];

/// The rung list under construction: numbered rungs, notes between them.
struct List {
    text: String,
    rungs: usize,
}

impl List {
    fn note(&mut self, note: &str) {
        let _ = writeln!(self.text, "\n; {note}");
    }

    /// One rung: its contacts (`LOD M1270 / AND M1273`), then its output.
    fn rung(&mut self, condition: &str, output: &str, comment: &str) {
        self.rungs += 1;
        let _ = write!(self.text, "{:>4}  {condition} / {output}", self.rungs);
        if !comment.is_empty() {
            let _ = write!(self.text, "   ; {comment}");
        }
        self.text.push('\n');
    }

    /// Rungs with the same contacts, one for each output, so that each draws as one rung.
    fn rungs(&mut self, condition: &str, outputs: &[String]) {
        for output in outputs {
            self.rung(condition, output, "");
        }
    }
}

fn mov(s1: impl std::fmt::Display, d1: &Device) -> String {
    format!("MOV(W) S1={s1} D1={d1} REP=1")
}

fn cmp(op: &str, s1: &Device, s2: impl std::fmt::Display, d1: &str) -> String {
    format!("CMP{op}(W) S1={s1} S2={s2} D1={d1} REP=1")
}

/// A constant as a word (W) instruction takes it: a decimal 0-65535, a negative one of the
/// corpus (`K-1`) as the same 16 bits (65535). `None` when it fits no word.
fn constant(k: i64) -> Option<String> {
    match k {
        0..=65535 => Some(k.to_string()),
        -32768..=-1 => Some((k as i16 as u16).to_string()),
        _ => None,
    }
}

/// Whether a word operand at `d` (16 points from its head, for a relay) reaches [`RELAYS`]. The
/// last digit of a relay number is octal: M1270 is point 127 * 8 + 0.
fn reaches_relays(d: &Device) -> bool {
    let point = |n: u32| n / 10 * 8 + n % 10;
    let (first, head) = (point(1270), point(d.index));
    d.code() == "M" && d.index < 8000 && head + 15 >= first && head <= first + 7
}

/// Whether `names` are exactly [`OPERANDS`], in any order.
fn idec_names<'a>(names: impl Iterator<Item = &'a String>) -> bool {
    let names: Vec<&str> = names.map(String::as_str).collect();
    names.len() == OPERANDS.len() && OPERANDS.iter().all(|o| names.contains(o))
}

fn joined<'a>(names: impl Iterator<Item = &'a String>) -> String {
    names.map(String::as_str).collect::<Vec<_>>().join(", ")
}

/// The instruction under test with its operands in [`OPERANDS`] order:
/// `ATOH(W) S1=D100 S2=4 D1=D200`.
fn instruction(profile: &Profile, rung: &Rung) -> Result<String, LiveError> {
    let def = profile.instructions.get(&rung.instruction).ok_or_else(|| {
        refused!(
            "rung {}: {} is no instruction of {}",
            rung.id,
            rung.instruction,
            profile.id
        )
    })?;
    if !idec_names(def.operands.keys()) || !idec_names(rung.operands.keys()) {
        return Err(refused!(
            "rung {} ({}): the ladder form takes the operands {}, the rung has {} and the \
             profile {}",
            rung.id,
            rung.instruction,
            OPERANDS.join(", "),
            joined(rung.operands.keys()),
            joined(def.operands.keys())
        ));
    }
    if !rung.addresses.is_empty() || rung.operands.values().any(|v| v.starts_with('@')) {
        return Err(refused!(
            "rung {} ({}): an operand by indirect specification; the IDEC program has none",
            rung.id,
            rung.instruction
        ));
    }
    let hexadecimal = |code: &str| profile.devices.is_hexadecimal(code);
    let mut fields = Vec::new();
    for name in OPERANDS {
        let text = &rung.operands[name];
        let value = match parse_operand(text, &hexadecimal)
            .map_err(|e| LiveError::within(format!("rung {} operand `{name}`", rung.id), e))?
        {
            Operand::Constant(k) => constant(k).ok_or_else(|| {
                refused!(
                    "rung {} operand {name} = {text}: no 16-bit word holds it",
                    rung.id
                )
            })?,
            Operand::Device(d) if reaches_relays(&d) => {
                return Err(refused!(
                    "rung {} operand {name} = {d} reaches the program's relays M1270-M1277",
                    rung.id
                ))
            }
            Operand::Device(d) => d.to_string(),
        };
        fields.push(format!("{name}={value}"));
    }
    Ok(format!("{}(W) {}", rung.instruction, fields.join(" ")))
}

/// The rung list of the test program and its setup checklist (for `trials` trials); `Err` when
/// a rung cannot be written in IDEC ladder.
pub(crate) fn ladder(
    manifest: &Manifest,
    profile: &Profile,
    trials: usize,
) -> Result<(String, String), LiveError> {
    let map = Map::of(profile)?;
    let list = rung_list(manifest, profile, &map)?;
    let setup = ladder_setup(manifest, profile, &map, trials, list.rungs);
    Ok((list.text, setup))
}

fn rung_list(manifest: &Manifest, profile: &Profile, map: &Map) -> Result<List, LiveError> {
    if !manifest.flags.is_empty() {
        return Err(refused!(
            "the manifest sets mode flags ({}); the IDEC program sets none",
            manifest.flags.join(", ")
        ));
    }
    let mb = manifest.mailbox_head(map)?;
    let w = |o| mailbox::at(&mb, o);
    let e = &manifest.error;
    let hash = manifest.hash32();
    let mut l = List {
        text: String::new(),
        rungs: 0,
    };
    let _ = writeln!(
        l.text,
        "; plc-conformance test program for {} ({}), variants {}.",
        profile.name,
        profile.id,
        manifest.variants.join(", ")
    );
    let _ = writeln!(
        l.text,
        "; Manifest {}, mailbox layout {} at {}, {} rungs under test; {}.",
        manifest.hash,
        manifest.layout,
        mailbox::range(&mb),
        manifest.rungs.len(),
        manifest.generator
    );
    l.text.push_str(
        "; Generated: do not edit. Enter by hand in WindLDR, in this order: each numbered line \
         is one rung, its contacts then its output, steps separated by \" / \"; rung numbers \
         are for reference. Lines starting with ';' are notes. Constants are decimal words. \
         Keep every rung out of MCS/MCR and JMP/JEND.\n",
    );
    let always = format!("LOD {ALWAYS_ON}");
    let (flag_on, flag_off) = (format!("AND {}", e.flag), format!("ANDN {}", e.flag));
    l.note(
        "Signature, scan counter and the error flag, every scan (M8125: on while the CPU runs).",
    );
    l.rung(&always, &mov(mailbox::MAGIC[0], &w(off::MAGIC)), "'PC'");
    l.rung(&always, &mov(mailbox::MAGIC[1], &w(off::MAGIC + 1)), "'HI'");
    l.rung(&always, &mov(manifest.layout, &w(off::LAYOUT)), "layout");
    let (low, high) = (hash as u16, (hash >> 16) as u16);
    l.rung(
        &always,
        &mov(low, &w(off::HASH)),
        &format!("hash low word {low:04X}H"),
    );
    l.rung(
        &always,
        &mov(high, &w(off::HASH + 1)),
        &format!("hash high word {high:04X}H"),
    );
    l.rung(
        &always,
        &mov(manifest.rungs.len(), &w(off::RUNGS)),
        "rung count",
    );
    l.rung(&always, &mov(0, &w(off::ORIGIN)), "a CPU runs this program");
    let scans = w(off::SCANS);
    let count = format!("ADD(W) S1={scans} S2=1 D1={scans} REP=1");
    l.rung(&always, &count, "scan counter, wraps at 65535");
    l.rung(
        &format!("LOD {}", e.flag),
        &mov(1, &w(off::FLAG_NOW)),
        "the error flag now",
    );
    l.rung(&format!("LODN {}", e.flag), &mov(0, &w(off::FLAG_NOW)), "");
    l.note(
        "The state the scan starts in, compared once here: a state written further down takes \
         effect in the next scan, as with a CASE.",
    );
    let new = cmp("<>", &w(off::TRIGGER), w(off::ACK), NEW);
    l.rung(&always, &new, "a new trigger");
    for (relay, st) in [
        (IDLE, state::IDLE),
        (RESETTING, state::RESETTING),
        (EXECUTING, state::EXECUTING),
        (DONE, state::DONE),
        (FAILED, state::RESET_FAILED),
    ] {
        l.rung(
            &always,
            &cmp("=", &w(off::STATE), st, relay),
            state::name(st),
        );
    }
    l.note("A new trigger in state 0 or 8: reset the error state and the proof of execution.");
    // A program that resets the flag itself (IDEC) clears it in this scan; a reset flag
    // (MELSEC SM50) is set here and cleared in the next scan, its rising edge doing the reset.
    let resets_itself = e.reset == e.flag;
    let verb = if resets_itself { "RST" } else { "SET" };
    l.rungs(
        &format!("LOD {IDLE} / OR {FAILED} / AND {NEW}"),
        &[
            format!("{verb} {}", e.reset),
            mov(0, &w(off::RAN)),
            mov(0, &w(off::RAN_FOR)),
            mov(0, &w(off::ENO)),
            mov(state::RESETTING, &w(off::STATE)),
        ],
    );
    l.note("State 1: the error flag must be off now; if it is not, the case fails unexecuted.");
    let resetting = format!("LOD {NEW} / AND {RESETTING}");
    if !resets_itself {
        l.rung(
            &resetting,
            &format!("RST {}", e.reset),
            "the reset flag off",
        );
    }
    l.rungs(
        &format!("{resetting} / {flag_on}"),
        &[
            mov(1, &w(off::FLAG_BEFORE)),
            mov(state::RESET_FAILED, &w(off::STATE)),
            mov(w(off::TRIGGER), &w(off::ACK)),
        ],
    );
    l.rungs(
        &format!("{resetting} / {flag_off}"),
        &[
            mov(0, &w(off::FLAG_BEFORE)),
            mov(state::EXECUTING, &w(off::STATE)),
        ],
    );
    l.note(
        "The rungs under test, one per instruction and operand tuple of the corpus. A rung is \
         enabled in the one scan that starts in state 2 with RUNG = its number. ATOH and HTOA \
         execute in every scan their input is on, and the manual asks for a SOTU pulse \
         (fc4a-user p.14-5): the state rungs give one scan already, SOTU keeps it one whatever \
         they do, and the proof of execution (the rung's number, the trigger, 1 when the \
         instruction left the error flag off) is written under the same pulse.",
    );
    let exec = format!("LOD {NEW} / AND {EXECUTING}");
    let pulse = format!("LOD {PULSE}");
    for rung in &manifest.rungs {
        let call = instruction(profile, rung)?;
        let select = cmp("=", &w(off::RUNG), rung.id, SELECTED);
        l.rung(
            &always,
            &select,
            &format!("rung {}: {}", rung.id, rung.instruction),
        );
        l.rung(
            &format!("{exec} / AND {SELECTED} / SOTU"),
            &format!("OUT {PULSE}"),
            "",
        );
        l.rungs(
            &pulse,
            &[
                call,
                mov(rung.id, &w(off::RAN)),
                mov(w(off::TRIGGER), &w(off::RAN_FOR)),
            ],
        );
        l.rung(&format!("{pulse} / {flag_off}"), &mov(1, &w(off::ENO)), "");
        l.rung(&format!("{pulse} / {flag_on}"), &mov(0, &w(off::ENO)), "");
    }
    l.note(
        "Capture the error in the scan of the instruction, the register one scan later; \
         acknowledge last.",
    );
    let register = e.register.clone().unwrap_or_else(|| "0".into());
    let extra = e.extra.clone().unwrap_or_else(|| "0".into());
    l.rung(
        &format!("{exec} / {flag_on}"),
        &mov(1, &w(off::FLAG_AFTER)),
        "",
    );
    l.rung(
        &format!("{exec} / {flag_off}"),
        &mov(0, &w(off::FLAG_AFTER)),
        "",
    );
    l.rungs(
        &exec,
        &[
            mov(&register, &w(off::CODE)),
            mov(extra, &w(off::CODE_EXTRA)),
            mov(state::DONE, &w(off::STATE)),
        ],
    );
    l.rungs(
        &format!("LOD {DONE}"),
        &[
            mov(&register, &w(off::CODE_NEXT)),
            mov(state::IDLE, &w(off::STATE)),
            mov(w(off::TRIGGER), &w(off::ACK)),
        ],
    );
    let _ = writeln!(l.text, "\n; {} rungs.", l.rungs);
    Ok(l)
}

/// Operands in the IDEC order where the names are S1, S2, D1 (`S1=D100 S2=K4 D1=D200`), by name
/// otherwise.
fn operands_text(operands: &BTreeMap<String, String>) -> String {
    let ordered: Vec<String> = OPERANDS
        .iter()
        .filter_map(|n| operands.get(*n).map(|v| format!("{n}={v}")))
        .collect();
    match ordered.len() == operands.len() {
        true => ordered.join(" "),
        false => operands
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(" "),
    }
}

/// The setup checklist (`SETUP.md`) for WindLDR and Modbus TCP.
fn ladder_setup(
    manifest: &Manifest,
    profile: &Profile,
    map: &Map,
    trials: usize,
    rungs: usize,
) -> String {
    let mut t = String::new();
    let _ = writeln!(t, "# Test program for {} ({})\n", profile.name, profile.id);
    let _ = writeln!(
        t,
        "Manifest `{}`, {} rungs under test for {trials} trials of variants {}; mailbox {} ({} \
         words), layout {}. Generated by {}.\n",
        manifest.hash,
        manifest.rungs.len(),
        manifest.variants.join(", "),
        manifest.mailbox,
        mailbox::WORDS,
        manifest.layout,
        manifest.generator
    );
    t.push_str(
        "**A bench CPU only.** The harness writes data registers of the CPU while it runs \
         (listed under \"What the run writes\"). Use a CPU that controls nothing: no outputs \
         wired, no other program.\n\n",
    );
    t.push_str(
        "## In WindLDR\n\nItems marked *check* are not confirmed from a manual; note what you \
         found.\n\n",
    );
    let ranges: Vec<String> = (manifest.variants.iter())
        .filter_map(|v| profile.variant(v).map(|var| (v, profile.ranges(var, "D"))))
        .map(|(v, r)| {
            let r = r.map_or("as the profile says".into(), |ranges| {
                ranges
                    .iter()
                    .map(|d| format!("D{}-D{}", d.first, d.last))
                    .collect::<Vec<_>>()
                    .join(", ")
            });
            format!("{v} {r}")
        })
        .collect();
    let _ = writeln!(
        t,
        "1. A new project for the CPU type under test (data registers by variant: {}).",
        ranges.join("; ")
    );
    t.push_str(
        "2. A user program execution error turns on M8004 and the ERR LED; the CPU must keep \
         running, or the first error case ends the run (*check* that it does on your CPU). The \
         program clears M8004 itself with `RST M8004` before each case (*check* that a user \
         program may reset it: where it stays on, every later case fails as \"the error reset \
         failed\", never with a result).\n",
    );
    t.push_str(
        "3. The Modbus TCP server, with writes to data registers allowed: built into the FC6A \
         (port 502 by default; *check* the setting's name in the function area settings); an \
         FC4A reaches Modbus TCP only through its web server module, with the FC6A's map \
         (unconfirmed: *check* that D0-D7999 are holding registers 0-7999 on it). The unit id \
         is 1 unless you give `unit=` in the backend.\n",
    );
    let _ = writeln!(
        t,
        "4. Enter the rungs of `{PROGRAM_FILE}` by hand, in order, one rung per numbered line, \
         none inside MCS/MCR or JMP/JEND: the state relays are compared at the top from the \
         state the scan starts in, and the rungs below must see that state. The program owns \
         these internal relays; use them nowhere else:"
    );
    for (relay, what) in RELAYS {
        let _ = writeln!(t, "   - {relay}: {what}");
    }
    t.push_str(
        "   The forms it uses; a form no quoted manual page prints is marked *check*: confirm \
         it in WindLDR's instruction dialog before the first run.\n",
    );
    let mut under_test: Vec<&str> = manifest
        .rungs
        .iter()
        .map(|r| r.instruction.as_str())
        .collect();
    under_test.sort_unstable();
    under_test.dedup();
    for name in under_test {
        match QUOTED.iter().find(|(q, _)| *q == name) {
            Some((_, page)) => {
                let _ = writeln!(
                    t,
                    "   - `{name}(W) S1 S2 D1` as the manual prints it ({page})"
                );
            }
            None => {
                let _ = writeln!(
                    t,
                    "   - `{name}(W) S1 S2 D1` *check*: the order of the ATOH page, whose \
                     operand names this one shares"
                );
            }
        }
    }
    t.push_str(
        "   - `MOV(W) S1 D1 REP`, `CMP=(W)` and `CMP<>(W) S1 S2 D1 REP`, `ADD(W) S1 S2 D1 REP`, \
         with REP=1 meaning no repeat *check*\n\
         \x20  - `SOTU` turns its output on for the one scan its input rises in (each rung's \
         enable falls between two cases, so the same rung fires again on the next) *check*\n\
         \x20  - `LOD`, `LODN`, `AND`, `ANDN`, `OR`, `OUT`, `SET`, `RST` as in any IDEC \
         instruction list *check*\n\
         \x20  - M8125, the in-operation output, is on in every scan while the CPU runs: the \
         contact of the rungs that run every scan *check*\n\
         \x20  - the scan counter `ADD(W)` wraps from 65535 to 0 without turning on M8004 *check*\n\
         \x20  - constants are decimal words 0-65535; a negative constant of the corpus is \
         written as its 16 bits (K-1 as 65535)\n",
    );
    let _ = writeln!(
        t,
        "   The program has {} SOTU instructions and {} rungs in all: *check* both against \
         the CPU's limits (WindLDR says when a program does not fit).",
        manifest.rungs.len(),
        rungs
    );
    t.push_str("5. Download the program to the CPU; switch to RUN.\n\n");
    t.push_str("## From the PC\n\n");
    let _ = writeln!(
        t,
        "```sh\nB='modbus:bench=HOST:502?manifest=manifest.json&confirm=CODE&sandbox=manifest'\n\
         plc-conformance hil doctor --backend \"$B\"      # read-only: type code, RUN, signature, scan counter\n\
         plc-conformance hil dry-run --backend \"$B\"     # every write checked, no socket\n\
         plc-conformance run --backend \"$B\"\n```\n"
    );
    t.push_str(
        "`confirm` is the CPU type code the CPU holds in D8002, as a decimal number; nothing is \
         written unless it matches. Which number each model reports is unconfirmed: read it \
         with `plc-conformance hil doctor` and confirm it yourself. `sandbox` is the set of \
         words the harness may write besides the mailbox's three PC words.\n\n",
    );
    super::setup::run_writes(
        &mut t,
        manifest,
        map,
        "Data registers",
        "Special data registers",
    );
    let _ = writeln!(
        t,
        "- **The program** also resets the error flag {} before each case and writes its \
         relays M1270-M1277 in every scan; each instruction writes its destination inside the \
         case windows.\n",
        manifest.error.reset
    );
    t.push_str(
        "Nothing else is written: no output, timer or counter, and no word outside these.\n\n",
    );
    super::setup::cases_and_rungs(&mut t, manifest, |operands, _| operands_text(operands));
    t
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::backend::bench::manifest::ErrorDevices;
    use crate::test_support::{manifest, rung};

    fn profile() -> Profile {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("vendors");
        let profiles = crate::load::load_profiles(&dir)
            .unwrap_or_else(|e| panic!("profiles do not load:\n{e}"));
        profiles
            .get("idec-fc4a")
            .expect("no idec-fc4a profile")
            .as_ref()
            .clone()
    }

    fn sample() -> Manifest {
        manifest(
            "idec-fc4a",
            "c10r2",
            "D300",
            ErrorDevices {
                flag: "M8004".into(),
                register: None,
                extra: None,
                reset: "M8004".into(),
            },
            vec![
                rung(1, "ATOH", &[("S1", "D100"), ("S2", "K4"), ("D1", "D200")]),
                rung(2, "HTOA", &[("S1", "D100"), ("S2", "K2"), ("D1", "D210")]),
            ],
            &["D100-D103", "D200-D213"],
            &[],
        )
    }

    fn at(o: u32) -> Device {
        mailbox::at(&Device::new("D", 300), o)
    }

    /// Each call takes S1, S2, D1 in the manual's order, not the map's sorted D1, S1, S2, and
    /// is followed by its proof of execution under the same pulse.
    #[test]
    fn every_rung_takes_its_operands_in_the_manuals_order_and_proves_it_ran() {
        let (text, _) = ladder(&sample(), &profile(), 7).expect("ladder");
        for (id, call) in [
            (1, "ATOH(W) S1=D100 S2=4 D1=D200"),
            (2, "HTOA(W) S1=D100 S2=2 D1=D210"),
        ] {
            let call_at = text
                .find(&format!("LOD {PULSE} / {call}"))
                .unwrap_or_else(|| panic!("{call}\n{text}"));
            let proofs = [
                format!("LOD {PULSE} / MOV(W) S1={id} D1={} REP=1", at(off::RAN)),
                format!(
                    "LOD {PULSE} / MOV(W) S1={} D1={} REP=1",
                    at(off::TRIGGER),
                    at(off::RAN_FOR)
                ),
                format!(
                    "LOD {PULSE} / ANDN M8004 / MOV(W) S1=1 D1={} REP=1",
                    at(off::ENO)
                ),
                format!(
                    "LOD {PULSE} / AND M8004 / MOV(W) S1=0 D1={} REP=1",
                    at(off::ENO)
                ),
            ];
            for proof in proofs {
                let found = text[call_at..].find(&proof);
                assert!(
                    found.is_some(),
                    "rung {id}: no `{proof}` after the call\n{text}"
                );
            }
            let select = format!("CMP=(W) S1={} S2={id} D1={SELECTED} REP=1", at(off::RUNG));
            assert!(text.contains(&select), "{select}");
        }
        assert!(
            !text.contains("D1=D200 S1"),
            "no operand in map order\n{text}"
        );
    }

    #[test]
    fn the_reset_step_clears_m8004_and_the_signature_holds_the_hash() {
        let m = sample();
        let (text, _) = ladder(&m, &profile(), 7).expect("ladder");
        let reset = format!("LOD {IDLE} / OR {FAILED} / AND {NEW} / RST M8004");
        assert!(text.contains(&reset), "{reset}\n{text}");
        assert!(!text.contains("SET M8004"), "the flag is only ever reset");
        let hash = m.hash32();
        for (word, o) in [
            (hash as u16, off::HASH),
            ((hash >> 16) as u16, off::HASH + 1),
        ] {
            let line = format!("MOV(W) S1={word} D1={} REP=1", at(o));
            assert!(text.contains(&line), "{line}\n{text}");
        }
        let scans = at(off::SCANS);
        assert!(text.contains(&format!("ADD(W) S1={scans} S2=1 D1={scans} REP=1")));
    }

    /// An operand the call does not name, a relay where a word goes, a mode flag (IDEC has
    /// none): each refused, with what says why where there is a word for it.
    #[rstest::rstest]
    #[case::an_operand_named_s(&[("s", "D100"), ("S2", "K4"), ("D1", "D200")], &[], "S1, S2, D1")]
    #[case::m1260_is_relays(&[("S1", "D100"), ("S2", "K4"), ("D1", "M1260")], &[], "relays")]
    #[case::no_mode_flags_on_idec(&[("S1", "D100"), ("S2", "K4"), ("D1", "D200")], &["M8005"], "")]
    fn rungs_the_ladder_cannot_write_are_refused(
        #[case] operands: &[(&str, &str)],
        #[case] flags: &[&str],
        #[case] says: &str,
    ) {
        let mut m = sample();
        m.rungs[0] = rung(1, "ATOH", operands);
        m.flags = flags.iter().map(|f| f.to_string()).collect();
        let e = ladder(&m, &profile(), 7).expect_err("refused").to_string();
        assert!(e.contains(says), "{e}");
    }

    #[test]
    fn the_setup_lists_the_rungs_and_the_commands() {
        let m = sample();
        let profile = profile();
        let (_, setup) = ladder(&m, &profile, 7).expect("ladder");
        assert!(
            setup.contains("| 1 | ATOH | S1=D100 S2=K4 D1=D200 |"),
            "{setup}"
        );
        assert!(
            setup.contains("`ATOH(W) S1 S2 D1` as the manual prints it"),
            "{setup}"
        );
        assert!(setup.contains("`HTOA(W) S1 S2 D1` *check*"), "{setup}");
        assert!(setup.contains("modbus:bench=HOST:502?manifest=manifest.json&confirm=CODE"));
        assert!(setup.contains("D300-D331"), "{setup}");
    }
}
