//! The generated test program as the simulated CPU runs it, scan by scan, with the reference
//! model executing each rung, and the settings that shape it: the one part that must behave
//! as the program on a real CPU does.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use super::cpu::{Audit, Cpu, SimRung};
use super::fault::FaultRule;
use crate::backend::bench::addressing::Addressing;
use crate::backend::bench::error::{refused, LiveError};
use crate::backend::bench::fence::{parse_ranges, WordRange};
use crate::backend::bench::mailbox::{self, off, state};
use crate::backend::bench::manifest::{parse_operand, Manifest};
use crate::backend::{Backend, Request as ModelRequest, Response as ModelResponse};
use crate::device::Device;
use crate::memory::{Fill, Image, Unit};
use crate::model::profile::Profile;
use crate::model::{ErrorSignal, Operand};

/// How a simulated CPU is set up; `L` is what its link's server adds (a name and model code,
/// a device form it refuses).
#[derive(Debug, Clone)]
pub struct SimSettings<L> {
    pub manifest: Manifest,
    /// The profile variant the CPU is.
    pub variant: String,
    /// Time between scans.
    pub scan: Duration,
    /// Whether the program is written to the CPU (without it the mailbox stays cleared).
    pub program: bool,
    /// Whether the CPU starts in RUN.
    pub run: bool,
    /// The port on 127.0.0.1 (0: any free one).
    pub port: u16,
    /// Evaluate a rung only in the scan it is selected, as a program with its rungs inside a
    /// CASE would: a pulse form's enable then never falls, and the rung fires on its first
    /// case only. The generator never writes such a program; tests use this to show that the
    /// corpus catches one.
    pub rungs_in_case: bool,
    /// Error registers the CPU leaves alone on an error (a firmware that does not copy the
    /// code to its second register): tests use this to show that the judge holds every
    /// register to the code.
    pub untouched_registers: Vec<Device>,
    /// Rungs missing from the program on the CPU: neither the call nor its proof of execution
    /// is there, while the program still acknowledges every trigger.
    pub missing_rungs: BTreeSet<u16>,
    /// Rungs whose call never executes (edited out, or its enable changed): the rung still
    /// writes its proof of execution, with ENO FALSE.
    pub disabled_rungs: BTreeSet<u16>,
    /// Whether the mailbox says a simulator runs the program ([`mailbox::SIMULATOR`]). Off, it
    /// stands for a CPU, so that what a real CPU's recording keeps can be tested.
    pub identifies: bool,
    /// A proxy between the PC and the program: after the first case every trigger written is
    /// kept from the program, and the status polls answer ack = trigger in state 1.
    pub premature_ack: bool,
    pub faults: Vec<FaultRule>,
    /// What the link's server adds.
    pub link: L,
}

impl<L> SimSettings<L> {
    /// The same CPU with what another server adds.
    pub(crate) fn relink<M>(self, link: M) -> SimSettings<M> {
        SimSettings {
            manifest: self.manifest,
            variant: self.variant,
            scan: self.scan,
            program: self.program,
            run: self.run,
            port: self.port,
            rungs_in_case: self.rungs_in_case,
            untouched_registers: self.untouched_registers,
            missing_rungs: self.missing_rungs,
            disabled_rungs: self.disabled_rungs,
            identifies: self.identifies,
            premature_ack: self.premature_ack,
            faults: self.faults,
            link,
        }
    }

    /// A CPU in RUN with the program, scanning every 200 µs.
    pub fn with_link(manifest: Manifest, variant: impl Into<String>, link: L) -> Self {
        SimSettings {
            manifest,
            variant: variant.into(),
            scan: Duration::from_micros(200),
            program: true,
            run: true,
            port: 0,
            rungs_in_case: false,
            untouched_registers: Vec::new(),
            missing_rungs: BTreeSet::new(),
            disabled_rungs: BTreeSet::new(),
            identifies: true,
            premature_ack: false,
            faults: Vec::new(),
            link,
        }
    }
}

/// The program and the CPU's memory, shared by the scan thread and the server's connections.
pub(crate) struct Program<L> {
    cpu: Mutex<Cpu>,
    pub(crate) stop: AtomicBool,
    pub(crate) settings: SimSettings<L>,
    profile: Arc<Profile>,
    model: Arc<dyn Backend>,
    pub(crate) mailbox: Device,
    rungs: Vec<SimRung>,
    allowed: Vec<WordRange>,
    /// Where the link's server shows whether the CPU runs (a status register, a relay), set on
    /// every change.
    show_state: fn(&SimSettings<L>, &mut Cpu),
}

