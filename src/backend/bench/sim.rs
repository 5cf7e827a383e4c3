//! A simulated CPU's program: the generated test program's behaviour run with a reference
//! model on a CPU's memory, for a link's simulated CPU (a server on 127.0.0.1 speaking the
//! link's protocol) to serve, so that a bench backend can be tested end to end without hardware
//! and be made to fail in each way a real port fails.
//!
//! A scan thread takes the memory lock once per scan, so requests interleave between scans as
//! they do with END processing, and runs the program as generated: the signature and scan
//! counter every scan; on a new trigger, an error reset (the reset flag's rising edge clears the
//! error flag and registers at the end of the scan), then one scan with the selected rung
//! enabled, the error flag and registers captured in that scan and the error register again one
//! scan later, then the acknowledgement. Every rung is evaluated every scan with its own enable,
//! and a pulse form (`...P`) executes only on its enable's rising edge, which is what makes the
//! same pulse rung fire again on the next case.
//!
//! Everything a server received is audited: the requests, and every written word that lies
//! outside the manifest's `writes` and the mailbox's PC words (a stray write the tests fail on).

use std::collections::{BTreeMap, BTreeSet};
use std::io::Read;
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

use super::addressing::Addressing;
use super::error::{refused, LiveError};
use super::fence::{parse_ranges, WordRange};
use super::mailbox::{self, off, state};
use super::manifest::{parse_operand, Manifest};
use crate::backend::{Backend, Request as ModelRequest, Response as ModelResponse};
use crate::device::Device;
use crate::memory::{Fill, Image, Unit, Value};
use crate::model::profile::Profile;
use crate::model::{ErrorSignal, Operand};

/// What a fault rule does to the request it matches.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FaultAction {
    /// Close the connection without processing the request or answering.
    Drop,
    /// Process the request, answer after this long.
    Delay(Duration),
    /// Answer with this error code (the protocol's end code or exception) without processing
    /// the request.
    EndCode(u16),
    /// Answer with bytes that are not a response of the protocol, without processing the request.
    Garbage,
    /// Process the request, answer with another serial number or transaction id than the
    /// request's.
    WrongSerial,
    /// Process the request, then go to STOP and stop scanning.
    Stop,
}

/// A fault on the `nth` request (from 1) of a command (the protocol's command or function
/// code), optionally only requests whose first device is `head`; it fires once.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FaultRule {
    pub command: u16,
    pub head: Option<Device>,
    pub nth: usize,
    pub action: FaultAction,
}

