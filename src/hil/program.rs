//! The generated program's text (structured text for GX Works3) and its setup checklist.
//!
//! The program is written in the plainest structured text: direct device names, signed decimal
//! constants, bit-specified word devices (`D12011.0`) for the flag bits, and no functions beyond
//! the instructions under test, so that as little as possible depends on the engineering tool's
//! dialect. Every call takes its operand order from the profile's `structured_text` table (the
//! form the manual prints), never from the operand names: FX5 ASCI is `ASCI(EN,s,n,d)`, and a
//! call in the ladder's (s), (d), (n) order would convert the wrong words. Each rung proves that
//! it ran: in the scan it is enabled it writes its number, the trigger and its ENO into the
//! mailbox. What a bench user must still check in the tool is in the setup checklist.

use std::collections::BTreeMap;
use std::fmt::Write;

use crate::backend::bench::error::{refused, LiveError};
use crate::backend::bench::mailbox::{self, off, state};
use crate::backend::bench::manifest::{parse_operand, Manifest};
use crate::backend::slmp;
use crate::device::Device;
use crate::model::profile::Profile;
use crate::model::Operand;

/// The label that receives each call's ENO.
pub(super) const ENO_LABEL: &str = "bEno";

/// A call statement from the profile's table: `bEno := ASCI(enable, D100, 4, D200);`.
fn call(
    profile: &Profile,
    instruction: &str,
    enable: &str,
    operands: &BTreeMap<String, String>,
) -> Result<String, LiveError> {
    let form = profile.calls.get(instruction).ok_or_else(|| {
        refused!(
            "{} has no structured-text form for {instruction} (`structured_text` in its \
             profile): the program cannot call it",
            profile.id
        )
    })?;
    form.render(ENO_LABEL, enable, operands).ok_or_else(|| {
        refused!(
            "the structured-text form of {instruction} takes {}, the rung has {}",
            form.operands.join(", "),
            operands.keys().cloned().collect::<Vec<_>>().join(", ")
        )
    })
}

fn word(head: &Device, offset: u32) -> String {
    mailbox::at(head, offset).to_string()
}

/// A constant as a signed decimal of its word, with the hex it stands for.
fn int(value: u16) -> String {
    format!("{}", value as i16)
}

