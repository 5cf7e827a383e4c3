//! A simulated CPU over Modbus TCP (IDEC MicroSmart): a Modbus TCP server on 127.0.0.1 over
//! the simulated program ([`crate::backend::bench::sim`]), which runs the generated test
//! program's behaviour with the reference model, at the addresses of the profile's map.
//!
//! The server answers function codes 01 (the map's coils), 03, 06 and 16 (the data registers of
//! the map up to its special ones, D0-D8499 on IDEC) for any unit id, as a CPU that is the server
//! itself does; the map's running relay says whether the CPU runs and its identity register
//! holds the type code. Anything else is answered with exception 01 (an unknown function) or 02
//! (an address the map does not have).

use std::io::Write;
use std::net::TcpStream;
use std::sync::Arc;

use super::frame::{self, Decoded, Request, Response};
use super::Map;
use crate::backend::bench::error::LiveError;
use crate::backend::bench::manifest::Manifest;
use crate::backend::bench::sim::{Cpu, FaultAction, FaultRule, Program, Running, SimSettings};
use crate::backend::Backend;
use crate::device::Device;
use crate::model::profile::Profile;

/// What the Modbus server adds to the simulated CPU.
#[derive(Debug, Clone)]
pub struct ModbusSim {
    /// What the map's identity register (D8002) holds.
    pub type_code: u16,
}

/// The simulated CPU as served: the profile's map.
#[derive(Debug, Clone)]
pub struct Served {
    map: Arc<Map>,
}

/// How the simulated IDEC CPU is set up.
pub type ModbusSimSettings = crate::backend::bench::sim::SimSettings<ModbusSim>;

/// The function codes the server answers, which a fault rule may name.
pub(crate) const FUNCTIONS: [u16; 4] = [
    frame::READ_COILS as u16,
    frame::READ_HOLDING as u16,
    frame::WRITE_SINGLE as u16,
    frame::WRITE_MULTIPLE as u16,
];

impl crate::backend::bench::sim::SimSettings<ModbusSim> {
    /// A CPU that holds `type_code` in D8002.
    pub fn idec(manifest: Manifest, variant: impl Into<String>, type_code: u16) -> Self {
        Self::with_link(manifest, variant, ModbusSim { type_code })
    }
}

impl FaultRule {
    /// A fault rule of the Modbus server: `10:3:drop` closes the connection on the third
    /// write of several registers (function codes in hexadecimal: 01, 03, 06, 10).
    pub fn modbus(text: &str) -> Result<FaultRule, LiveError> {
        FaultRule::parse(text, &FUNCTIONS)
    }
}

/// The map's running relay (M8000) on while the CPU runs.
fn show_state(settings: &SimSettings<Served>, cpu: &mut Cpu) {
    let running = cpu.running;
    cpu.set_bit(&settings.link.map.running().to_string(), running);
}

/// A running simulated IDEC CPU; dropping it stops it.
pub type ModbusSimulator = Running<Served>;

impl Running<Served> {
    /// Starts the server and the scan thread.
    pub fn start(
        settings: ModbusSimSettings,
        profile: Arc<Profile>,
        model: Arc<dyn Backend>,
    ) -> Result<ModbusSimulator, LiveError> {
        let map = Arc::new(Map::of(&profile)?);
        let type_code = settings.link.type_code;
        let identity = map.identity().clone();
        let held = map.through_special();
        let more: Vec<(&str, usize)> = held.iter().map(|(c, n)| (c.as_str(), *n)).collect();
        let settings = settings.relink(Served { map: map.clone() });
        let shared = Program::new(settings, profile, model, map.as_ref(), &more, show_state)?;
        shared.lock().set_word(&identity, type_code);
        Running::serve(shared, serve)
    }
}

/// Reads one whole request by its MBAP length; `None` when the connection ends or the header
/// is not Modbus TCP (a server drops such a connection).
fn read_request(shared: &Program<Served>, stream: &mut TcpStream) -> Option<Vec<u8>> {
    let mut header = [0u8; 6];
    shared.fill(stream, &mut header, 0)?;
    let total = frame::message_len(&header).ok()?;
    let mut buf = header.to_vec();
    buf.resize(total, 0);
    shared.fill(stream, &mut buf, 6)?;
    Some(buf)
}

