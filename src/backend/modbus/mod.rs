//! A CPU over Modbus TCP (IDEC MicroSmart): one link of the bench layer
//! ([`crate::backend::bench`]), which owns the mailbox, the fence and the interlocks.
//!
//! Where the CPU's server puts its devices is data: the profile's `bench.modbus` map (for IDEC,
//! the FC6A's, fc6a-comm p.6-9; docs/live-cpu.md#idec-over-modbus-tcp). The link reads and
//! writes data registers as holding registers (function codes 03, 16, and 06 for a word written
//! alone), reads whether the CPU runs from the map's running relay as a coil (01), and names the
//! CPU by the value of the map's identity register (03). No other function can be encoded: no
//! coil is ever written, so no link can start or stop the CPU.

pub(crate) mod client;
pub(crate) mod frame;
pub(crate) mod sim;

use std::path::Path;
use std::time::Duration;

use std::sync::Arc;

use super::bench::tcp::TransportError;
use client::{ModbusClient, ModbusError, ModbusSettings};

use super::bench::error::{refused, LiveError};
use super::bench::fence::{FencedWrite, Kind, WordRange};
use super::bench::manifest::Manifest;
use super::bench::settings::Spec;
use super::bench::{
    Addressing, BenchSettings, Failure, Identity, Link, LinkError, LinkSettings, RunState,
};
use crate::device::Device;
use crate::model::profile::{DeviceTable, ModbusRange, Profile, Profiles};

/// How Modbus TCP reaches a CPU's devices: the map of the profile's `bench.modbus`, with the
/// profile's numbering.
#[derive(Debug, Clone)]
pub struct Map {
    registers: Vec<ModbusRange>,
    coils: Vec<ModbusRange>,
    identity: Device,
    running: Device,
    /// The profile's device table: how each code is numbered.
    devices: DeviceTable,
}

impl Map {
    /// The map of a profile whose bench link is Modbus TCP.
    pub fn of(profile: &Profile) -> Result<Map, LiveError> {
        let map = (profile.bench.as_ref())
            .and_then(|b| b.modbus.as_ref())
            .ok_or_else(|| {
                refused!(
                    "{} has no Modbus map (`bench.modbus` in its profile): no Modbus TCP link \
                     reaches its CPUs",
                    profile.id
                )
            })?;
        let device = |name: &str| {
            profile
                .devices
                .parse(name)
                .map_err(|e| LiveError::within(format!("`bench.modbus` of {}", profile.id), e))
        };
        Ok(Map {
            registers: map.registers.clone(),
            coils: map.coils.clone(),
            identity: device(&map.identity)?,
            running: device(&map.running)?,
            devices: profile.devices.clone(),
        })
    }

    /// The wire address of `device` in `ranges`, and its range.
    fn wire<'a>(
        &self,
        ranges: &'a [ModbusRange],
        device: &Device,
    ) -> Option<(u16, &'a ModbusRange)> {
        let numbering = self.devices.get(device.code())?.numbering;
        ranges
            .iter()
            .filter(|r| r.device == device.code() && (r.first..=r.last).contains(&device.index))
            .find_map(|r| {
                let offset = numbering.point(device.index)? - numbering.point(r.first)?;
                let wire = u64::from(r.address) + offset;
                u16::try_from(wire).ok().map(|w| (w, r))
            })
    }

    /// The holding register of a word device.
    pub(crate) fn register(&self, device: &Device) -> Option<u16> {
        self.wire(&self.registers, device).map(|(w, _)| w)
    }

    /// The coil of a bit device.
    pub(crate) fn coil(&self, device: &Device) -> Option<u16> {
        self.wire(&self.coils, device).map(|(w, _)| w)
    }

    /// The bit device at a coil's wire address.
    pub(crate) fn relay(&self, wire: u16) -> Option<Device> {
        self.device(&self.coils, wire)
    }

    /// The word device at a holding register's wire address.
    pub(crate) fn device_at(&self, wire: u16) -> Option<Device> {
        self.device(&self.registers, wire)
    }

    /// The device of `ranges` at a wire address.
    fn device(&self, ranges: &[ModbusRange], wire: u16) -> Option<Device> {
        ranges.iter().find_map(|r| {
            let numbering = self.devices.get(&r.device)?.numbering;
            let point = numbering.point(r.first)? + u64::from(wire.checked_sub(r.address)?);
            if point > numbering.point(r.last)? {
                return None;
            }
            let number = numbering.number(point)?;
            Some(match self.devices.is_hexadecimal(&r.device) {
                true => Device::hexadecimal(&r.device, number),
                false => Device::new(&r.device, number),
            })
        })
    }

    /// Each register code up to the end of its special registers (D0-D8499 on IDEC): what a
    /// simulated CPU holds besides the profile's devices, so that its identity register exists.
    pub(crate) fn through_special(&self) -> Vec<(String, usize)> {
        (self.registers.iter())
            .filter(|r| r.special)
            .map(|r| (r.device.clone(), r.last as usize + 1))
            .collect()
    }

    /// The register that names the CPU.
    pub(crate) fn identity(&self) -> &Device {
        &self.identity
    }

    /// The relay on while the CPU runs.
    pub(crate) fn running(&self) -> &Device {
        &self.running
    }
}