/// Word devices the CPU holds, with their sizes: the profile's for the variant, and `more`.
fn word_devices(
    profile: &Profile,
    variant: &str,
    more: &[(&str, usize)],
) -> BTreeMap<String, Vec<u16>> {
    let mut words = BTreeMap::new();
    if let Some(v) = profile.variant(variant) {
        for code in profile.devices.keys() {
            if let Some(r) = profile.ranges(v, code) {
                let last = r.iter().map(|r| r.last).max().unwrap_or(0);
                words.insert(code.clone(), vec![0u16; last as usize + 1]);
            }
        }
    }
    for (code, size) in more {
        let w = words.entry(code.to_string()).or_insert_with(Vec::new);
        if w.len() < *size {
            w.resize(*size, 0);
        }
    }
    words
}

/// Whether an instruction is the pulse form of another one the profile has.
fn is_pulse(profile: &Profile, instruction: &str) -> bool {
    instruction
        .strip_suffix('P')
        .is_some_and(|base| profile.instructions.contains_key(base))
}

impl<L> Program<L> {
    /// The program, its rungs and a CPU's cleared memory, from the settings: every word device
    /// of the profile's variant, and `more` words of the codes the link's server adds (special
    /// registers, link registers). `show_state` writes whether the CPU runs where the link reads
    /// it.
    pub(crate) fn new(
        settings: SimSettings<L>,
        profile: Arc<Profile>,
        model: Arc<dyn Backend>,
        addressing: &dyn Addressing,
        more: &[(&str, usize)],
        show_state: fn(&SimSettings<L>, &mut Cpu),
    ) -> Result<Arc<Program<L>>, LiveError> {
        settings.manifest.validate(addressing)?;
        if profile.variant(&settings.variant).is_none() {
            return Err(refused!(
                "`{}` is not a variant of {}",
                settings.variant,
                profile.id
            ));
        }
        let mailbox = settings.manifest.mailbox_head(addressing)?;
        let rungs = settings
            .manifest
            .rungs
            .iter()
            .map(|r| {
                let hexadecimal = |code: &str| profile.devices.is_hexadecimal(code);
                let operands = r
                    .operands
                    .iter()
                    .map(|(k, v)| parse_operand(v, &hexadecimal).map(|o| (k.clone(), o)))
                    .collect::<Result<BTreeMap<_, _>, _>>()?;
                let device = |text: &str| Device::parse_numbered(text, hexadecimal);
                let addresses = (r.addresses.iter())
                    .map(|(p, t)| Ok((device(p)?, device(t)?)))
                    .collect::<Result<Vec<_>, crate::device::DeviceSyntaxError>>()
                    .map_err(|e| LiveError::within(format!("rung {}", r.id), e))?;
                Ok(SimRung {
                    id: r.id,
                    instruction: r.instruction.clone(),
                    operands,
                    indirect: (r.operands.iter())
                        .filter(|(_, v)| v.starts_with('@'))
                        .map(|(k, _)| k.clone())
                        .collect(),
                    addresses,
                    pulse: is_pulse(&profile, &r.instruction),
                })
            })
            .collect::<Result<Vec<_>, LiveError>>()?;
        let mut allowed = parse_ranges(&settings.manifest.writes.join(","), addressing)
            .map_err(|e| LiveError::within("the manifest's `writes`", e))?;
        allowed.extend(mailbox::pc_words(&mailbox));
        let cpu = Cpu {
            words: word_devices(&profile, &settings.variant, more),
            image: None,
            bits: BTreeMap::new(),
            running: settings.run,
            prev: vec![false; rungs.len() + 1],
            prev_reset: false,
            audit: Audit::default(),
            faults: settings.faults.iter().map(|f| (f.clone(), 0)).collect(),
            addressed: Vec::new(),
            triggers: 0,
            withheld: None,
            held: BTreeSet::new(),
        };
        let mut cpu = cpu;
        show_state(&settings, &mut cpu);
        Ok(Arc::new(Program {
            cpu: Mutex::new(cpu),
            stop: AtomicBool::new(false),
            settings,
            profile,
            model,
            mailbox,
            rungs,
            allowed,
            show_state,
        }))
    }

