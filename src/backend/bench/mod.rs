//! A real CPU as a backend, over any link that reads and writes its words.
//!
//! A client of a PLC's protocol can read and write words but cannot execute an instruction, so
//! the CPU runs a generated test program (`plc-conformance hil generate`) with one rung per
//! instruction and operand tuple of the corpus, and the PC hands it one case at a time through a
//! mailbox of data registers ([`mailbox`]): write the case's memory window, the rung and the
//! flags, then the trigger; poll until the program acknowledges; read the window and the
//! captured error flag and registers back. The words that changed are the case's writes.
//!
//! Everything here holds for any word-addressed CPU; what differs per protocol is a [`Link`]
//! (read and write words, name the CPU, say whether it runs) and its [`Addressing`] (which
//! devices it reaches, how it numbers them); each link is a folder of its own under `backend`.
//!
//! Safety comes first, because the other end is a CPU that might be wired to something:
//! - every write is built by the [`fence::WriteFence`] from the declared sandbox and the
//!   mailbox's PC words, and refused before a byte is encoded when one word lies outside;
//! - nothing is written before the interlocks pass: the CPU names itself as the configured
//!   `confirm`, it is in RUN, the mailbox carries the signature (magic, layout, hash) of the very
//!   program the manifest describes, and its scan counter moves;
//! - the backend is built without a socket ([`BenchBackend::new`]): a dry run or planning never
//!   connects, and [`BenchBackend::connect`] is the one step that does;
//! - a link can send only reads, the fenced writes and the CPU's identification: no link has a
//!   way to start, stop or reset a CPU.
//!
//! Faults map onto the kinds every backend reports: no reply or no acknowledgement in time is a
//! timeout, a lost connection a crash, a reply the link cannot decode, an error answer or an
//! inconsistent capture a protocol error, and a CPU that cannot be reached or leaves RUN is
//! unreachable. After `max_consecutive_faults` faults in a row the remaining trials are not run.

// Its types are `pub` for the `testing` module alone (this repository's tests); none appears in
// the crate root's interface, though rustc counts some reachable through the trait impls.
#![allow(unnameable_types)]

mod addressing;
pub(crate) mod doctor;
pub(crate) mod error;
pub(crate) mod fence;
mod link;
pub(crate) mod mailbox;
pub(crate) mod manifest;
pub(crate) mod settings;
pub(crate) mod sim;
pub(crate) mod tcp;

use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

pub(crate) use addressing::Addressing;
use fence::{WordRange, WriteFence};
pub(crate) use link::{Failure, Identity, Link, LinkError, LinkSettings, RunState};
use mailbox::{off, state, Signature};
pub(crate) use settings::BenchSettings;

use super::breaker::Breaker;
use super::external::{closing, window};
use super::{Backend, Fault, Outcome, Request, Response, Setting};
use crate::backend::bench::error::{refused, LiveError};
use crate::device::Device;
use crate::error_chain::chain;
use crate::memory::Value;
use crate::model::pointer_words;
use crate::model::profile::{Profile, Profiles, Variant};
use manifest::Call;

/// A live CPU backend, over any link.
pub(crate) struct BenchBackend {
    settings: BenchSettings,
    profile: Arc<Profile>,
    rungs: HashMap<String, u16>,
    unrealisable: HashMap<String, String>,
    instructions: Vec<String>,
    mailbox: Device,
    fence: WriteFence,
    signature: Signature,
    state: Mutex<Live>,
    reconnects: AtomicUsize,
}

struct Live {
    link: Box<dyn Link>,
    /// The interlocks passed on the current connection.
    verified: bool,
    /// The connection (by count) the interlocks passed on: a read retried on a new connection
    /// leaves `verified` set, and the next write must not go out before they run again.
    verified_on: u64,
    /// The last trigger written (or found acknowledged).
    trigger: u16,
    /// The CPU's type name, once read.
    cpu: Option<String>,
    /// The mailbox says the simulated CPU runs the program, not a CPU.
    simulated: bool,
    /// The rung whose proof of execution said, on the last case, that it did not execute.
    not_executed: Option<u16>,
    /// Set when the circuit breaker trips or the CPU left RUN: every later case gets this.
    down: Option<String>,
    breaker: Breaker,
}

