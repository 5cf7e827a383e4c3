//! A simulated CPU: an SLMP server on 127.0.0.1 that runs the generated test program's
//! behaviour with a reference model, so that the live backend can be tested end to end without
//! hardware, and can be made to fail in each way a real port fails.
//!
//! The server answers 0101, 0401, 0403 and 1401 in 3E or 4E frames, binary code, in the frame
//! of each request. A scan thread takes the memory lock once per scan, so requests interleave
//! between scans as they do with END processing, and runs the program as generated: the
//! signature and scan counter every scan; on a new trigger, an error reset (the reset flag's
//! rising edge clears the error flag and registers at the end of the scan), then one scan with
//! the selected rung enabled, the error flag and registers captured in that scan and the error
//! register again one scan later, then the acknowledgement. Every rung is evaluated every scan
//! with its own enable, and a pulse form (`...P`) executes only on its enable's rising edge,
//! which is what makes the same pulse rung fire again on the next case.
//!
//! Everything it received is audited: the commands, and every written word that lies outside
//! the manifest's `writes` and the mailbox's PC words (a stray write the tests fail on).

mod remote;

pub use remote::RemoteProgram;

use std::collections::{BTreeMap, BTreeSet};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

use super::frame::{
    self, decode_body, message_len, Code, Decoded, DeviceForm, DeviceRef, FrameKind, Request,
    Response,
};
use super::limits::{Family, Limits};
use crate::backend::bench::error::{refused, LiveError};
use crate::backend::bench::fence::{parse_ranges, WordRange};
use crate::backend::bench::mailbox::{self, off, state};
use crate::backend::bench::manifest::{parse_operand, Manifest};
use crate::backend::{Backend, Request as ModelRequest, Response as ModelResponse};
use crate::device::Device;
use crate::memory::{Fill, Image, Value};
use crate::model::profile::Profile;
use crate::model::{ErrorSignal, Operand};

/// What a fault rule does to the request it matches.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FaultAction {
    /// Close the connection without processing the request or answering.
    Drop,
    /// Process the request, answer after this long.
    Delay(Duration),
    /// Answer with this end code without processing the request.
    EndCode(u16),
    /// Answer with bytes that are not an SLMP response, without processing the request.
    Garbage,
    /// Process the request, answer with another serial number (4E).
    WrongSerial,
    /// Process the request, then go to STOP (SD203) and stop scanning.
    Stop,
}

/// A fault on the `nth` request (from 1) of a command, optionally only requests whose first
/// device is `head`; it fires once.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FaultRule {
    pub command: u16,
    pub head: Option<Device>,
    pub nth: usize,
    pub action: FaultAction,
}

impl FaultRule {
    /// Reads `COMMAND:NTH:ACTION` as `hil sim --fault` takes it: `1401:3:drop` closes the
    /// connection on the third write; actions `drop`, `delay=MS`, `end=C051` (an end code in
    /// hexadecimal), `garbage`, `serial` (another 4E serial), `stop` (go to STOP).
    pub fn parse(text: &str) -> Result<FaultRule, LiveError> {
        let usage = "a fault is COMMAND:NTH:ACTION, e.g. 1401:3:drop, 0403:2:delay=3000, \
                     0401:1:end=C051; actions: drop, delay=MS, end=CODE, garbage, serial, stop";
        let mut parts = text.split(':');
        let (Some(command), Some(nth), Some(action), None) =
            (parts.next(), parts.next(), parts.next(), parts.next())
        else {
            return Err(refused!("`{text}`: {usage}"));
        };
        let command = u16::from_str_radix(command, 16)
            .ok()
            .filter(|c| {
                [
                    frame::command::READ_TYPE_NAME,
                    frame::command::READ,
                    frame::command::RANDOM_READ,
                    frame::command::WRITE,
                ]
                .contains(c)
            })
            .ok_or_else(|| refused!("`{text}`: the command is 0101, 0401, 0403 or 1401"))?;
        let nth = nth
            .parse::<usize>()
            .ok()
            .filter(|n| *n > 0)
            .ok_or_else(|| refused!("`{text}`: NTH counts requests from 1"))?;
        let action = match action.split_once('=') {
            None if action == "drop" => FaultAction::Drop,
            None if action == "garbage" => FaultAction::Garbage,
            None if action == "serial" => FaultAction::WrongSerial,
            None if action == "stop" => FaultAction::Stop,
            Some(("delay", ms)) => {
                FaultAction::Delay(Duration::from_millis(ms.parse().map_err(|e| {
                    LiveError::within(format!("`{text}`: delay=MS takes milliseconds"), e)
                })?))
            }
            Some(("end", code)) => FaultAction::EndCode(
                u16::from_str_radix(code.trim_end_matches('H'), 16)
                    .ok()
                    .filter(|c| *c != 0)
                    .ok_or_else(|| refused!("`{text}`: end=CODE takes a non-zero hex code"))?,
            ),
            _ => return Err(refused!("`{text}`: {usage}")),
        };
        Ok(FaultRule {
            command,
            head: None,
            nth,
            action,
        })
    }
}