fn serve(shared: &Program<Served>, mut stream: TcpStream) {
    while let Some(bytes) = read_request(shared, &mut stream) {
        let Ok((tid, unit, decoded)) = frame::decode_request(&bytes) else {
            return;
        };
        let (function, head) = match &decoded {
            Decoded::Request(r) => (r.function(), first_device(&shared.settings.link.map, r)),
            Decoded::Unsupported { function } | Decoded::Illegal { function, .. } => {
                (*function, None)
            }
        };
        let action = {
            let mut cpu = shared.lock();
            *cpu.audit.commands.entry(u16::from(function)).or_default() += 1;
            cpu.take_fault(u16::from(function), head.as_ref())
        };
        let response = match &action {
            Some(FaultAction::Drop) => return,
            Some(FaultAction::Garbage) => {
                let _ = stream.write_all(b"\xFF\x00garbage, not Modbus\r\n");
                continue;
            }
            Some(FaultAction::EndCode(code)) => Response::Exception {
                function,
                code: *code as u8,
            },
            _ => match decoded {
                Decoded::Request(r) => handle(shared, &r),
                Decoded::Unsupported { function } => Response::Exception { function, code: 1 },
                Decoded::Illegal { function, code } => Response::Exception { function, code },
            },
        };
        let mut tid = tid;
        match action {
            Some(FaultAction::Delay(d)) => std::thread::sleep(d),
            Some(FaultAction::WrongSerial) => tid = tid.wrapping_add(1),
            Some(FaultAction::Stop) => {
                let mut cpu = shared.lock();
                shared.set_running(&mut cpu, false);
            }
            _ => {}
        }
        if stream
            .write_all(&frame::encode_response(tid, unit, &response))
            .is_err()
        {
            return;
        }
    }
}

/// The register a request starts at, as the map names it.
fn first_device(map: &Map, request: &Request) -> Option<Device> {
    match request {
        Request::ReadHolding { address, .. }
        | Request::WriteSingle { address, .. }
        | Request::WriteMultiple { address, .. } => map.device_at(*address),
        Request::ReadCoils { .. } => None,
    }
}

/// Answers one request.
fn handle(shared: &Program<Served>, request: &Request) -> Response {
    let map = &shared.settings.link.map;
    let function = request.function();
    let illegal_address = Response::Exception { function, code: 2 };
    let mut cpu = shared.lock();
    // The registers from `address` on, each as the map names it and held by this CPU.
    let registers = |address: u16, count: usize| -> Option<Vec<Device>> {
        (0..count)
            .map(|i| {
                let wire = u16::try_from(usize::from(address) + i).ok()?;
                map.device_at(wire)
            })
            .collect()
    };
    match request {
        Request::ReadCoils { address, count } => {
            let relays: Option<Vec<Device>> = (0..*count)
                .map(|i| map.relay(address.checked_add(i)?))
                .collect();
            match relays {
                Some(relays) => {
                    Response::Coils(relays.iter().map(|r| cpu.bit(&r.to_string())).collect())
                }
                None => illegal_address,
            }
        }
        Request::ReadHolding { address, count } => {
            let words: Option<Vec<u16>> = registers(*address, usize::from(*count))
                .and_then(|ds| ds.iter().map(|d| shared.read(&cpu, d)).collect());
            match words {
                Some(words) => Response::Registers(words),
                None => illegal_address,
            }
        }
        Request::WriteSingle { address, value } => match registers(*address, 1) {
            Some(ds) if ds.iter().all(|d| cpu.word(d).is_some()) => {
                shared.write(&mut cpu, &ds[0], &[*value]);
                Response::WroteSingle {
                    address: *address,
                    value: *value,
                }
            }
            _ => illegal_address,
        },
        Request::WriteMultiple { address, values } => match registers(*address, values.len()) {
            Some(ds) if ds.iter().all(|d| cpu.word(d).is_some()) => {
                shared.write(&mut cpu, &ds[0], values);
                Response::WroteMultiple {
                    address: *address,
                    count: values.len() as u16,
                }
            }
            _ => illegal_address,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fault_rules_name_function_codes() {
        let rule = FaultRule::modbus("10:3:drop").expect("drop");
        assert_eq!((rule.command, rule.nth), (0x10, 3));
        assert!(FaultRule::modbus("05:1:drop").is_err(), "05 is never sent");
    }
}