impl FaultRule {
    /// Reads `COMMAND:NTH:ACTION` as `hil sim --fault` takes it: `CMD:3:drop` closes the
    /// connection on the third request of command CMD; actions `drop`, `delay=MS`, `end=C051`
    /// (an error code in hexadecimal), `garbage`, `serial` (another serial or transaction id),
    /// `stop` (go to STOP). `commands` are the ones the server answers (in hexadecimal in
    /// messages).
    pub fn parse(text: &str, commands: &[u16]) -> Result<FaultRule, LiveError> {
        // Codes as protocols write them: two hexadecimal digits below 100H, four from there.
        let known: Vec<String> = (commands.iter())
            .map(|c| match c {
                0..=0xFF => format!("{c:02X}"),
                _ => format!("{c:04X}"),
            })
            .collect();
        let usage = format!(
            "a fault is COMMAND:NTH:ACTION, COMMAND one of {} (hexadecimal), e.g. {}:1:drop; \
             actions: drop, delay=MS, end=CODE, garbage, serial, stop",
            known.join(", "),
            known.last().map_or("10", String::as_str)
        );
        let mut parts = text.split(':');
        let (Some(command), Some(nth), Some(action), None) =
            (parts.next(), parts.next(), parts.next(), parts.next())
        else {
            return Err(refused!("`{text}`: {usage}"));
        };
        let command = u16::from_str_radix(command, 16)
            .ok()
            .filter(|c| commands.contains(c))
            .ok_or_else(|| refused!("`{text}`: the command is one of {}", known.join(", ")))?;
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

pub(crate) struct Cpu {
    pub(crate) words: BTreeMap<String, Vec<u16>>,
    /// `words` as the models read them, each device named as the profile numbers it (`W1A`):
    /// built at the first execution, then kept up by [`Cpu::set_word`]. Building it for each
    /// execution cost most of a simulated run.
    image: Option<Arc<BTreeMap<Device, Value>>>,
    bits: BTreeMap<Device, bool>,
    pub(crate) running: bool,
    prev: Vec<bool>,
    prev_reset: bool,
    pub(crate) audit: Audit,
    faults: Vec<(FaultRule, usize)>,
    /// The devices ADRSET has stored an address of: this CPU's address of a device is its
    /// place here, with [`ADDRESS_TAG`] in the pointer's second word.
    addressed: Vec<Device>,
    /// Triggers written so far, and (with `premature_ack`) the last one kept from the program.
    triggers: usize,
    withheld: Option<u16>,
    /// Bits nothing turns off: a CPU whose program cannot reset its error flag.
    held: BTreeSet<Device>,
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

/// A simulated CPU serving on 127.0.0.1; dropping it stops it. `L` is its link's server.
pub struct Running<L> {
    address: SocketAddr,
    program: Arc<Program<L>>,
    threads: Vec<JoinHandle<()>>,
}

impl<L: Send + Sync + 'static> Running<L> {
    /// Starts `program`'s scan thread and a server whose connections `serve` answers.
    pub(crate) fn serve(
        program: Arc<Program<L>>,
        serve: fn(&Program<L>, TcpStream),
    ) -> Result<Running<L>, LiveError> {
        let (address, threads) = program.start(serve)?;
        Ok(Running {
            address,
            program,
            threads,
        })
    }

    /// `127.0.0.1:PORT`.
    pub fn address(&self) -> SocketAddr {
        self.address
    }

    pub fn audit(&self) -> Audit {
        self.program.lock().audit.clone()
    }

    /// Puts the CPU in RUN or STOP.
    pub fn set_running(&self, run: bool) {
        let mut cpu = self.program.lock();
        self.program.set_running(&mut cpu, run);
    }

    /// Adds a fault rule while running.
    pub fn add_fault(&self, rule: FaultRule) {
        self.program.lock().add_fault(rule);
    }

    /// A word of device memory (0 for one the CPU does not have).
    pub fn read(&self, device: &Device) -> u16 {
        self.program.lock().word(device).unwrap_or(0)
    }

    /// Keeps the error flag on whatever the program does, as a CPU on which the program cannot
    /// reset it would.
    pub fn hold_error_flag(&self, held: bool) {
        let flag = self.program.settings.manifest.error.flag.clone();
        self.program.lock().hold(&flag, held);
    }
}

impl<L> Drop for Running<L> {
    fn drop(&mut self) {
        self.program.stop.store(true, Ordering::SeqCst);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
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

    /// Starts the scan thread, and a server on 127.0.0.1 (the settings' port) whose every
    /// connection `serve` answers in a thread of its own. The CPU has scanned once before the
    /// port opens, as a CPU in RUN has before anyone can connect to it.
    pub(crate) fn start(
        self: &Arc<Self>,
        serve: fn(&Program<L>, TcpStream),
    ) -> Result<(SocketAddr, Vec<JoinHandle<()>>), LiveError>
    where
        L: Send + Sync + 'static,
    {
        let port = self.settings.port;
        let listener = TcpListener::bind(("127.0.0.1", port))
            .map_err(|e| LiveError::within(format!("cannot listen on 127.0.0.1:{port}"), e))?;
        let address = listener
            .local_addr()
            .map_err(|e| LiveError::within("no local address", e))?;
        listener
            .set_nonblocking(true)
            .map_err(|e| LiveError::within("cannot poll the listener", e))?;
        {
            let mut cpu = self.lock();
            scan(self, &mut cpu);
        }
        let s = self.clone();
        let scanning = std::thread::spawn(move || {
            while !s.stop.load(Ordering::SeqCst) {
                {
                    let mut cpu = s.lock();
                    scan(&s, &mut cpu);
                }
                std::thread::sleep(s.settings.scan);
            }
        });
        let s = self.clone();
        let accepting = std::thread::spawn(move || {
            let mut connections: Vec<JoinHandle<()>> = Vec::new();
            while !s.stop.load(Ordering::SeqCst) {
                match listener.accept() {
                    Ok((stream, _)) => {
                        s.lock().audit.connections += 1;
                        let s = s.clone();
                        connections.push(std::thread::spawn(move || {
                            let _ = stream.set_read_timeout(Some(Duration::from_millis(20)));
                            let _ = stream.set_nodelay(true);
                            serve(&s, stream)
                        }));
                    }
                    Err(_) => std::thread::sleep(Duration::from_millis(2)),
                }
                connections.retain(|c| !c.is_finished());
            }
            for c in connections {
                let _ = c.join();
            }
        });
        Ok((address, vec![scanning, accepting]))
    }

    /// Fills `buf` from `at` on, polling the stop flag; `None` when the connection ends.
    pub(crate) fn fill(&self, stream: &mut TcpStream, buf: &mut [u8], mut at: usize) -> Option<()> {
        while at < buf.len() {
            if self.stop.load(Ordering::SeqCst) {
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

    pub(crate) fn word(&self, d: &Device) -> Option<u16> {
        self.words
            .get(d.code())
            .and_then(|w| w.get(d.index as usize))
            .copied()
    }

    pub(crate) fn set_word(&mut self, d: &Device, value: u16) {
        if let Some(w) = self
            .words
            .get_mut(d.code())
            .and_then(|w| w.get_mut(d.index as usize))
        {
            *w = value;
            if let Some(image) = &mut self.image {
                // In place: no execution holds the image between scans.
                let image = Arc::make_mut(image);
                // The image names the word as the profile numbers its code.
                for named in [
                    Device::new(d.code(), d.index),
                    Device::hexadecimal(d.code(), d.index),
                ] {
                    if let Some(v) = image.get_mut(&named) {
                        *v = Value::from(value);
                        break;
                    }
                }
            }
        }
    }

    /// The image of every word device (see [`Cpu::image`]'s field).
    fn image(
        &mut self,
        devices: &crate::model::profile::DeviceTable,
    ) -> Arc<BTreeMap<Device, Value>> {
        let words = &self.words;
        self.image
            .get_or_insert_with(|| {
                Arc::new(
                    words
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
                        .collect(),
                )
            })
            .clone()
    }

    pub(crate) fn bit(&self, name: &str) -> bool {
        name.parse::<Device>()
            .ok()
            .and_then(|d| self.bits.get(&d).copied())
            .unwrap_or(false)
    }

    pub(crate) fn set_bit(&mut self, name: &str, on: bool) {
        if let Ok(d) = name.parse::<Device>() {
            let on = on || self.held.contains(&d);
            self.bits.insert(d, on);
        }
    }

    /// Turns a bit on for good, or lets it go again.
    pub(crate) fn hold(&mut self, name: &str, held: bool) {
        if let Ok(d) = name.parse::<Device>() {
            match held {
                true => self.held.insert(d),
                false => self.held.remove(&d),
            };
        }
        if held {
            self.set_bit(name, true);
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

    /// Adds a fault rule while running.
    pub(crate) fn add_fault(&mut self, rule: FaultRule) {
        self.faults.push((rule, 0));
    }

    /// The fault a request of `command` whose first device is `head` meets, if one fires now.
    pub(crate) fn take_fault(
        &mut self,
        command: u16,
        head: Option<&Device>,
    ) -> Option<FaultAction> {
        for (rule, seen) in self.faults.iter_mut() {
            if rule.command != command {
                continue;
            }
            if let Some(want) = &rule.head {
                if head != Some(want) {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn cpu() -> Cpu {
        Cpu {
            words: BTreeMap::from([("D".to_string(), vec![0; 400])]),
            image: None,
            bits: BTreeMap::new(),
            running: true,
            prev: Vec::new(),
            prev_reset: false,
            audit: Audit::default(),
            faults: Vec::new(),
            addressed: Vec::new(),
            triggers: 0,
            withheld: None,
            held: BTreeSet::new(),
        }
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