impl Addressing for Map {
    fn hex_numbered(&self, code: &str) -> bool {
        self.devices.is_hexadecimal(code)
    }

    fn kind(&self, device: &Device) -> Kind {
        match self.wire(&self.registers, device) {
            Some((_, r)) if r.special => Kind::Special,
            Some(_) => Kind::Data,
            None if self
                .devices
                .get(device.code())
                .is_some_and(|d| d.points_per_word > 1) =>
            {
                Kind::Bit
            }
            None if self.registers.iter().any(|r| r.device == device.code()) => Kind::Special,
            None => Kind::Bit,
        }
    }

    fn unaddressable(&self, device: &Device) -> Option<String> {
        self.register(device).is_none().then(|| {
            let ranges: Vec<String> = (self.registers.iter())
                .map(|r| format!("{}{}-{}{}", r.device, r.first, r.device, r.last))
                .collect();
            format!(
                "{device} is not a holding register of the Modbus map ({})",
                ranges.join(", ")
            )
        })
    }

    fn sandbox_devices(&self) -> &'static str {
        "the map's data registers, and its special registers when named"
    }

    fn data_devices(&self) -> &'static str {
        "data register of the Modbus map"
    }
}

/// The Modbus client as a bench's link, over a profile's map.
struct ModbusLink {
    client: ModbusClient,
    map: Arc<Map>,
}

impl ModbusLink {
    /// The wire address of a word the map has; an error that sends nothing otherwise.
    fn address(&self, device: &Device) -> Result<u16, LinkError> {
        self.map.register(device).ok_or_else(|| {
            LinkError::new(
                Failure::Protocol,
                ModbusError::Transport(TransportError::refused(
                    format!("an access to {device}"),
                    self.map.unaddressable(device).unwrap_or_default(),
                )),
            )
        })
    }
}

impl Link for ModbusLink {
    /// The value of the map's identity register, as `confirm` gives it: a decimal number.
    fn identify(&mut self) -> Result<Identity, LinkError> {
        let at = self.address(self.map.identity())?;
        let code = self.client.read_holding(at, 1)?;
        let code = code.first().copied().unwrap_or(0);
        Ok(Identity {
            name: code.to_string(),
            shown: format!("type code {code} ({}={code:04X}H)", self.map.identity()),
        })
    }

    fn run_state(&mut self) -> Result<RunState, LinkError> {
        let relay = self.map.running().clone();
        let at = self.map.coil(&relay).ok_or_else(|| {
            LinkError::new(
                Failure::Protocol,
                ModbusError::Transport(TransportError::refused(
                    format!("a read of {relay}"),
                    "the relay is not a coil of the Modbus map",
                )),
            )
        })?;
        let on = (self.client.read_coils(at, 1)?.first().copied()).unwrap_or(false);
        Ok(RunState {
            running: on,
            text: match on {
                true => format!("RUN ({relay} on)"),
                false => format!("STOP ({relay} off)"),
            },
        })
    }

    fn read(&mut self, head: &Device, count: u32) -> Result<Vec<u16>, LinkError> {
        let at = self.address(head)?;
        self.address(&head.with_index(head.index + count.max(1) - 1))?;
        Ok(self.client.read_holding(at, count as usize)?)
    }

    fn write(&mut self, write: &FencedWrite) -> Result<(), LinkError> {
        let at = self.address(write.head())?;
        Ok(self.client.write_registers(at, write.words())?)
    }

    fn batch_words(&self) -> usize {
        self.client.settings().limits.write_registers
    }

    fn connections(&self) -> u64 {
        self.client.connections()
    }

    fn requests(&self) -> u64 {
        self.client.requests()
    }

    fn is_connected(&self) -> bool {
        self.client.is_connected()
    }

    fn disconnect(&mut self) {
        self.client.disconnect();
    }
}

/// How to reach a CPU over Modbus TCP: the client's settings and the profile's map.
#[derive(Debug, Clone)]
pub(crate) struct ModbusLinkSettings {
    pub client: ModbusSettings,
    pub map: Arc<Map>,
}

impl LinkSettings for ModbusLinkSettings {
    fn kind(&self) -> crate::model::profile::LinkKind {
        crate::model::profile::LinkKind::ModbusTcp
    }
    fn open(&self) -> Box<dyn Link> {
        Box::new(ModbusLink {
            client: ModbusClient::new(self.client.clone()),
            map: self.map.clone(),
        })
    }
    fn describe(&self) -> String {
        self.client.describe()
    }
    fn address(&self) -> &str {
        &self.client.address
    }
    fn addressing(&self) -> &dyn Addressing {
        self.map.as_ref()
    }
    fn clone_box(&self) -> Box<dyn LinkSettings> {
        Box::new(self.clone())
    }
}