/// How the simulated CPU is set up.
#[derive(Debug, Clone)]
pub struct SimSettings {
    pub manifest: Manifest,
    /// The profile variant the CPU is.
    pub variant: String,
    /// What 0101 answers.
    pub type_name: String,
    pub model_code: u16,
    /// Time between scans.
    pub scan: Duration,
    /// Whether the program is written to the CPU (without it the mailbox stays cleared).
    pub program: bool,
    /// Whether the CPU starts in RUN.
    pub run: bool,
    /// Whether the CPU takes the long device form (subcommand 0002); an FX5 does not.
    pub long_form: bool,
    /// The port on 127.0.0.1 (0: any free one).
    pub port: u16,
    /// Evaluate a rung only in the scan it is selected, as a program with its rungs inside a
    /// CASE would: a pulse form's enable then never falls, and the rung fires on its first
    /// case only. The generator never writes such a program; tests use this to show that the
    /// corpus catches one.
    pub rungs_in_case: bool,
    /// Error registers the CPU leaves alone on an error (a firmware that does not copy the
    /// code to SD8067): tests use this to show that the judge holds every register to the code.
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
}

impl SimSettings {
    pub fn new(
        manifest: Manifest,
        variant: impl Into<String>,
        type_name: impl Into<String>,
    ) -> Self {
        let long_form = manifest.profile != "mitsubishi-fx5";
        let type_name = type_name.into();
        SimSettings {
            manifest,
            variant: variant.into(),
            model_code: model_code(&type_name).unwrap_or(0),
            type_name,
            scan: Duration::from_micros(200),
            program: true,
            run: true,
            long_form,
            port: 0,
            rungs_in_case: false,
            untouched_registers: Vec::new(),
            missing_rungs: BTreeSet::new(),
            disabled_rungs: BTreeSet::new(),
            identifies: true,
            premature_ack: false,
            faults: Vec::new(),
        }
    }
}

/// The model code a CPU reports to 0101 beside its type name, for the CPUs the simulator is
/// usually asked to be. iQ-R: the SLMP reference manual's CPU module model codes (R04CPU 4800H
/// to R120CPU 4804H), which an independent client library's table repeats. FX5: the FX5 SLMP
/// manual's processor type table (FX5U-32MR/ES 4A21H ... FX5UC-32MT/DSS 4A99H); FX5U-32MT/DS
/// 4A49H is on a later revision's table and was read off an FX5U-32MT/DS by the aslmp project.
pub(crate) fn model_code(type_name: &str) -> Option<u16> {
    Some(match type_name {
        "R04CPU" => 0x4800,
        "R08CPU" => 0x4801,
        "R16CPU" => 0x4802,
        "R32CPU" => 0x4803,
        "R120CPU" => 0x4804,
        "FX5U-32MR/ES" => 0x4A21,
        "FX5U-64MR/ES" => 0x4A23,
        "FX5U-80MR/ES" => 0x4A24,
        "FX5U-32MT/ES" => 0x4A29,
        "FX5U-64MT/ES" => 0x4A2B,
        "FX5U-80MT/ES" => 0x4A2C,
        "FX5U-32MT/ESS" => 0x4A31,
        "FX5U-64MT/ESS" => 0x4A33,
        "FX5U-80MT/ESS" => 0x4A34,
        "FX5U-32MT/DS" => 0x4A49,
        "FX5UC-32MT/D" => 0x4A91,
        "FX5UC-32MT/DSS" => 0x4A99,
        _ => return None,
    })
}