/// One case's capture from the mailbox.
#[derive(Debug, Clone)]
struct Status {
    ack: u16,
    state: u16,
    flag_before: u16,
    flag_after: u16,
    code: u16,
    extra: u16,
    next: u16,
    /// The proof of execution: the rung that ran, the trigger it ran for, its ENO.
    ran: u16,
    ran_for: u16,
    eno: u16,
    state_now: RunState,
}

/// Why a case went wrong before it had an outcome.
enum CaseError {
    Link(LinkError),
    Fault(Fault),
    /// The CPU left RUN: no further case can run.
    Stopped(String),
}

impl From<LinkError> for CaseError {
    fn from(e: LinkError) -> Self {
        CaseError::Link(e)
    }
}

/// What a case writes: its window with the values before execution.
pub(crate) struct Plan {
    pub rung: u16,
    pub flags: u16,
    /// Each window range with its words.
    pub window: Vec<(Device, Vec<u16>)>,
}

/// The manifest's mailbox head, checked to lie with all its words on the variant: what the
/// backend and a simulated CPU both refuse a manifest for.
pub(crate) fn mailbox_on(
    profile: &Profile,
    variant: &str,
    manifest: &manifest::Manifest,
    addressing: &dyn Addressing,
) -> Result<Device, LiveError> {
    let mailbox = manifest.mailbox_head(addressing)?;
    if !profile.words_exist(variant_of(profile, variant)?, &mailbox, mailbox::WORDS) {
        return Err(refused!(
            "the mailbox {} does not exist on variant {variant} of {}",
            mailbox::range(&mailbox),
            profile.id
        ));
    }
    Ok(mailbox)
}

/// The profile's variant of this id, or a refusal that lists the ones it has.
fn variant_of<'p>(profile: &'p Profile, variant: &str) -> Result<&'p Variant, LiveError> {
    profile.variant(variant).ok_or_else(|| {
        refused!(
            "variant `{variant}` is not a variant of {}; it has: {}",
            profile.id,
            (profile.variants.iter())
                .map(|v| v.id.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )
    })
}