/// The structured text of the test program; `Err` when an instruction has no call form.
pub(crate) fn structured_text(manifest: &Manifest, profile: &Profile) -> Result<String, LiveError> {
    let mb = manifest.mailbox_head(&slmp::ADDRESSING)?;
    let w = |o| word(&mb, o);
    let e = &manifest.error;
    let hash = manifest.hash32();
    let mut t = String::new();
    let _ = writeln!(
        t,
        "(* plc-conformance test program for {} ({}), variants {}. *)",
        profile.name,
        profile.id,
        manifest.variants.join(", ")
    );
    let _ = writeln!(
        t,
        "(* Manifest {}, mailbox layout {} at {}-{}, {} rungs; {}. *)",
        manifest.hash,
        manifest.layout,
        mb,
        mailbox::at(&mb, mailbox::WORDS - 1),
        manifest.rungs.len(),
        manifest.generator
    );
    t.push_str(
        "(* Generated: do not edit. Every rung is evaluated in every scan, each with its own \
         enable, so that a pulse form sees its enable fall between two cases and executes again \
         on the next one: keep the rungs out of IF and CASE. Declare the labels bExec and bEno \
         (BOOL). *)\n\n",
    );
    t.push_str("(* Signature, scan counter and the error flag, every scan. *)\n");
    let _ = writeln!(
        t,
        "{} := {}; (* 'PC' *)",
        w(off::MAGIC),
        int(mailbox::MAGIC[0])
    );
    let _ = writeln!(
        t,
        "{} := {}; (* 'HI' *)",
        w(off::MAGIC + 1),
        int(mailbox::MAGIC[1])
    );
    let _ = writeln!(t, "{} := {};", w(off::LAYOUT), manifest.layout);
    let _ = writeln!(
        t,
        "{} := {}; (* hash low word {:04X}H *)",
        w(off::HASH),
        int(hash as u16),
        hash as u16
    );
    let _ = writeln!(
        t,
        "{} := {}; (* hash high word {:04X}H *)",
        w(off::HASH + 1),
        int((hash >> 16) as u16),
        (hash >> 16) as u16
    );
    let _ = writeln!(t, "{} := {};", w(off::RUNGS), manifest.rungs.len());
    let _ = writeln!(
        t,
        "{} := 0; (* a CPU runs this program; the simulated CPU writes 'SI' *)",
        w(off::ORIGIN)
    );
    let _ = writeln!(t, "{} := {} + 1;", w(off::SCANS), w(off::SCANS));
    let _ = writeln!(
        t,
        "IF {} THEN {} := 1; ELSE {} := 0; END_IF;",
        e.flag,
        w(off::FLAG_NOW),
        w(off::FLAG_NOW)
    );
    t.push_str("bExec := FALSE;\n\n");
    t.push_str(
        "(* A new trigger: reset the error state (one scan), check it, then enable the selected \
         rung for exactly one scan. *)\n",
    );
    let _ = writeln!(t, "IF {} <> {} THEN", w(off::TRIGGER), w(off::ACK));
    let _ = writeln!(t, "  CASE {} OF", w(off::STATE));
    let _ = writeln!(t, "    {}, {}:", state::IDLE, state::RESET_FAILED);
    let _ = writeln!(t, "      {} := TRUE;", e.reset);
    for o in [off::RAN, off::RAN_FOR, off::ENO] {
        let _ = writeln!(t, "      {} := 0;", w(o));
    }
    let _ = writeln!(t, "      {} := {};", w(off::STATE), state::RESETTING);
    let _ = writeln!(t, "    {}:", state::RESETTING);
    let _ = writeln!(t, "      {} := FALSE;", e.reset);
    let _ = writeln!(t, "      IF {} THEN", e.flag);
    let _ = writeln!(t, "        {} := 1;", w(off::FLAG_BEFORE));
    let _ = writeln!(t, "        {} := {};", w(off::STATE), state::RESET_FAILED);
    let _ = writeln!(t, "        {} := {};", w(off::ACK), w(off::TRIGGER));
    t.push_str("      ELSE\n");
    let _ = writeln!(t, "        {} := 0;", w(off::FLAG_BEFORE));
    let _ = writeln!(t, "        {} := {};", w(off::STATE), state::EXECUTING);
    t.push_str("      END_IF;\n");
    let _ = writeln!(t, "    {}:", state::EXECUTING);
    for (i, f) in manifest.flags.iter().enumerate() {
        let _ = writeln!(t, "      {f} := {}.{:X};", w(off::FLAGS), i);
    }
    t.push_str("      bExec := TRUE;\n");
    t.push_str("  END_CASE;\n");
    t.push_str("END_IF;\n\n");
    t.push_str(
        "(* The rungs: one per instruction and operand tuple of the corpus, each call in the \
         form the manual prints, then the rung's proof that it ran: its number, the trigger and \
         its ENO. *)\n",
    );
    let hexadecimal = |code: &str| profile.devices.is_hexadecimal(code);
    for rung in &manifest.rungs {
        let args: BTreeMap<String, String> = (rung.operands.iter())
            .map(|(name, text)| {
                let arg = match parse_operand(text, &hexadecimal) {
                    // Indirect specification is written as it is: `@D10`.
                    _ if text.starts_with('@') => text.clone(),
                    Ok(Operand::Constant(k)) => k.to_string(),
                    Ok(Operand::Device(d)) => d.to_string(),
                    Err(_) => text.clone(),
                };
                (name.clone(), arg)
            })
            .collect();
        let enable = format!("bExec AND {} = {}", w(off::RUNG), rung.id);
        for (pointer, target) in &rung.addresses {
            let operands = BTreeMap::from([
                ("s".to_string(), target.clone()),
                ("d".to_string(), pointer.clone()),
            ]);
            let _ = writeln!(t, "{}", call(profile, "ADRSET", &enable, &operands)?);
        }
        let _ = writeln!(t, "{}", call(profile, &rung.instruction, &enable, &args)?);
        let _ = writeln!(
            t,
            "IF {enable} THEN {} := {}; {} := {}; IF {ENO_LABEL} THEN {} := 1; ELSE {} := 0; \
             END_IF; END_IF;",
            w(off::RAN),
            rung.id,
            w(off::RAN_FOR),
            w(off::TRIGGER),
            w(off::ENO),
            w(off::ENO)
        );
    }
    t.push_str("\n(* Capture the error in the scan of the instruction, and the register one scan later; acknowledge last. *)\n");
    t.push_str("IF bExec THEN\n");
    let _ = writeln!(
        t,
        "  IF {} THEN {} := 1; ELSE {} := 0; END_IF;",
        e.flag,
        w(off::FLAG_AFTER),
        w(off::FLAG_AFTER)
    );
    let register = e.register.as_deref().unwrap_or("0");
    let _ = writeln!(t, "  {} := {};", w(off::CODE), register);
    match &e.extra {
        Some(extra) => {
            let _ = writeln!(t, "  {} := {};", w(off::CODE_EXTRA), extra);
        }
        None => {
            let _ = writeln!(t, "  {} := 0;", w(off::CODE_EXTRA));
        }
    }
    for f in &manifest.flags {
        let _ = writeln!(t, "  {f} := FALSE;");
    }
    let _ = writeln!(t, "  {} := {};", w(off::STATE), state::DONE);
    let _ = writeln!(t, "ELSIF {} = {} THEN", w(off::STATE), state::DONE);
    let _ = writeln!(t, "  {} := {};", w(off::CODE_NEXT), register);
    let _ = writeln!(t, "  {} := {};", w(off::STATE), state::IDLE);
    let _ = writeln!(t, "  {} := {};", w(off::ACK), w(off::TRIGGER));
    t.push_str("END_IF;\n");
    Ok(t)
}

