//! What every setup checklist says the same way, whatever the link: the words a run writes,
//! the cases no program can hold and the rung table.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::backend::bench::fence::{self, Kind};
use crate::backend::bench::mailbox;
use crate::backend::bench::manifest::Manifest;
use crate::backend::bench::Addressing;

/// "What the run writes": the case windows' data registers (`data` names them as the CPU's
/// family does), the special ones a sandbox holds only when named (`special`), and the mailbox's
/// PC words. The program's own writes follow, in the caller's words.
pub(super) fn run_writes(
    t: &mut String,
    manifest: &Manifest,
    addressing: &dyn Addressing,
    data: &str,
    special: &str,
) {
    t.push_str("## What the run writes\n\n");
    let ranges = fence::parse_ranges(&manifest.writes.join(","), addressing).unwrap_or_default();
    let (data_ranges, special_ranges): (Vec<_>, Vec<_>) = ranges
        .iter()
        .partition(|r| addressing.kind(&r.head()) == Kind::Data);
    let names = |rs: &[&fence::WordRange]| rs.iter().map(ToString::to_string).collect::<Vec<_>>();
    if !data_ranges.is_empty() {
        let _ = writeln!(
            t,
            "- **{data}** the case windows write (`sandbox=manifest` covers them): {}.",
            names(&data_ranges).join(", ")
        );
    }
    if !special_ranges.is_empty() {
        let _ = writeln!(
            t,
            "- **{special}** the case windows write, only when you name them \
             (`sandbox=manifest,{}`); their cases are not run otherwise: {}.",
            names(&special_ranges).join(","),
            names(&special_ranges).join(", ")
        );
    }
    if let Ok(head) = manifest.mailbox_head(addressing) {
        let pc = mailbox::pc_words(&head);
        let _ =
            writeln!(
            t,
            "- **The mailbox** {}: the PC writes {} (trigger, rung, flags); the program writes \
             the rest.",
            mailbox::range(&head),
            pc.iter().map(ToString::to_string).collect::<Vec<_>>().join(", ")
        );
    }
}

/// The checklist's last sections: the cases no program can hold, with the reason their trials
/// are skipped, and the rung table. `call` writes an instruction's operands (and what each
/// pointer addresses) as the link's program shows them, so that a rung reads as it does there.
pub(super) fn cases_and_rungs(
    t: &mut String,
    manifest: &Manifest,
    call: impl Fn(&BTreeMap<String, String>, &BTreeMap<String, String>) -> String,
) {
    if !manifest.unrealisable.is_empty() {
        t.push_str(
            "## Cases no program can hold\n\nTheir trials are skipped with this reason:\n\n",
        );
        for u in &manifest.unrealisable {
            let operands = call(&u.operands, &u.addresses);
            let _ = writeln!(t, "- {} {operands}: {}", u.instruction, u.reason);
        }
        t.push('\n');
    }
    t.push_str("## Rungs\n\n| rung | instruction | operands |\n|---|---|---|\n");
    for r in &manifest.rungs {
        let operands = call(&r.operands, &r.addresses);
        let _ = writeln!(t, "| {} | {} | {operands} |", r.id, r.instruction);
    }
}
