//! A MELSEC CPU over SLMP (3E or 4E frames, binary or ASCII code, TCP): one link of the bench
//! layer ([`crate::backend::bench`]), which owns the mailbox, the fence and the interlocks.
//!
//! The link names the CPU by its type name (0101), reads its state from SD203, and reads and
//! writes words with 0401, 0403 and 1401. No other command can be encoded: no remote
//! RUN/STOP/RESET. `sim` is a simulated CPU speaking the same frames.

pub(crate) mod ascii;
pub(crate) mod client;
pub(crate) mod frame;
pub(crate) mod limits;
pub(crate) mod probe;
pub(crate) mod sim;

use std::path::Path;
use std::time::Duration;

use client::{Client, ClientSettings, Code};
use frame::{DeviceForm, FrameKind};
use limits::Family;

use super::bench::error::{refused, LiveError};
use super::bench::fence::{FencedWrite, Kind, WordRange};
use super::bench::manifest::Manifest;
use super::bench::settings::Spec;
use super::bench::{Addressing, BenchSettings, Identity, Link, LinkError, LinkSettings, RunState};
use crate::device::Device;

/// How SLMP reaches a MELSEC CPU's devices.
pub struct Slmp;

/// The one SLMP addressing.
pub static ADDRESSING: Slmp = Slmp;

/// The special register that holds the CPU's operating status.
const STATUS: (&str, u32) = ("SD", 203);

impl Addressing for Slmp {
    fn hex_numbered(&self, code: &str) -> bool {
        frame::hex_numbered(code)
    }

    /// Data, file and link registers (D, R, ZR, W) are memory a test program may own; special
    /// and link special registers (SD, SW) are the CPU's and the network's own.
    fn kind(&self, device: &Device) -> Kind {
        match device.code() {
            "D" | "R" | "ZR" | "W" => Kind::Data,
            "SD" | "SW" => Kind::Special,
            _ => Kind::Bit,
        }
    }

    /// The client has no SLMP device code for timers, counters and index registers; and a
    /// profile that numbers a code otherwise than MELSEC does would put other words in the
    /// program, the manifest and a sandbox (`W1A` is hexadecimal, `D100` decimal).
    fn unaddressable(&self, device: &Device) -> Option<String> {
        let code = device.code();
        if frame::device_code(code).is_none() {
            return Some(format!(
                "{code} has no SLMP device code in this client (it addresses {})",
                frame::DEVICE_LETTERS.join(", ")
            ));
        }
        (device.is_hexadecimal() != frame::hex_numbered(code)).then(|| {
            let (profile, melsec) = match device.is_hexadecimal() {
                true => ("hexadecimal", "decimal"),
                false => ("decimal", "hexadecimal"),
            };
            format!("the profile numbers {code} in {profile}, and MELSEC in {melsec}")
        })
    }

    fn sandbox_devices(&self) -> &'static str {
        "D, R, ZR, W, and SD or SW when named"
    }

    fn data_devices(&self) -> &'static str {
        "data or link register (D, R, ZR, W)"
    }
}

/// Whether an SD203 value says RUN: its low four bits hold the operating status, 0 for RUN (the
/// Q-series special register list says so for SD203; the iQ-R list codes the per-CPU status
/// SD230 the same way; for iQ-R and FX5 SD203 itself this is inferred).
pub(crate) fn is_run(sd203: u16) -> bool {
    sd203 & 0x000F == 0
}

/// What an SD203 value says, for messages.
pub(crate) fn status_text(sd203: u16) -> String {
    let name = match sd203 & 0x000F {
        0 => "RUN",
        1 => "STEP-RUN",
        2 => "STOP",
        3 => "PAUSE",
        _ => "not RUN",
    };
    format!("{name} (SD203={sd203:04X}H)")
}

fn run_state(sd203: u16) -> RunState {
    RunState {
        running: is_run(sd203),
        text: status_text(sd203),
    }
}

/// The SLMP client as a bench's link.
struct SlmpLink(Client);

impl Link for SlmpLink {
    fn identify(&mut self) -> Result<Identity, LinkError> {
        let t = self.0.type_name()?;
        Ok(Identity {
            shown: t.to_string(),
            name: t.name,
        })
    }

    fn run_state(&mut self) -> Result<RunState, LinkError> {
        let words = self.0.random_read(&[Device::new(STATUS.0, STATUS.1)])?;
        Ok(run_state(words.first().copied().unwrap_or(u16::MAX)))
    }