/// Operands as `s=D100 d=@D20`, then what each pointer addresses: `(@D20: D200)`.
fn call_text(operands: &BTreeMap<String, String>, addresses: &BTreeMap<String, String>) -> String {
    let operands = operands.iter().map(|(k, v)| format!("{k}={v}"));
    let addresses = addresses.iter().map(|(p, t)| format!("(@{p}: {t})"));
    operands.chain(addresses).collect::<Vec<_>>().join(" ")
}

/// The setup checklist (`SETUP.md`).
pub(crate) fn setup_text(manifest: &Manifest, profile: &Profile, trials: usize) -> String {
    let mb = manifest.mailbox.clone();
    let mut t = String::new();
    let _ = writeln!(t, "# Test program for {} ({})\n", profile.name, profile.id);
    let _ = writeln!(
        t,
        "Manifest `{}`, {} rungs for {trials} trials of variants {}; mailbox {} ({} words), \
         layout {}. Generated by {}.\n",
        manifest.hash,
        manifest.rungs.len(),
        manifest.variants.join(", "),
        mb,
        mailbox::WORDS,
        manifest.layout,
        manifest.generator
    );
    t.push_str(
        "**A bench CPU only.** The harness writes words of the CPU while it runs (listed under \
         \"What the run writes\"). Use a CPU that controls nothing: no outputs wired, no other \
         program.\n\n",
    );
    t.push_str("## In the engineering tool (GX Works3)\n\n");
    t.push_str("Items marked *check* are not confirmed from a manual; note what you found.\n\n");
    let _ = writeln!(
        t,
        "1. A new project for the CPU model under test ({}). Device ranges as the profile \
         variant says (data registers {}).",
        manifest.variants.join(" / "),
        manifest
            .variants
            .iter()
            .filter_map(|v| profile.variant(v))
            .filter_map(|v| profile.ranges(v, "D"))
            .map(|r| format!("D{}-D{}", r.first, r.last))
            .next()
            .unwrap_or_else(|| "as the profile says".into())
    );
    t.push_str(
        "2. CPU parameter, RAS setting, operation at an error: operation errors must **continue** \
         (not stop), or the first error case stops the CPU and ends the run. *check* the \
         item's name and default on your model.\n",
    );
    t.push_str(
        "3. Ethernet port: an SLMP connection, TCP, **binary** code, a port number of your \
         choice; the frame the backend uses (4E by default, 3E on FX5); writes from the \
         connection allowed during RUN (*check* whether your model has such a setting).\n",
    );
    t.push_str(
        "4. A program in structured text: paste `executive.st`, declare the labels `bExec` and `bEno` \
         (BOOL), convert. *check* that every instruction call converts with its enable first; \
         a rung that does not convert cannot be run (remove it and regenerate with a filter, \
         or report it).\n",
    );
    t.push_str(
        "   Each call passes its operands in this order \
         (docs/semantics.md#structured-text-calls); a form no quoted manual page prints is marked *check*: confirm it in the \
         instruction's help before the first run.\n",
    );
    let mut unconfirmed: Vec<String> = manifest
        .rungs
        .iter()
        .map(|r| r.instruction.clone())
        .chain((manifest.rungs.iter().any(|r| !r.addresses.is_empty())).then(|| "ADRSET".into()))
        .collect();
    unconfirmed.sort();
    unconfirmed.dedup();
    for name in unconfirmed {
        if let Some(form) = profile.calls.get(&name) {
            let mark = match form.basis {
                crate::model::profile::CallBasis::Manual => "as the manual prints it",
                crate::model::profile::CallBasis::Inferred => "*check*",
            };
            let _ = writeln!(
                t,
                "   - `ENO:={}(EN,{});` {mark}",
                form.instruction,
                form.operands.join(",")
            );
        }
    }
    if manifest.rungs.iter().any(|r| !r.addresses.is_empty()) {
        t.push_str(
            "   Rungs with indirect specification store the address first: \
             `ADRSET(enable, D100, D10)` puts D100's address in D10 and D11, and the \
             instruction's `@D10` is D100. *check* that ADRSET takes the device, then the \
             pointer, and that `@D10` converts in structured text.\n",
        );
    }
    t.push_str("5. Write parameters and program to the CPU; switch to RUN.\n\n");
    t.push_str("## From the PC\n\n");
    let _ = writeln!(
        t,
        "```sh\nB='slmp:bench=HOST:PORT?manifest=manifest.json&confirm=TYPE-NAME&sandbox=manifest'\n\
         plc-conformance hil doctor --backend \"$B\"      # read-only: type, RUN, signature, scan counter\n\
         plc-conformance hil dry-run --backend \"$B\"     # every write checked, no socket\n\
         plc-conformance run --backend \"$B\"\n```\n"
    );
    t.push_str(
        "`confirm` is the type name the CPU reports (0101), e.g. `R04CPU`; nothing is written \
         unless it matches. `sandbox` is the set of words the harness may write besides the \
         mailbox's three PC words.\n\n",
    );
    super::setup::run_writes(
        &mut t,
        manifest,
        &slmp::ADDRESSING,
        "Data and link registers",
        "Special registers",
    );
    let _ = writeln!(
        t,
        "- **The program** also sets the error reset {} and the mode flags {} for the scan of \
         each case, and each instruction writes its destination inside the case windows.\n",
        manifest.error.reset,
        if manifest.flags.is_empty() {
            "(none)".to_string()
        } else {
            manifest.flags.join(", ")
        }
    );
    t.push_str(
        "Nothing else is written: no bit device, output or timer, and no word outside these.\n\n",
    );
    super::setup::cases_and_rungs(&mut t, manifest, call_text);
    t
}