/// A bench over Modbus TCP, while its link settings may still change.
pub(crate) type ModbusBench = BenchSettings<ModbusLinkSettings>;

/// The keys the Modbus link reads besides the bench's own.
const LINK_KEYS: [&str; 2] = ["unit", "reply_ms"];

impl BenchSettings<ModbusLinkSettings> {
    /// Settings with the link's defaults (unit 1, replies within 1 s) and the map of the
    /// manifest's profile.
    pub(crate) fn modbus(
        name: impl Into<String>,
        address: impl Into<String>,
        map: Arc<Map>,
        manifest: Manifest,
        variant: impl Into<String>,
        confirm: impl Into<String>,
        sandbox: Vec<WordRange>,
    ) -> Self {
        let link = ModbusLinkSettings {
            client: ModbusSettings::new(address),
            map,
        };
        BenchSettings::with_link(name, link, manifest, variant, confirm, sandbox)
    }

    /// Reads `modbus:NAME=HOST:PORT?key=value&...`; `None` when `text` is not of this form.
    /// Keys: `manifest`, `confirm` (the value of the map's identity register, D8002 on IDEC),
    /// `sandbox` as for every bench, and optionally `variant`, `unit` (the unit id, 0-255),
    /// `reply_ms` (how long one reply may take), `timeout`, `max_faults`, `poll_ms`. The map is
    /// the manifest's profile's.
    pub(crate) fn parse(
        text: &str,
        base: &Path,
        profiles: &Profiles,
    ) -> Result<Option<ModbusBench>, LiveError> {
        let Some(spec) = Spec::split(text, "modbus", &LINK_KEYS)? else {
            return Ok(None);
        };
        let map = |m: &Manifest| -> Result<Map, LiveError> {
            let profile = profiles.get(&m.profile).ok_or_else(|| {
                refused!(
                    "the manifest is for profile `{}`, which is not loaded",
                    m.profile
                )
            })?;
            Map::of(profile)
        };
        let (manifest, variant, confirm, sandbox, map) = spec.parts(base, map)?;
        let mut s = ModbusBench::modbus(
            spec.name,
            spec.address,
            Arc::new(map),
            manifest,
            variant,
            confirm,
            sandbox,
        );
        if let Some(v) = spec.get("unit") {
            s.link.client.unit = v
                .parse::<u8>()
                .map_err(|_| refused!("`unit={v}`: give a unit id from 0 to 255"))?;
        }
        if let Some(ms) = spec.number("reply_ms")? {
            s.link.client.reply_timeout = Duration::from_secs_f64(ms / 1000.0);
        }
        spec.timings(&mut s)?;
        Ok(Some(s))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fc4a() -> Map {
        let profiles = crate::load::load_profiles(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("vendors"),
        )
        .expect("profiles");
        Map::of(profiles.get("idec-fc4a").expect("FC4A")).expect("a Modbus map")
    }

    /// The FC6A's map as the FC4A profile gives it: a data register's wire address is its
    /// number in the three ranges, and M8000-M8317 are coils 9001 on (one-based), eight to
    /// each ten of the relay's number.
    #[test]
    fn the_map_is_the_fc6a_manuals() {
        let map = fc4a();
        let d = |n| Device::new("D", n);
        let m = |n| Device::new("M", n);
        for (n, wire) in [(0, Some(0)), (7999, Some(7999)), (8000, Some(8000))] {
            assert_eq!(map.register(&d(n)), wire, "D{n}");
        }
        for n in [8500, 9999, 56000] {
            assert_eq!(map.register(&d(n)), None, "D{n}");
        }
        assert_eq!(map.register(&d(10000)), Some(10000));
        assert_eq!(map.register(&m(100)), None);
        assert_eq!(map.coil(&m(8000)), Some(9000));
        assert_eq!(map.coil(&m(8004)), Some(9004), "wire 0x232C, coil 009005");
        assert_eq!(map.coil(&m(8010)), Some(9008));
        assert_eq!(map.coil(&m(8317)), Some(9255));
        assert_eq!(map.coil(&m(7777)), None);
        assert_eq!(map.relay(9000), Some(m(8000)));
        assert_eq!(map.relay(9008), Some(m(8010)));
        assert_eq!(map.relay(9255), Some(m(8317)));
        assert_eq!(map.relay(9256), None);
        assert_eq!(map.device_at(8002), Some(d(8002)));
        assert_eq!(map.device_at(12345), Some(d(12345)));
        assert_eq!(map.device_at(9000), None);
        assert_eq!(map.kind(&d(8006)), Kind::Special);
        assert_eq!(map.kind(&d(100)), Kind::Data);
        assert_eq!(map.kind(&m(100)), Kind::Bit);
        assert_eq!((map.identity(), map.running()), (&d(8002), &m(8000)));
        assert_eq!(map.through_special(), [("D".to_string(), 8500)]);
    }
}