/// What the simulator received and did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Audit {
    /// Requests by command code.
    pub commands: BTreeMap<u16, usize>,
    /// Words written outside the manifest's `writes` and the mailbox's PC words.
    pub stray_writes: Vec<String>,
    /// Rung executions.
    pub executions: usize,
    /// Things the program could not do (a rung the model does not implement, ...).
    pub anomalies: Vec<String>,
    pub connections: usize,
}

struct Cpu {
    words: BTreeMap<String, Vec<u16>>,
    bits: BTreeMap<Device, bool>,
    running: bool,
    prev: Vec<bool>,
    prev_reset: bool,
    audit: Audit,
    faults: Vec<(FaultRule, usize)>,
    /// The devices ADRSET has stored an address of: this CPU's address of a device is its
    /// place here, with [`ADDRESS_TAG`] in the pointer's second word.
    addressed: Vec<Device>,
    /// Triggers written so far, and (with `premature_ack`) the last one kept from the program.
    triggers: usize,
    withheld: Option<u16>,
}

/// The second word of an address as this simulated CPU's ADRSET stores it: an encoding of its
/// own, since the manuals the project quotes do not give the real one.
const ADDRESS_TAG: u16 = 0xADD5;

/// One rung of the program as the simulated CPU runs it.
struct SimRung {
    id: u16,
    instruction: String,
    /// Operands, an indirect one as its pointer.
    operands: BTreeMap<String, Operand>,
    /// The operands given by indirect specification.
    indirect: BTreeSet<String>,
    /// ADRSET before the instruction: (pointer, the device whose address it stores).
    addresses: Vec<(Device, Device)>,
    pulse: bool,
}

struct Shared {
    cpu: Mutex<Cpu>,
    stop: AtomicBool,
    settings: SimSettings,
    profile: Arc<Profile>,
    model: Arc<dyn Backend>,
    mailbox: Device,
    rungs: Vec<SimRung>,
    allowed: Vec<WordRange>,
}

/// A running simulator; dropping it stops it.
pub struct Simulator {
    address: SocketAddr,
    shared: Arc<Shared>,
    threads: Vec<JoinHandle<()>>,
}

/// Word devices the simulator serves over SLMP, with their sizes.
fn word_devices(profile: &Profile, variant: &str) -> BTreeMap<String, Vec<u16>> {
    let mut words = BTreeMap::new();
    if let Some(v) = profile.variant(variant) {
        for code in profile.devices.keys() {
            if let Some(r) = profile.ranges(v, code) {
                let last = r.iter().map(|r| r.last).max().unwrap_or(0);
                words.insert(code.clone(), vec![0u16; last as usize + 1]);
            }
        }
    }
    // Special registers: SD0, SD203, SD8067 and their neighbours.
    words.entry("SD".into()).or_insert_with(|| vec![0; 12288]);
    // Link registers, which every MELSEC CPU has though a profile may not name them (iQ-R's
    // default allocation: W0-W1FFF, SW0-SW7FF).
    words.entry("W".into()).or_insert_with(|| vec![0; 0x2000]);
    words.entry("SW".into()).or_insert_with(|| vec![0; 0x800]);
    words
}

impl Simulator {
    /// Starts the server and the scan thread.
    pub fn start(
        settings: SimSettings,
        profile: Arc<Profile>,
        model: Arc<dyn Backend>,
    ) -> Result<Simulator, LiveError> {
        let shared = Shared::new(settings, profile, model)?;
        let port = shared.settings.port;
        let listener = TcpListener::bind(("127.0.0.1", port))
            .map_err(|e| LiveError::within(format!("cannot listen on 127.0.0.1:{port}"), e))?;
        let address = listener
            .local_addr()
            .map_err(|e| LiveError::within("no local address", e))?;
        listener
            .set_nonblocking(true)
            .map_err(|e| LiveError::within("cannot poll the listener", e))?;
        {
            // A CPU in RUN has scanned before anyone can connect to it.
            let mut cpu = shared.lock();
            cpu.set_status();
            scan(&shared, &mut cpu);
        }
        let mut threads = Vec::new();
        let s = shared.clone();
        threads.push(std::thread::spawn(move || scan_loop(&s)));
        let s = shared.clone();
        threads.push(std::thread::spawn(move || accept_loop(&s, &listener)));
        Ok(Simulator {
            address,
            shared,
            threads,
        })
    }