    fn read(&mut self, head: &Device, count: u32) -> Result<Vec<u16>, LinkError> {
        Ok(self.0.read_words(head, count)?)
    }

    /// One random read (0403) of the devices and SD203.
    fn poll(&mut self, devices: &[Device]) -> Result<(Vec<u16>, RunState), LinkError> {
        let mut asked = devices.to_vec();
        asked.push(Device::new(STATUS.0, STATUS.1));
        let mut words = self.0.random_read(&asked)?;
        let sd203 = words.pop().unwrap_or(u16::MAX);
        Ok((words, run_state(sd203)))
    }

    fn write(&mut self, write: &FencedWrite) -> Result<(), LinkError> {
        Ok(self.0.write(write)?)
    }

    fn batch_words(&self) -> usize {
        self.0.settings().limits.batch_words
    }

    fn connections(&self) -> u64 {
        self.0.connections()
    }

    fn requests(&self) -> u64 {
        self.0.requests()
    }

    fn is_connected(&self) -> bool {
        self.0.is_connected()
    }

    fn disconnect(&mut self) {
        self.0.disconnect();
    }
}

impl LinkSettings for ClientSettings {
    fn kind(&self) -> crate::model::profile::LinkKind {
        crate::model::profile::LinkKind::Slmp
    }
    fn open(&self) -> Box<dyn Link> {
        Box::new(SlmpLink(Client::new(self.clone())))
    }
    fn describe(&self) -> String {
        ClientSettings::describe(self)
    }
    fn address(&self) -> &str {
        &self.address
    }
    fn addressing(&self) -> &dyn Addressing {
        &ADDRESSING
    }
    fn clone_box(&self) -> Box<dyn LinkSettings> {
        Box::new(self.clone())
    }
}

/// A bench over SLMP, while its link settings may still change.
pub(crate) type SlmpBench = BenchSettings<ClientSettings>;

/// The keys the SLMP link reads besides the bench's own.
const LINK_KEYS: [&str; 4] = ["frame", "code", "form", "monitor"];

impl BenchSettings<ClientSettings> {
    /// Settings with the defaults of the manifest's family: FX5 CPUs get 3E frames, the
    /// Q-compatible device form (an FX5U refuses the long form) and the monitoring timer 0;
    /// others 4E, the long form and 2 s. The limits follow the code and the form
    /// ([`SlmpBench::fit_limits`]).
    pub fn new(
        name: impl Into<String>,
        address: impl Into<String>,
        manifest: Manifest,
        variant: impl Into<String>,
        confirm: impl Into<String>,
        sandbox: Vec<WordRange>,
    ) -> Self {
        let mut client = ClientSettings::new(address);
        let family = Family::of_profile(&manifest.profile);
        if family == Family::Fx5 {
            client.frame = FrameKind::E3;
            client.form = DeviceForm::Short;
        }
        client.timer = limits::monitoring_timer(family);
        let mut settings =
            BenchSettings::with_link(name, client, manifest, variant, confirm, sandbox);
        settings.fit_limits();
        settings
    }

    /// The limits of the port as now configured: to call after changing the code or the form.
    pub fn fit_limits(&mut self) {
        let family = Family::of_profile(&self.manifest.profile);
        self.link.limits = limits::limits(family, self.link.code, self.link.form);
    }