impl BenchBackend {
    /// The backend, checked against the profiles, without any connection.
    pub(crate) fn new<L: LinkSettings + Clone + 'static>(
        settings: BenchSettings<L>,
        profiles: &Profiles,
    ) -> Result<BenchBackend, LiveError> {
        let settings = settings.erased();
        let manifest = &settings.manifest;
        let profile = profiles.get(&manifest.profile).cloned().ok_or_else(|| {
            refused!(
                "the manifest is for profile `{}`, which is not loaded; known profiles: {}",
                manifest.profile,
                profiles.ids().join(", ")
            )
        })?;
        // A manifest's CPU is reached by its profile's link: SLMP to an IDEC CPU would address
        // devices its program does not have.
        let wanted = profile.bench.as_ref().map(|b| b.link);
        if wanted != Some(settings.link.kind()) {
            return Err(refused!(
                "the manifest is for {}, whose CPUs are benched over {}, not {}: {}",
                profile.id,
                wanted.map_or("no link (its profile has no `bench` section)".into(), |l| {
                    l.to_string()
                }),
                settings.link.kind(),
                crate::backend::BENCH_FORMS
            ));
        }
        variant_of(&profile, &settings.variant)?;
        if !manifest.variants.contains(&settings.variant) {
            return Err(refused!(
                "the manifest's program was generated for variants {}, not `{}`",
                manifest.variants.join(", "),
                settings.variant
            ));
        }
        let addressing = settings.link.addressing();
        if let Some(why) =
            (settings.sandbox.iter()).find_map(|r| fence::sandbox_refuses(r, addressing))
        {
            return Err(refused!("`sandbox`: {why}"));
        }
        let mailbox = mailbox_on(&profile, &settings.variant, manifest, addressing)?;
        let whole = mailbox::range(&mailbox);
        if let Some(r) = settings.sandbox.iter().find(|r| r.overlaps(&whole)) {
            return Err(refused!(
                "the sandbox range {r} overlaps the mailbox {whole}: the program's own words \
                 must not be writable"
            ));
        }
        let mut allowed = settings.sandbox.clone();
        allowed.extend(mailbox::pc_words(&mailbox));
        let rungs = manifest.rung_index(addressing)?;
        let unrealisable = manifest
            .unrealisable
            .iter()
            .map(|u| {
                for v in u.operands.values() {
                    manifest::parse_operand(v, &|code| profile.devices.is_hexadecimal(code))?;
                }
                Ok((u.key(), u.reason.clone()))
            })
            .collect::<Result<HashMap<_, _>, LiveError>>()?;
        let mut instructions: Vec<String> = manifest
            .rungs
            .iter()
            .map(|r| r.instruction.clone())
            .chain(manifest.unrealisable.iter().map(|u| u.instruction.clone()))
            .collect();
        instructions.sort();
        instructions.dedup();
        let signature = manifest.signature();
        Ok(BenchBackend {
            state: Mutex::new(Live {
                link: settings.link.open(),
                verified: false,
                verified_on: 0,
                trigger: 0,
                cpu: None,
                simulated: false,
                not_executed: None,
                down: None,
                breaker: Breaker::new(settings.max_consecutive_faults),
            }),
            fence: WriteFence::new(allowed),
            settings,
            profile,
            rungs,
            unrealisable,
            instructions,
            mailbox,
            signature,
            reconnects: AtomicUsize::new(0),
        })
    }

    pub(crate) fn settings(&self) -> &BenchSettings {
        &self.settings
    }

    #[cfg(test)]
    pub(crate) fn fence(&self) -> &WriteFence {
        &self.fence
    }

    fn variant(&self) -> Option<&Variant> {
        self.profile.variant(&self.settings.variant)
    }

    /// Connects and runs the interlocks now, so that a bench that is not ready is an error
    /// before the first case. Writes nothing.
    pub(crate) fn connect(&self) -> Result<(), LiveError> {
        let mut live = self.lock();
        self.verify(&mut live).map_err(|e| match e {
            CaseError::Link(c) => LiveError::Link(c),
            CaseError::Fault(f) => LiveError::Refused(f.to_string()),
            CaseError::Stopped(s) => LiveError::Refused(s),
        })
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Live> {
        match self.state.lock() {
            Ok(s) => s,
            Err(poisoned) => poisoned.into_inner(),
        }
    }

    /// The rung the last case's proof of execution found not executed, taken once: what the
    /// pulse self-test tells from any other fault.
    pub(crate) fn take_not_executed(&self) -> Option<u16> {
        self.lock().not_executed.take()
    }

    /// Requests sent so far.
    #[cfg(test)]
    pub(crate) fn requests(&self) -> u64 {
        self.lock().link.requests()
    }

    /// The rung, flags and window a request would run with, each window range checked against
    /// the fence; no socket is involved. `Err` is why the case cannot run on this program.
    pub(crate) fn plan(&self, req: &Request<'_>) -> Result<Plan, LiveError> {
        let key = Call::new(req.operands, req.indirect).key(req.instruction);
        let Some(&rung) = self.rungs.get(&key) else {
            return Err(LiveError::Refused(self.no_rung(&key)));
        };
        let all = req.all_flags();
        let flags = self
            .settings
            .manifest
            .flags
            .iter()
            .enumerate()
            .filter(|(_, f)| all.get(*f).copied().unwrap_or(false))
            .fold(0u16, |acc, (i, _)| acc | 1 << i);
        let mut window = Vec::new();
        for (head, last) in window::ranges(req) {
            let (code, first) = (head.code(), head.index);
            if let Some(why) = self.settings.link.addressing().unaddressable(&head) {
                return Err(refused!("not run: the case sets {code} words: {why}"));
            }
            let range = WordRange::within(&head, first, last);
            self.fence.check(&range).map_err(|e| {
                match self.settings.link.addressing().kind(&head) {
                    fence::Kind::Special => refused!(
                        "not run: {e}; {code} is a special register, which `sandbox=manifest` \
                     leaves out: name it to let the harness write it (sandbox=manifest,{range})"
                    ),
                    _ => refused!(
                        "not run: {e}; declare a sandbox that covers the manifest's `writes`"
                    ),
                }
            })?;
            let words = (first..=last)
                .step_by(head.points() as usize)
                .map(|i| req.memory.word(&head.with_index(i)))
                .collect();
            window.push((head, words));
        }
        Ok(Plan {
            rung,
            flags,
            window,
        })
    }

    fn no_rung(&self, key: &str) -> String {
        match self.unrealisable.get(key) {
            Some(reason) => format!("the program cannot hold `{key}`: {reason}"),
            None => format!(
                "the program has no rung for `{key}`: generate it again from this corpus \
                 (`plc-conformance hil generate`) and write it to the CPU"
            ),
        }
    }

    /// The interlocks, before any write on a connection: type name, RUN, signature, a moving
    /// scan counter, and the program idle. Read-only.
    fn verify(&self, live: &mut Live) -> Result<(), CaseError> {
        let name = live.link.identify()?;
        live.cpu = Some(name.shown.clone());
        if name.name != self.settings.confirm {
            return Err(CaseError::Stopped(format!(
                "the CPU says it is `{}`, but `confirm` says `{}`: not the CPU this backend is \
                 configured for, so nothing is written",
                name.name, self.settings.confirm
            )));
        }
        let run = live.link.run_state()?;
        if !run.running {
            return Err(CaseError::Stopped(format!(
                "the CPU is in {}: the test program runs only in RUN; nothing is written and no \
                 remote RUN is sent",
                run.text
            )));
        }
        let words = live.link.read(&self.mailbox, mailbox::WORDS)?;
        if let Some(why) = Signature::of(&words).mismatch(&self.signature) {
            return Err(CaseError::Stopped(why));
        }
        live.simulated = words.get(off::ORIGIN as usize) == Some(&mailbox::SIMULATOR);
        let scans = |w: &[u16]| w.get(off::SCANS as usize).copied().unwrap_or(0);
        let first = scans(&words);
        let since = Instant::now();
        let counter = mailbox::at(&self.mailbox, off::SCANS);
        loop {
            let now = live.link.read(&counter, 1)?;
            if now.first().copied() != Some(first) {
                break;
            }
            if since.elapsed() > Duration::from_secs(1) {
                return Err(CaseError::Stopped(format!(
                    "the scan counter {counter} did not move in 1 s: the program is not \
                     running"
                )));
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        // A case left over from a lost connection finishes before a new one starts.
        let pair = |w: &[u16]| (w[0], w[1]);
        let trigger_at = mailbox::at(&self.mailbox, off::TRIGGER);
        let mut tw = live.link.read(&trigger_at, 2)?;
        let since = Instant::now();
        while pair(&tw).0 != pair(&tw).1 {
            if since.elapsed() > self.settings.case_timeout {
                return Err(CaseError::Fault(Fault::Timeout(format!(
                    "the program is still busy with an earlier case (trigger {}, ack {}) after \
                     {} s",
                    tw[0],
                    tw[1],
                    self.settings.case_timeout.as_secs_f64()
                ))));
            }
            std::thread::sleep(Duration::from_millis(2));
            tw = live.link.read(&trigger_at, 2)?;
        }
        live.trigger = tw[1];
        live.verified = true;
        live.verified_on = live.link.connections();
        Ok(())
    }

    fn poll(&self, live: &mut Live) -> Result<Status, LinkError> {
        let at = |o| mailbox::at(&self.mailbox, o);
        let (w, state_now) = live.link.poll(&[
            at(off::ACK),
            at(off::STATE),
            at(off::FLAG_BEFORE),
            at(off::FLAG_AFTER),
            at(off::CODE),
            at(off::CODE_EXTRA),
            at(off::CODE_NEXT),
            at(off::RAN),
            at(off::RAN_FOR),
            at(off::ENO),
        ])?;
        let get = |i: usize| w.get(i).copied().unwrap_or(0);
        Ok(Status {
            ack: get(0),
            state: get(1),
            flag_before: get(2),
            flag_after: get(3),
            code: get(4),
            extra: get(5),
            next: get(6),
            ran: get(7),
            ran_for: get(8),
            eno: get(9),
            state_now,
        })
    }

    /// One case on the CPU.
    fn run_case(
        &self,
        live: &mut Live,
        req: &Request<'_>,
        plan: &Plan,
    ) -> Result<Outcome, CaseError> {
        live.not_executed = None;
        if !live.verified
            || live.verified_on != live.link.connections()
            || !live.link.is_connected()
        {
            if live.link.connections() > 0 {
                self.reconnects.fetch_add(1, Ordering::Relaxed);
            }
            self.verify(live)?;
        }
        let batch = live.link.batch_words();
        let refused = |e: fence::Refused| CaseError::Fault(Fault::Protocol(e.to_string()));
        for (head, words) in &plan.window {
            for w in self.fence.writes(batch, head, words).map_err(refused)? {
                live.link.write(&w)?;
            }
        }
        let rung_at = mailbox::at(&self.mailbox, off::RUNG);
        for w in self
            .fence
            .writes(batch, &rung_at, &[plan.rung, plan.flags])
            .map_err(refused)?
        {
            live.link.write(&w)?;
        }
        let trigger = mailbox::next_trigger(live.trigger);
        let trigger_at = mailbox::at(&self.mailbox, off::TRIGGER);
        for w in self
            .fence
            .writes(batch, &trigger_at, &[trigger])
            .map_err(refused)?
        {
            live.link.write(&w)?;
        }
        live.trigger = trigger;
        let deadline = Instant::now() + self.settings.case_timeout;
        let mut wait = self.settings.first_poll;
        let status = loop {
            let s = self.poll(live)?;
            if !s.state_now.running {
                return Err(CaseError::Stopped(format!(
                    "the CPU left RUN during case {} (now {}); if an operation error stops it, \
                     set the CPU parameter for operation errors to continue (docs/live-cpu.md)",
                    req.case_id, s.state_now.text
                )));
            }
            if s.ack == trigger {
                // The program acknowledges in the scan it goes idle (or finds the error reset
                // failed): an acknowledgement in any other state is not the program's.
                if s.state != state::IDLE && s.state != state::RESET_FAILED {
                    return Err(CaseError::Fault(Fault::Protocol(format!(
                        "case {} is acknowledged (trigger {trigger}) while the program's state \
                         says {} ({}): the generated program acknowledges only once it is done, \
                         so something other than it answered; nothing is judged",
                        req.case_id,
                        s.state,
                        state::name(s.state)
                    ))));
                }
                break s;
            }
            if Instant::now() >= deadline {
                return Err(CaseError::Fault(Fault::Timeout(format!(
                    "the program did not acknowledge case {} (trigger {trigger}, ack {}, state \
                     {}) within {} s: is the CPU in RUN with the generated program, and the \
                     mailbox where the manifest says?",
                    req.case_id,
                    s.ack,
                    s.state,
                    self.settings.case_timeout.as_secs_f64()
                ))));
            }
            std::thread::sleep(wait);
            wait = (wait * 2).min(self.settings.max_poll);
        };
        if status.state == state::RESET_FAILED || status.flag_before != 0 {
            let errors = &self.settings.manifest.error;
            let code = (errors.register.as_ref())
                .map(|r| format!(" ({r}={:04X}H)", status.code))
                .unwrap_or_default();
            return Err(CaseError::Fault(Fault::Unreachable(format!(
                "the error flag {} stayed on after the error reset ({}), so case {} was not \
                 executed{code}",
                errors.flag, errors.reset, req.case_id,
            ))));
        }
        // The proof of execution: the rung itself says it ran for this trigger, and executed.
        let not_executed = if status.ran != plan.rung || status.ran_for != trigger {
            Some(format!(
                "rung {} did not run for case {} (trigger {trigger}): the mailbox says rung {} \
                 ran last, for trigger {}; the rung is missing from the program on the CPU or \
                 did not execute, so nothing is judged",
                plan.rung, req.case_id, status.ran, status.ran_for
            ))
        } else if status.eno == 0 && status.flag_after == 0 {
            Some(format!(
                "rung {} was enabled for case {} but its instruction reported ENO FALSE and no \
                 error: it did not execute (a pulse form whose enable did not fall since the \
                 last case, or a call edited out of the rung), so nothing is judged",
                plan.rung, req.case_id
            ))
        } else {
            None
        };
        if let Some(why) = not_executed {
            live.not_executed = Some(plan.rung);
            return Err(CaseError::Fault(Fault::Protocol(why)));
        }
        let mut outcome = Outcome::default();
        // The rung stores each address in its pointer its own way: not judged.
        let pointers = pointer_words(req.indirect.values());
        for (head, before) in &plan.window {
            let after = live.link.read(head, before.len() as u32)?;
            for (i, (b, a)) in before.iter().zip(&after).enumerate() {
                let device = head.with_index(head.index + i as u32);
                if a != b && !pointers.contains(&device) {
                    outcome.writes.insert(device, Value::from(*a));
                }
            }
        }
        if status.flag_after != 0 {
            let errors = &self.settings.manifest.error;
            if status.next != status.code {
                return Err(CaseError::Fault(Fault::Protocol(format!(
                    "{} changed after the scan of case {}: {:04X}H right after the instruction, \
                     {:04X}H one scan later",
                    errors.register.as_deref().unwrap_or("the error register"),
                    req.case_id,
                    status.code,
                    status.next
                ))));
            }
            // The code is the error register as read; the registers go to the judge, which
            // holds each one (a family's further register beside the first) to the code.
            outcome.error = Some(req.error(status.code));
            let read = [
                (errors.register.as_ref(), status.code),
                (errors.extra.as_ref(), status.extra),
            ];
            for (name, value) in read {
                if let Some(device) = name.and_then(|n| n.parse::<Device>().ok()) {
                    outcome.registers.insert(device, Value::from(value));
                }
            }
        }
        Ok(outcome)
    }

    /// The CPU (or the simulated one) as it reported itself, the variant, the program and the
    /// transport.
    fn what_answers(&self) -> String {
        let live = self.lock();
        let cpu = live
            .cpu
            .clone()
            .unwrap_or_else(|| format!("`{}` (not yet read)", self.settings.confirm));
        let what = if live.simulated {
            "simulated CPU"
        } else {
            "live CPU"
        };
        format!(
            "{what} {cpu}, {} variant {}, program {} (mailbox layout {}), {}",
            self.profile.id,
            self.settings.variant,
            self.settings.manifest.hash,
            mailbox::LAYOUT,
            self.settings.link.describe()
        )
    }
}

impl Backend for BenchBackend {
    fn name(&self) -> &str {
        &self.settings.name
    }

    fn profile(&self) -> &str {
        &self.profile.id
    }

    /// What a recording names as the backend's version: the CPU as it reported itself (its
    /// name as the link reads it, once connected), the profile variant, the program (manifest
    /// hash and mailbox layout) and the transport; both fills of every case are executed.
    fn describe(&self) -> String {
        format!("{}, both fills", self.what_answers())
    }

    fn version(&self) -> Option<String> {
        Some(self.what_answers())
    }

    fn simulated_by(&self) -> Option<String> {
        self.lock().simulated.then(|| {
            format!(
                "the simulated CPU (plc-conformance hil sim) at {}",
                self.settings.link.address()
            )
        })
    }

    fn claims(&self, instruction: &str, variant: &str) -> bool {
        variant == self.settings.variant
            && self.instructions.iter().any(|i| i == instruction)
            && self
                .variant()
                .is_some_and(|v| self.profile.has_instruction(v, instruction))
    }

    fn declines(&self, setting: &Setting<'_>) -> Option<String> {
        let key = Call::new(setting.operands, setting.indirect).key(setting.instruction);
        (!self.rungs.contains_key(&key)).then(|| self.no_rung(&key))
    }

    fn chunk_trials(&self) -> usize {
        16
    }

    fn restarts(&self) -> usize {
        self.reconnects.load(Ordering::Relaxed)
    }

    fn execute(&self, req: &Request<'_>) -> Result<Response, Fault> {
        let plan = match self.plan(req) {
            Ok(p) => p,
            Err(why) => return Ok(Response::Unsupported(chain(&why))),
        };
        let mut live = self.lock();
        if let Some(why) = &live.down {
            return Err(Fault::Unreachable(why.clone()));
        }
        if closing() {
            return Err(Fault::Unreachable(
                "not run: the run was interrupted".into(),
            ));
        }
        match self.run_case(&mut live, req, &plan) {
            Ok(outcome) => {
                live.breaker.answered();
                Ok(Response::Done(outcome))
            }
            Err(e) => {
                live.link.disconnect();
                live.verified = false;
                let fault = match e {
                    CaseError::Link(c) => c.fault(),
                    CaseError::Fault(f) => f,
                    CaseError::Stopped(why) => {
                        live.down = Some(format!("not run: {why}"));
                        return Err(Fault::Unreachable(why));
                    }
                };
                if let Some(why) = live.breaker.trips(&self.settings.name, &fault) {
                    live.down = Some(why);
                }
                Err(fault)
            }
        }
    }
}

#[cfg(test)]
mod end_to_end;