    /// `127.0.0.1:PORT`.
    pub fn address(&self) -> SocketAddr {
        self.address
    }

    pub fn audit(&self) -> Audit {
        self.shared.lock().audit.clone()
    }

    /// Puts the CPU in RUN or STOP.
    pub fn set_running(&self, run: bool) {
        let mut cpu = self.shared.lock();
        cpu.running = run;
        cpu.set_status();
    }

    /// Adds a fault rule while running.
    pub fn add_fault(&self, rule: FaultRule) {
        self.shared.lock().faults.push((rule, 0));
    }

    /// A word of device memory (0 for one the CPU does not have).
    pub fn read(&self, device: &Device) -> u16 {
        self.shared.lock().word(device).unwrap_or(0)
    }

    /// Sets a word of device memory, as a program or an operator would (not audited).
    pub fn poke(&self, device: &Device, value: u16) {
        self.shared.lock().set_word(device, value);
    }
}

impl Drop for Simulator {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::SeqCst);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

/// Whether an instruction is the pulse form of another one the profile has.
fn is_pulse(profile: &Profile, instruction: &str) -> bool {
    instruction
        .strip_suffix('P')
        .is_some_and(|base| profile.instructions.contains_key(base))
}

impl Shared {
    /// The program, its rungs and a CPU's cleared memory, from the settings.
    fn new(
        settings: SimSettings,
        profile: Arc<Profile>,
        model: Arc<dyn Backend>,
    ) -> Result<Arc<Shared>, LiveError> {
        settings.manifest.validate(&super::ADDRESSING)?;
        if profile.variant(&settings.variant).is_none() {
            return Err(refused!(
                "`{}` is not a variant of {}",
                settings.variant,
                profile.id
            ));
        }
        let mailbox = settings.manifest.mailbox_head(&super::ADDRESSING)?;
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
        let mut allowed = parse_ranges(&settings.manifest.writes.join(","), &super::ADDRESSING)
            .map_err(|e| LiveError::within("the manifest's `writes`", e))?;
        allowed.extend(mailbox::pc_words(&mailbox));
        let cpu = Cpu {
            words: word_devices(&profile, &settings.variant),
            bits: BTreeMap::new(),
            running: settings.run,
            prev: vec![false; rungs.len() + 1],
            prev_reset: false,
            audit: Audit::default(),
            faults: settings.faults.iter().map(|f| (f.clone(), 0)).collect(),
            addressed: Vec::new(),
            triggers: 0,
            withheld: None,
        };
        Ok(Arc::new(Shared {
            cpu: Mutex::new(cpu),
            stop: AtomicBool::new(false),
            settings,
            profile,
            model,
            mailbox,
            rungs,
            allowed,
        }))
    }

    fn lock(&self) -> MutexGuard<'_, Cpu> {
        match self.cpu.lock() {
            Ok(c) => c,
            Err(poisoned) => poisoned.into_inner(),
        }
    }
}

impl Cpu {
    /// ADRSET: stores the address of `target` in `pointer` and the word after it.
    fn adrset(&mut self, target: &Device, pointer: &Device) {
        let place = match self.addressed.iter().position(|d| d == target) {
            Some(place) => place,
            None => {
                self.addressed.push(target.clone());
                self.addressed.len() - 1
            }
        };
        self.set_word(pointer, place as u16);
        if let Some(next) = pointer.offset(1) {
            self.set_word(&next, ADDRESS_TAG);
        }
    }