    pub(crate) fn lock(&self) -> MutexGuard<'_, Cpu> {
        match self.cpu.lock() {
            Ok(c) => c,
            Err(poisoned) => poisoned.into_inner(),
        }
    }

    /// Puts the CPU in RUN or STOP.
    pub(crate) fn set_running(&self, cpu: &mut Cpu, run: bool) {
        cpu.running = run;
        (self.show_state)(&self.settings, cpu);
    }

    /// A write from the PC, as the CPU takes it: audited against the manifest's words, and
    /// with `premature_ack` every trigger after the first kept from the program.
    pub(crate) fn write(&self, cpu: &mut Cpu, head: &Device, words: &[u16]) {
        let asked = WordRange::of(head, words.len() as u32);
        if !self.allowed.iter().any(|r| r.contains(&asked)) {
            cpu.audit.stray_writes.push(asked.to_string());
        }
        let trigger = mailbox::at(&self.mailbox, off::TRIGGER);
        for (i, w) in words.iter().enumerate() {
            let device = head.with_index(head.index + i as u32);
            if trigger == device {
                cpu.triggers += 1;
                if self.settings.premature_ack && cpu.triggers > 1 {
                    cpu.withheld = Some(*w);
                    continue;
                }
            }
            cpu.set_word(&device, *w);
        }
    }

    /// A word as a status poll reads it: with `premature_ack`, the proxy answers the trigger it
    /// kept as the ack, and state 1.
    pub(crate) fn read(&self, cpu: &Cpu, device: &Device) -> Option<u16> {
        let at = |o| mailbox::at(&self.mailbox, o);
        match cpu.withheld {
            Some(withheld) if *device == at(off::ACK) => Some(withheld),
            Some(_) if *device == at(off::STATE) => Some(state::RESETTING),
            _ => cpu.word(device),
        }
    }
}

/// One scan of the generated program.
pub(crate) fn scan<L>(shared: &Program<L>, cpu: &mut Cpu) {
    if !cpu.running || !shared.settings.program {
        return;
    }
    let m = &shared.settings.manifest;
    let at = |o: u32| mailbox::at(&shared.mailbox, o);
    let hash = m.hash32();
    cpu.set_word(&at(off::MAGIC), mailbox::MAGIC[0]);
    cpu.set_word(&at(off::MAGIC + 1), mailbox::MAGIC[1]);
    cpu.set_word(&at(off::LAYOUT), mailbox::LAYOUT);
    cpu.set_word(&at(off::HASH), hash as u16);
    cpu.set_word(&at(off::HASH + 1), (hash >> 16) as u16);
    cpu.set_word(&at(off::RUNGS), m.rungs.len() as u16);
    let origin = match shared.settings.identifies {
        true => mailbox::SIMULATOR,
        false => 0,
    };
    cpu.set_word(&at(off::ORIGIN), origin);
    let scans = cpu.word(&at(off::SCANS)).unwrap_or(0).wrapping_add(1);
    cpu.set_word(&at(off::SCANS), scans);
    let flag_now = u16::from(cpu.bit(&m.error.flag));
    cpu.set_word(&at(off::FLAG_NOW), flag_now);
    let resets_itself = m.error.reset == m.error.flag;
    let trigger = cpu.word(&at(off::TRIGGER)).unwrap_or(0);
    let ack = cpu.word(&at(off::ACK)).unwrap_or(0);
    let st = cpu.word(&at(off::STATE)).unwrap_or(0);
    let mut exec = false;
    if trigger != ack {
        match st {
            state::IDLE | state::RESET_FAILED => {
                // A program that resets the flag itself (`RST M8004`) clears it in this scan;
                // a reset flag clears it at the end of the scan it rises in.
                cpu.set_bit(&m.error.reset, !resets_itself);
                for o in [off::RAN, off::RAN_FOR, off::ENO] {
                    cpu.set_word(&at(o), 0);
                }
                cpu.set_word(&at(off::STATE), state::RESETTING);
            }
            state::RESETTING => {
                if !resets_itself {
                    cpu.set_bit(&m.error.reset, false);
                }
                if cpu.bit(&m.error.flag) {
                    cpu.set_word(&at(off::FLAG_BEFORE), 1);
                    cpu.set_word(&at(off::STATE), state::RESET_FAILED);
                    cpu.set_word(&at(off::ACK), trigger);
                } else {
                    cpu.set_word(&at(off::FLAG_BEFORE), 0);
                    cpu.set_word(&at(off::STATE), state::EXECUTING);
                }
            }
            state::EXECUTING => {
                let bits = cpu.word(&at(off::FLAGS)).unwrap_or(0);
                for (i, f) in m.flags.iter().enumerate() {
                    cpu.set_bit(f, bits & (1 << i) != 0);
                }
                exec = true;
            }
            _ => {}
        }
    }
    let selected = cpu.word(&at(off::RUNG)).unwrap_or(0);
    let settings = &shared.settings;
    for rung in &shared.rungs {
        if settings.missing_rungs.contains(&rung.id) {
            continue;
        }
        let enable = exec && selected == rung.id;
        let i = usize::from(rung.id);
        if settings.rungs_in_case && !enable {
            continue;
        }
        // ADRSET is no pulse form: it stores the addresses whenever the rung is enabled.
        if enable {
            for (pointer, target) in &rung.addresses {
                cpu.adrset(target, pointer);
            }
        }
        let fire = if rung.pulse {
            enable && !cpu.prev[i]
        } else {
            enable
        } && !settings.disabled_rungs.contains(&rung.id);
        cpu.prev[i] = enable;
        let mut eno = false;
        if fire {
            match cpu.resolve(rung) {
                Ok(operands) => {
                    let flag_before = cpu.bit(&m.error.flag);
                    execute(shared, cpu, &rung.instruction, &operands);
                    // ENO FALSE on an operation error, as IEC 61131-3 has it.
                    eno = flag_before || !cpu.bit(&m.error.flag);
                }
                Err(why) => cpu.audit.anomalies.push(crate::error_chain::chain(&why)),
            }
        }
        // The rung's proof of execution, in the scan it is enabled.
        if enable {
            cpu.set_word(&at(off::RAN), rung.id);
            cpu.set_word(&at(off::RAN_FOR), trigger);
            cpu.set_word(&at(off::ENO), u16::from(eno));
        }
    }
    if exec {
        let flag = u16::from(cpu.bit(&m.error.flag));
        cpu.set_word(&at(off::FLAG_AFTER), flag);
        let code = m.error.register.as_ref().map_or(0, |r| cpu.reg(r));
        cpu.set_word(&at(off::CODE), code);
        let extra = m.error.extra.as_ref().map_or(0, |e| cpu.reg(e));
        cpu.set_word(&at(off::CODE_EXTRA), extra);
        for f in &m.flags {
            cpu.set_bit(f, false);
        }
        cpu.set_word(&at(off::STATE), state::DONE);
    } else if st == state::DONE {
        let code = m.error.register.as_ref().map_or(0, |r| cpu.reg(r));
        cpu.set_word(&at(off::CODE_NEXT), code);
        cpu.set_word(&at(off::STATE), state::IDLE);
        cpu.set_word(&at(off::ACK), trigger);
    }
    // END processing: the reset flag's rising edge clears the error state.
    let reset = !resets_itself && cpu.bit(&m.error.reset);
    if reset && !cpu.prev_reset {
        cpu.set_bit(&m.error.flag, false);
        if let Some(r) = &m.error.register {
            cpu.set_reg(r, 0);
        }
        if let Some(e) = &m.error.extra {
            cpu.set_reg(e, 0);
        }
    }
    cpu.prev_reset = reset;
}

