//! An IDEC MicroSmart CPU over Modbus TCP: one link of the bench layer
//! ([`crate::backend::bench`]), which owns the mailbox, the fence and the interlocks.
//!
//! The link reads and writes data registers as holding registers (function codes 03, 16, and 06
//! for a word written alone), reads whether the CPU runs from the start control relay M8000 as
//! a coil (01), and names the CPU by its type code in a special data register (03). No other
//! function can be encoded: no coil is ever written, so no link can start or stop the CPU.
//!
//! The address map is the FC6A's Modbus TCP server's (fc6a-comm p.6-9, "Calculating Modbus
//! Addresses"; docs/live-cpu.md#idec-over-modbus-tcp): D0000-D7999 are holding
//! registers 400001 on, D8000-D8499 408001 on and D10000-D55999 410001 on, so a data register's
//! wire address is its number; M8000-M8317 are coils 009001 on, the last digit octal. An FC4A
//! reaches Modbus TCP through its web server module with the same map (unconfirmed).

pub(crate) mod client;
pub(crate) mod frame;
pub(crate) mod sim;

use std::path::Path;
use std::time::Duration;

use client::{ModbusClient, ModbusError, ModbusSettings};

use super::bench::error::{refused, LiveError};
use super::bench::fence::{FencedWrite, Kind};
use super::bench::settings::Spec;
use super::bench::{
    Addressing, BenchSettings, Failure, Identity, Link, LinkError, LinkSettings, RunState,
};
use crate::device::Device;

/// How Modbus TCP reaches an IDEC MicroSmart's devices.
pub struct Idec;

/// The one [`Idec`] addressing.
pub static ADDRESSING: Idec = Idec;

/// The data registers the map reaches, with their kind: the holding registers of the FC6A's
/// map, whose wire address is the register's number.
const DATA_REGISTERS: [(u32, u32, Kind); 3] = [
    (0, 7999, Kind::Data),
    (8000, 8499, Kind::Special),
    (10000, 55999, Kind::Data),
];

/// The start control special internal relay: on while the CPU runs.
const START_CONTROL: u32 = 8000;

/// The special data register that holds the CPU's type code, what `confirm` is compared with.
const TYPE_CODE: u32 = 8002;

/// The wire address of a data register the map reaches.
fn register(device: &Device) -> Option<u16> {
    (device.code() == "D"
        && DATA_REGISTERS
            .iter()
            .any(|(first, last, _)| (*first..=*last).contains(&device.index)))
    .then_some(device.index as u16)
}

/// The wire address of a special internal relay M8000-M8317: coils 009001 on, eight to each
/// ten of the relay's number (its last digit is octal).
fn coil(relay: u32) -> Option<u16> {
    let (tens, digit) = (relay / 10, relay % 10);
    (relay <= 8317 && tens >= 800 && digit < 8).then(|| ((tens - 800) * 8 + digit + 9000) as u16)
}

impl Addressing for Idec {
    fn hex_numbered(&self, _: &str) -> bool {
        false
    }

    fn kind(&self, device: &Device) -> Kind {
        let kind = DATA_REGISTERS
            .iter()
            .find(|(first, last, _)| (*first..=*last).contains(&device.index))
            .map(|(_, _, k)| *k);
        match (device.code(), kind) {
            ("D", Some(k)) => k,
            ("D", None) => Kind::Special,
            _ => Kind::Bit,
        }
    }

    fn unaddressable(&self, device: &Device) -> Option<String> {
        register(device).is_none().then(|| {
            format!(
                "{device} is not a holding register of the Modbus map (D0-D7999, D8000-D8499, \
                 D10000-D55999)"
            )
        })
    }

    fn sandbox_devices(&self) -> &'static str {
        "D0-D7999, D10000-D55999, and D8000-D8499 when named"
    }

    fn data_devices(&self) -> &'static str {
        "data register (D0-D7999, D10000-D55999)"
    }
}

impl From<ModbusError> for LinkError {
    fn from(e: ModbusError) -> Self {
        let failure = match e {
            ModbusError::Connect { .. } => Failure::Unreachable,
            ModbusError::Timeout { .. } => Failure::Timeout,
            ModbusError::Closed { .. } => Failure::Lost,
            ModbusError::Frame { .. }
            | ModbusError::Exception { .. }
            | ModbusError::Request { .. } => Failure::Protocol,
        };
        LinkError::new(failure, e)
    }
}

impl From<ModbusError> for LiveError {
    fn from(e: ModbusError) -> Self {
        LiveError::Link(e.into())
    }
}

/// The Modbus client as a bench's link.
struct IdecLink(ModbusClient);

impl IdecLink {
    fn address(device: &Device) -> Result<u16, LinkError> {
        register(device).ok_or_else(|| {
            LinkError::new(
                Failure::Protocol,
                ModbusError::Request {
                    what: format!("an access to {device}"),
                    detail: ADDRESSING.unaddressable(device).unwrap_or_default(),
                },
            )
        })
    }
}

impl Link for IdecLink {
    /// The type code in D8002, as `confirm` gives it: a decimal number.
    fn identify(&mut self) -> Result<Identity, LinkError> {
        let code = self.0.read_holding(TYPE_CODE as u16, 1)?;
        let code = code.first().copied().unwrap_or(0);
        Ok(Identity {
            name: code.to_string(),
            shown: format!("type code {code} (D{TYPE_CODE}={code:04X}H)"),
        })
    }