    /// A rung's operands with each indirect one read through its pointer, as the CPU does when
    /// the instruction runs.
    fn resolve(&self, rung: &SimRung) -> Result<BTreeMap<String, Operand>, LiveError> {
        let mut operands = rung.operands.clone();
        for name in &rung.indirect {
            let Some(Operand::Device(pointer)) = rung.operands.get(name) else {
                continue;
            };
            let place = self.word(pointer);
            let tag = pointer.offset(1).and_then(|d| self.word(&d));
            let target = match (place, tag) {
                (Some(place), Some(ADDRESS_TAG)) => self.addressed.get(usize::from(place)),
                _ => None,
            };
            let Some(target) = target else {
                return Err(refused!(
                    "{}: @{pointer} holds no address ADRSET stored",
                    rung.instruction
                ));
            };
            operands.insert(name.clone(), Operand::Device(target.clone()));
        }
        Ok(operands)
    }

    fn word(&self, d: &Device) -> Option<u16> {
        self.words
            .get(d.code())
            .and_then(|w| w.get(d.index as usize))
            .copied()
    }

    fn set_word(&mut self, d: &Device, value: u16) {
        if let Some(w) = self
            .words
            .get_mut(d.code())
            .and_then(|w| w.get_mut(d.index as usize))
        {
            *w = value;
        }
    }

    fn bit(&self, name: &str) -> bool {
        name.parse::<Device>()
            .ok()
            .and_then(|d| self.bits.get(&d).copied())
            .unwrap_or(false)
    }

    fn set_bit(&mut self, name: &str, on: bool) {
        if let Ok(d) = name.parse::<Device>() {
            self.bits.insert(d, on);
        }
    }

    fn set_reg(&mut self, name: &str, value: u16) {
        if let Ok(d) = name.parse::<Device>() {
            self.set_word(&d, value);
        }
    }

    fn reg(&self, name: &str) -> u16 {
        name.parse::<Device>()
            .ok()
            .and_then(|d| self.word(&d))
            .unwrap_or(0)
    }

    /// SD203: 0 in the low four bits for RUN, 2 for STOP.
    fn set_status(&mut self) {
        let v = if self.running { 0x0000 } else { 0x0002 };
        self.set_word(&Device::new("SD", 203), v);
    }

    fn device_words(&self, d: DeviceRef, count: usize) -> Result<&[u16], u16> {
        let letters = frame::device_letters(d.code).ok_or(0xC05C_u16)?;
        let words = self.words.get(letters).ok_or(0xC05C_u16)?;
        let first = d.number as usize;
        words.get(first..first + count).ok_or(0xC056)
    }
}

fn scan_loop(shared: &Shared) {
    while !shared.stop.load(Ordering::SeqCst) {
        {
            let mut cpu = shared.lock();
            scan(shared, &mut cpu);
        }
        std::thread::sleep(shared.settings.scan);
    }
}