/// Executes one rung with the reference model on the device memory.
fn execute<L>(
    shared: &Program<L>,
    cpu: &mut Cpu,
    instruction: &str,
    operands: &BTreeMap<String, Operand>,
) {
    cpu.audit.executions += 1;
    let Some(variant) = shared.profile.variant(&shared.settings.variant) else {
        return;
    };
    let flags: BTreeMap<String, bool> = shared
        .settings
        .manifest
        .flags
        .iter()
        .map(|f| (f.clone(), cpu.bit(f)))
        .collect();
    // The whole of every word device, so that the model reads what the CPU holds; dropped
    // before the writes, which then update the kept image in place.
    let image = Image::sharing(cpu.image(&shared.profile.devices), Fill::A, Unit::Word);
    let request = ModelRequest {
        profile: &shared.profile,
        variant,
        instruction,
        case_id: "simulated",
        flags: &flags,
        operands,
        indirect: crate::model::DIRECT,
        memory: &image,
    };
    let answer = shared.model.execute(&request);
    drop(image);
    match answer {
        Ok(ModelResponse::Done(outcome)) => {
            // A word of a 16-bit family: its model writes no more.
            for (d, v) in &outcome.writes {
                cpu.set_word(d, *v as u16);
            }
            let errors = &shared.settings.manifest.error;
            match outcome.error {
                Some(ErrorSignal::Code(_)) => {
                    cpu.set_bit(&errors.flag, true);
                    for (register, code) in &outcome.registers {
                        if !shared.settings.untouched_registers.contains(register) {
                            cpu.set_word(register, *code as u16);
                        }
                    }
                }
                Some(ErrorSignal::Flag(f)) => cpu.set_bit(&f.to_string(), true),
                None => {}
            }
        }
        Ok(other) => cpu
            .audit
            .anomalies
            .push(format!("{instruction}: the model answered {other:?}")),
        Err(fault) => cpu
            .audit
            .anomalies
            .push(format!("{instruction}: the model failed: {fault}")),
    }
}