    /// Reads `slmp:NAME=HOST:PORT?key=value&...`; `None` when `text` is not of this form.
    /// Keys: `manifest` (path), `confirm` (the CPU type name), `sandbox` (ranges such as
    /// `D0-D4359,D7900-D7999`, where `manifest` stands for the data and link registers of the
    /// manifest's `writes`: `manifest,SD100-SD167` adds special registers), and optionally
    /// `variant`, `frame` (3e, 4e), `code` (binary, ascii), `form` (short, long), `timeout`
    /// (case seconds), `monitor` (monitoring timer, units of 250 ms), `max_faults`, `poll_ms`.
    pub fn parse(text: &str, base: &Path) -> Result<Option<SlmpBench>, LiveError> {
        let Some(spec) = Spec::split(text, "slmp", &LINK_KEYS)? else {
            return Ok(None);
        };
        let (manifest, variant, confirm, sandbox, _) = spec.parts(base, |_| Ok(Slmp))?;
        let mut s = SlmpBench::new(spec.name, spec.address, manifest, variant, confirm, sandbox);
        if let Some(f) = spec.get("frame") {
            s.link.frame = match f {
                "3e" | "3E" => FrameKind::E3,
                "4e" | "4E" => FrameKind::E4,
                _ => return Err(refused!("`frame={f}`: give 3e or 4e")),
            };
        }
        if let Some(c) = spec.get("code") {
            s.link.code = match c {
                "binary" => Code::Binary,
                "ascii" => Code::Ascii,
                _ => return Err(refused!("`code={c}`: give binary or ascii")),
            };
        }
        if let Some(f) = spec.get("form") {
            s.link.form = match f {
                "short" => DeviceForm::Short,
                "long" => DeviceForm::Long,
                _ => {
                    return Err(refused!(
                        "`form={f}`: give short (subcommand 0000) or long (0002)"
                    ))
                }
            };
        }
        spec.timings(&mut s)?;
        s.fit_limits();
        if let Some(v) = spec.get("monitor") {
            let units = v.parse::<u16>().ok().filter(|n| *n <= 240).ok_or_else(|| {
                refused!("`monitor={v}`: give 0 (the FX5 value) to 240 (units of 250 ms)")
            })?;
            s.link.timer = units;
            // With 0 the CPU does not time itself, and the client's default reply time holds.
            if units > 0 {
                s.link.reply_timeout =
                    Duration::from_millis(250 * u64::from(units)) + Duration::from_millis(500);
            }
        }
        Ok(Some(s))
    }
}

/// The fault kind of a client error.
#[cfg(test)]
pub(crate) fn fault_of(e: &client::ClientError) -> super::Fault {
    LinkError::from(e.clone()).fault()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::bench::fence::{parse_ranges, sandbox_refuses};

    /// A device is addressed when the client has its code and the profile numbers it as MELSEC
    /// does, since the program, the manifest and the frames write its number MELSEC's way.
    #[test]
    fn a_device_is_addressed_when_its_code_and_numbering_agree() {
        let unaddressable = |d: &Device| ADDRESSING.unaddressable(d);
        assert_eq!(unaddressable(&Device::new("D", 100)), None);
        assert_eq!(unaddressable(&Device::hexadecimal("W", 0x1A)), None);
        assert_eq!(unaddressable(&Device::hexadecimal("SW", 0x0F)), None);
        let decimal_w = unaddressable(&Device::new("W", 26)).expect("refused");
        assert!(decimal_w.contains("MELSEC in hexadecimal"), "{decimal_w}");
        let hex_d = unaddressable(&Device::hexadecimal("D", 26)).expect("refused");
        assert!(hex_d.contains("MELSEC in decimal"), "{hex_d}");
        let timer = unaddressable(&Device::new("T", 5)).expect("refused");
        assert!(timer.contains("no SLMP device code"), "{timer}");
    }

    /// Link registers read and print in hexadecimal, as MELSEC numbers them; data registers
    /// in decimal.
    #[test]
    fn a_range_is_numbered_as_melsec_numbers_its_device() {
        let r: Vec<WordRange> = parse_ranges("W0-W1FF,SW10,D10-D20", &ADDRESSING).expect("ranges");
        let shown: Vec<String> = r.iter().map(ToString::to_string).collect();
        assert_eq!(shown, ["W0-W1FF", "SW10", "D10-D20"]);
        assert_eq!((r[0].first, r[0].last, r[1].first), (0, 0x1FF, 16));
        assert!(parse_ranges("D1A", &ADDRESSING).is_err(), "D is decimal");
    }

    #[test]
    fn a_sandbox_holds_word_devices_only() {
        for bits in ["Y0-Y17", "M0-M15", "SM0", "B0-BF", "X0"] {
            let r = WordRange::parse(bits, &ADDRESSING).expect("range");
            assert!(sandbox_refuses(&r, &ADDRESSING).is_some(), "{bits}");
        }
        for words in ["D0-D10", "R5", "W0-W1F", "SD100-SD167", "SW0-SW1"] {
            let r = WordRange::parse(words, &ADDRESSING).expect("range");
            assert_eq!(sandbox_refuses(&r, &ADDRESSING), None, "{words}");
        }
        assert_eq!(ADDRESSING.kind(&Device::new("SD", 0)), Kind::Special);
        assert_eq!(ADDRESSING.kind(&Device::hexadecimal("W", 0)), Kind::Data);
    }
}