/// One scan of the generated program.
fn scan(shared: &Shared, cpu: &mut Cpu) {
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
    let trigger = cpu.word(&at(off::TRIGGER)).unwrap_or(0);
    let ack = cpu.word(&at(off::ACK)).unwrap_or(0);
    let st = cpu.word(&at(off::STATE)).unwrap_or(0);
    let mut exec = false;
    if trigger != ack {
        match st {
            state::IDLE | state::RESET_FAILED => {
                cpu.set_bit(&m.error.reset, true);
                for o in [off::RAN, off::RAN_FOR, off::ENO] {
                    cpu.set_word(&at(o), 0);
                }
                cpu.set_word(&at(off::STATE), state::RESETTING);
            }
            state::RESETTING => {
                cpu.set_bit(&m.error.reset, false);
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
        let code = cpu.reg(&m.error.register);
        cpu.set_word(&at(off::CODE), code);
        let extra = m.error.extra.as_ref().map_or(0, |e| cpu.reg(e));
        cpu.set_word(&at(off::CODE_EXTRA), extra);
        for f in &m.flags {
            cpu.set_bit(f, false);
        }
        cpu.set_word(&at(off::STATE), state::DONE);
    } else if st == state::DONE {
        let code = cpu.reg(&m.error.register);
        cpu.set_word(&at(off::CODE_NEXT), code);
        cpu.set_word(&at(off::STATE), state::IDLE);
        cpu.set_word(&at(off::ACK), trigger);
    }
    // END processing: the reset flag's rising edge clears the error state.
    let reset = cpu.bit(&m.error.reset);
    if reset && !cpu.prev_reset {
        cpu.set_bit(&m.error.flag, false);
        cpu.set_reg(&m.error.register, 0);
        if let Some(e) = &m.error.extra {
            cpu.set_reg(e, 0);
        }
    }
    cpu.prev_reset = reset;
}

/// Executes one rung with the reference model on the device memory.
fn execute(
    shared: &Shared,
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
    // The whole of every word device, so that the model reads what the CPU holds, each named
    // as the profile numbers it (`W1A`).
    let devices = &shared.profile.devices;
    let image: BTreeMap<Device, Value> = cpu
        .words
        .iter()
        .flat_map(|(code, words)| {
            let hexadecimal = devices.is_hexadecimal(code);
            words.iter().enumerate().map(move |(i, w)| {
                let device = match hexadecimal {
                    true => Device::hexadecimal(code, i as u32),
                    false => Device::new(code, i as u32),
                };
                (device, Value::from(*w))
            })
        })
        .collect();
    let image = Image::new(image, Fill::A);
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
    match shared.model.execute(&request) {
        Ok(ModelResponse::Done(outcome)) => {
            // A MELSEC device is a 16-bit word: the model of a word family writes no more.
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

fn accept_loop(shared: &Arc<Shared>, listener: &TcpListener) {
    let mut connections: Vec<JoinHandle<()>> = Vec::new();
    while !shared.stop.load(Ordering::SeqCst) {
        match listener.accept() {
            Ok((stream, _)) => {
                shared.lock().audit.connections += 1;
                let s = shared.clone();
                connections.push(std::thread::spawn(move || serve(&s, stream)));
            }
            Err(_) => std::thread::sleep(Duration::from_millis(2)),
        }
        connections.retain(|c| !c.is_finished());
    }
    for c in connections {
        let _ = c.join();
    }
}

/// Reads one whole request, polling the stop flag; `None` when the connection ends.
fn read_request(shared: &Shared, stream: &mut TcpStream) -> Option<Vec<u8>> {
    let mut buf = vec![0u8; 2];
    fill(shared, stream, &mut buf, 0)?;
    let frame = FrameKind::of_request(buf[0]).unwrap_or(FrameKind::E3);
    let header = frame.header_len();
    buf.resize(header, 0);
    fill(shared, stream, &mut buf, 2)?;
    let total = message_len(frame, &buf).ok()?;
    buf.resize(total, 0);
    fill(shared, stream, &mut buf, header)?;
    Some(buf)
}

fn fill(shared: &Shared, stream: &mut TcpStream, buf: &mut [u8], mut at: usize) -> Option<()> {
    while at < buf.len() {
        if shared.stop.load(Ordering::SeqCst) {
            return None;
        }
        match stream.read(&mut buf[at..]) {
            Ok(0) => return None,
            Ok(n) => at += n,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::TimedOut
                        | std::io::ErrorKind::Interrupted
                ) => {}
            Err(_) => return None,
        }
    }
    Some(())
}

fn serve(shared: &Shared, mut stream: TcpStream) {
    let _ = stream.set_read_timeout(Some(Duration::from_millis(20)));
    let _ = stream.set_nodelay(true);
    while let Some(bytes) = read_request(shared, &mut stream) {
        // A request that does not decode gets no answer, as a CPU stays silent on a frame it
        // does not take.
        let Ok(request) = Request::decode(&bytes) else {
            continue;
        };
        let body = decode_body(&request);
        let action = {
            let mut cpu = shared.lock();
            *cpu.audit.commands.entry(request.command).or_default() += 1;
            let head = match &body {
                Ok(Decoded::Read { head, .. } | Decoded::Write { head, .. }) => Some(*head),
                Ok(Decoded::RandomRead { devices }) => devices.first().copied(),
                _ => None,
            };
            take_fault(&mut cpu, request.command, head)
        };
        let mut response = Response {
            frame: request.frame,
            serial: request.serial,
            route: request.route,
            end_code: 0,
            data: Vec::new(),
        };
        match &action {
            Some(FaultAction::Drop) => return,
            Some(FaultAction::EndCode(code)) => {
                response.end_code = *code;
                response.data = error_information(&request);
            }
            Some(FaultAction::Garbage) => {
                let _ = stream.write_all(b"\xFF\x00garbage, not SLMP\r\n");
                continue;
            }
            _ => {
                let (end_code, data) = match body {
                    Ok(decoded) => handle(shared, &request, decoded),
                    Err(_) => (0xC061, Vec::new()),
                };
                response.end_code = end_code;
                response.data = if end_code == 0 {
                    data
                } else {
                    error_information(&request)
                };
            }
        }
        match action {
            Some(FaultAction::Delay(d)) => std::thread::sleep(d),
            Some(FaultAction::WrongSerial) => response.serial = response.serial.wrapping_add(1),
            Some(FaultAction::Stop) => {
                let mut cpu = shared.lock();
                cpu.running = false;
                cpu.set_status();
            }
            _ => {}
        }
        if stream.write_all(&response.encode()).is_err() {
            return;
        }
    }
}

/// The error information of an error response: the route and the command that failed.
fn error_information(request: &Request) -> Vec<u8> {
    let mut out = vec![request.route.network, request.route.station];
    out.extend_from_slice(&request.route.module_io.to_le_bytes());
    out.push(request.route.multidrop);
    out.extend_from_slice(&request.command.to_le_bytes());
    out.extend_from_slice(&request.subcommand.to_le_bytes());
    out
}

fn take_fault(cpu: &mut Cpu, command: u16, head: Option<DeviceRef>) -> Option<FaultAction> {
    for (rule, seen) in cpu.faults.iter_mut() {
        if rule.command != command {
            continue;
        }
        if let Some(want) = &rule.head {
            let matches = head.is_some_and(|h| {
                frame::device_letters(h.code).is_some_and(|letters| want.is(letters, h.number))
            });
            if !matches {
                continue;
            }
        }
        *seen += 1;
        if *seen == rule.nth {
            return Some(rule.action.clone());
        }
    }
    None
}

/// What the proxy of `premature_ack` answers for a word of a status poll in the program's
/// place: the trigger it kept as the ack, and state 1.
fn proxied(shared: &Shared, cpu: &Cpu, d: DeviceRef) -> Option<u16> {
    let withheld = cpu.withheld?;
    let letters = frame::device_letters(d.code)?;
    let at = |o| mailbox::at(&shared.mailbox, o);
    let is = |o| at(o).is(letters, d.number);
    if is(off::ACK) {
        Some(withheld)
    } else if is(off::STATE) {
        Some(state::RESETTING)
    } else {
        None
    }
}

/// What a request may carry on this CPU: the limits of its family in binary code, the one this
/// simulator speaks, for the device form the request uses.
fn limits(shared: &Shared, request: &Request) -> Limits {
    let form = match request.subcommand {
        0x0002 => DeviceForm::Long,
        _ => DeviceForm::Short,
    };
    super::limits::limits(
        Family::of_profile(&shared.settings.manifest.profile),
        Code::Binary,
        form,
    )
}

/// Answers one decoded request: (end code, data).
fn handle(shared: &Shared, request: &Request, decoded: Decoded) -> (u16, Vec<u8>) {
    if request.subcommand == 0x0002 && !shared.settings.long_form {
        return (0xC059, Vec::new());
    }
    let mut cpu = shared.lock();
    match decoded {
        Decoded::TypeName => (
            0,
            frame::type_name_data(&shared.settings.type_name, shared.settings.model_code),
        ),
        Decoded::Read { head, count } => {
            if count == 0 || count > limits(shared, request).batch_words {
                return (0xC051, Vec::new());
            }
            match cpu.device_words(head, count) {
                Ok(words) => (0, words.iter().flat_map(|w| w.to_le_bytes()).collect()),
                Err(code) => (code, Vec::new()),
            }
        }
        Decoded::RandomRead { devices } => {
            if devices.is_empty() || devices.len() > limits(shared, request).random_points {
                return (0xC054, Vec::new());
            }
            let mut data = Vec::with_capacity(2 * devices.len());
            for d in devices {
                match cpu.device_words(d, 1) {
                    Ok(w) => {
                        let word = proxied(shared, &cpu, d).unwrap_or(w[0]);
                        data.extend_from_slice(&word.to_le_bytes());
                    }
                    Err(code) => return (code, Vec::new()),
                }
            }
            (0, data)
        }
        Decoded::Write { head, words } => {
            if words.is_empty() || words.len() > limits(shared, request).batch_words {
                return (0xC051, Vec::new());
            }
            if let Err(code) = cpu.device_words(head, words.len()) {
                return (code, Vec::new());
            }
            let Some(letters) = frame::device_letters(head.code) else {
                return (0xC05C, Vec::new());
            };
            let asked = WordRange {
                hex: frame::hex_numbered(letters),
                ..WordRange::new(letters, head.number, head.number + words.len() as u32 - 1)
            };
            if !shared.allowed.iter().any(|r| r.contains(&asked)) {
                cpu.audit.stray_writes.push(asked.to_string());
            }
            let trigger = mailbox::at(&shared.mailbox, off::TRIGGER);
            for (i, w) in words.iter().enumerate() {
                let device = Device::new(letters, head.number + i as u32);
                if trigger.is(letters, device.index) {
                    cpu.triggers += 1;
                    if shared.settings.premature_ack && cpu.triggers > 1 {
                        cpu.withheld = Some(*w);
                        continue;
                    }
                }
                cpu.set_word(&device, *w);
            }
            (0, Vec::new())
        }
        Decoded::Other { .. } => (0xC059, Vec::new()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cpu() -> Cpu {
        Cpu {
            words: BTreeMap::from([("D".to_string(), vec![0; 400])]),
            bits: BTreeMap::new(),
            running: true,
            prev: Vec::new(),
            prev_reset: false,
            audit: Audit::default(),
            faults: Vec::new(),
            addressed: Vec::new(),
            triggers: 0,
            withheld: None,
        }
    }

    /// `@D10` is read through D10 and D11 when the instruction runs: nothing before ADRSET,
    /// the device whose address ADRSET stored after it.
    #[test]
    fn fault_rules_read_from_the_command_line() {
        let rule = FaultRule::parse("1401:3:drop").expect("drop");
        assert_eq!(
            (rule.command, rule.nth, rule.action),
            (0x1401, 3, FaultAction::Drop)
        );
        let rule = FaultRule::parse("0403:2:delay=3000").expect("delay");
        assert_eq!(rule.action, FaultAction::Delay(Duration::from_secs(3)));
        let rule = FaultRule::parse("0401:1:end=C051").expect("end code");
        assert_eq!(rule.action, FaultAction::EndCode(0xC051));
        for bad in [
            "1401:0:drop",
            "1402:1:drop",
            "1401:1:explode",
            "1401:1",
            "0401:1:end=0",
        ] {
            assert!(FaultRule::parse(bad).is_err(), "{bad}");
        }
        assert_eq!(model_code("FX5U-32MT/DS"), Some(0x4A49));
        assert_eq!(model_code("R04CPU"), Some(0x4800));
    }

    #[test]
    fn an_indirect_operand_is_read_through_the_address_adrset_stored() {
        let d = |i| Device::new("D", i);
        let rung = SimRung {
            id: 1,
            instruction: "ASCI".into(),
            operands: BTreeMap::from([
                ("s".to_string(), Operand::Device(d(10))),
                ("d".to_string(), Operand::Device(d(200))),
            ]),
            indirect: BTreeSet::from(["s".to_string()]),
            addresses: vec![(d(10), d(100))],
            pulse: false,
        };
        let mut cpu = cpu();
        let e = crate::error_chain::chain(&cpu.resolve(&rung).expect_err("no address stored yet"));
        assert!(e.contains("@D10"), "{e}");
        cpu.adrset(&d(300), &d(20));
        cpu.adrset(&d(100), &d(10));
        let operands = cpu.resolve(&rung).expect("resolved");
        assert_eq!(operands["s"], Operand::Device(d(100)));
        assert_eq!(operands["d"], Operand::Device(d(200)));
        assert_eq!(cpu.word(&d(11)), Some(ADDRESS_TAG));
        assert_ne!(
            cpu.word(&d(10)),
            cpu.word(&d(20)),
            "two devices, two addresses"
        );
    }
}