    fn run_state(&mut self) -> Result<RunState, LinkError> {
        let at = coil(START_CONTROL).unwrap_or(9000);
        let on = self.0.read_coils(at, 1)?.first().copied().unwrap_or(false);
        Ok(RunState {
            running: on,
            text: match on {
                true => format!("RUN (M{START_CONTROL} on)"),
                false => format!("STOP (M{START_CONTROL} off)"),
            },
        })
    }

    fn read(&mut self, head: &Device, count: u32) -> Result<Vec<u16>, LinkError> {
        let at = Self::address(head)?;
        Self::address(&head.with_index(head.index + count.max(1) - 1))?;
        Ok(self.0.read_holding(at, count as usize)?)
    }

    fn write(&mut self, write: &FencedWrite) -> Result<(), LinkError> {
        let at = Self::address(write.head())?;
        Ok(self.0.write_registers(at, write.words())?)
    }

    fn batch_words(&self) -> usize {
        self.0.settings().limits.write_registers
    }

    fn connections(&self) -> u64 {
        self.0.connections
    }

    fn requests(&self) -> u64 {
        self.0.requests
    }

    fn is_connected(&self) -> bool {
        self.0.is_connected()
    }

    fn disconnect(&mut self) {
        self.0.disconnect();
    }
}

impl LinkSettings for ModbusSettings {
    fn open(&self) -> Box<dyn Link> {
        Box::new(IdecLink(ModbusClient::new(self.clone())))
    }
    fn describe(&self) -> String {
        ModbusSettings::describe(self)
    }
    fn address(&self) -> &str {
        &self.address
    }
    fn addressing(&self) -> &'static dyn Addressing {
        &ADDRESSING
    }
    fn clone_box(&self) -> Box<dyn LinkSettings> {
        Box::new(self.clone())
    }
}

/// A bench over Modbus TCP, while its link settings may still change.
pub type ModbusBench = BenchSettings<ModbusSettings>;

/// The keys the Modbus link reads besides the bench's own.
const LINK_KEYS: [&str; 2] = ["unit", "reply_ms"];

impl BenchSettings<ModbusSettings> {
    /// Settings with the link's defaults (unit 1, replies within 1 s).
    pub fn modbus(
        name: impl Into<String>,
        address: impl Into<String>,
        manifest: super::bench::manifest::Manifest,
        variant: impl Into<String>,
        confirm: impl Into<String>,
        sandbox: Vec<super::bench::fence::WordRange>,
    ) -> Self {
        BenchSettings::with_link(
            name,
            ModbusSettings::new(address),
            manifest,
            variant,
            confirm,
            sandbox,
        )
    }

    /// Reads `modbus:NAME=HOST:PORT?key=value&...`; `None` when `text` is not of this form.
    /// Keys: `manifest`, `confirm` (the CPU's type code in D8002), `sandbox` as for every
    /// bench, and optionally `variant`, `unit` (the unit id, 0-255), `reply_ms` (how long one
    /// reply may take), `timeout`, `max_faults`, `poll_ms`.
    pub fn parse(text: &str, base: &Path) -> Result<Option<ModbusBench>, LiveError> {
        let Some(spec) = Spec::split(text, "modbus", &LINK_KEYS)? else {
            return Ok(None);
        };
        let (manifest, variant, confirm, sandbox) = spec.parts(base, &ADDRESSING)?;
        let mut s =
            ModbusBench::modbus(spec.name, spec.address, manifest, variant, confirm, sandbox);
        if let Some(v) = spec.get("unit") {
            s.link.unit = v
                .parse::<u8>()
                .map_err(|_| refused!("`unit={v}`: give a unit id from 0 to 255"))?;
        }
        if let Some(ms) = spec.number("reply_ms")? {
            s.link.reply_timeout = Duration::from_secs_f64(ms / 1000.0);
        }
        spec.timings(&mut s)?;
        Ok(Some(s))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The FC6A's map: a data register's wire address is its number in the three ranges, and
    /// M8000-M8317 are coils 9001 on (one-based), eight to each ten.
    #[test]
    fn the_map_is_the_fc6a_manuals() {
        for (d, wire) in [(0, Some(0)), (7999, Some(7999)), (8000, Some(8000))] {
            assert_eq!(register(&Device::new("D", d)), wire, "D{d}");
        }
        for d in [8500, 9999, 56000] {
            assert_eq!(register(&Device::new("D", d)), None, "D{d}");
        }
        assert_eq!(register(&Device::new("D", 10000)), Some(10000));
        assert_eq!(register(&Device::new("M", 100)), None);
        assert_eq!(coil(8000), Some(9000));
        assert_eq!(coil(8004), Some(9004), "wire 0x232C, coil 009005");
        assert_eq!(coil(8010), Some(9008));
        assert_eq!(coil(8317), Some(9255));
        assert_eq!(coil(8008), None, "the last digit is octal");
        assert_eq!(coil(7999), None);
        assert_eq!(ADDRESSING.kind(&Device::new("D", 8006)), Kind::Special);
        assert_eq!(ADDRESSING.kind(&Device::new("D", 100)), Kind::Data);
        assert_eq!(ADDRESSING.kind(&Device::new("M", 100)), Kind::Bit);
    }
}
