//! A simulated IDEC MicroSmart CPU: a Modbus TCP server on 127.0.0.1 over the simulated
//! program ([`crate::backend::bench::sim`]), which runs the generated test program's behaviour
//! with the reference model.
//!
//! The server answers function codes 01 (coils M8000-M8317), 03, 06 and 16 (data registers
//! D0-D8499) for any unit id, as a CPU that is the server itself does; M8000 says whether the
//! CPU runs and D8002 holds its type code. Anything else is answered with exception 01 (an
//! unknown function) or 02 (an address the map does not have).

use std::io::Write;
use std::net::{SocketAddr, TcpStream};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::thread::JoinHandle;

use super::frame::{self, Decoded, Request, Response};
use super::{coil, START_CONTROL, TYPE_CODE};
use crate::backend::bench::error::LiveError;
use crate::backend::bench::manifest::Manifest;
use crate::backend::bench::sim::{Audit, Cpu, FaultAction, FaultRule, Program};
use crate::backend::Backend;
use crate::device::Device;
use crate::model::profile::Profile;

/// What the Modbus server adds to the simulated CPU.
#[derive(Debug, Clone)]
pub struct IdecSim {
    /// What D8002 holds.
    pub type_code: u16,
}

/// How the simulated IDEC CPU is set up.
pub type IdecSimSettings = crate::backend::bench::sim::SimSettings<IdecSim>;

/// The function codes the server answers, which a fault rule may name.
pub(crate) const FUNCTIONS: [u16; 4] = [
    frame::READ_COILS as u16,
    frame::READ_HOLDING as u16,
    frame::WRITE_SINGLE as u16,
    frame::WRITE_MULTIPLE as u16,
];

/// The data registers the simulated CPU holds: D0-D8499, the special data registers included.
const REGISTERS: usize = 8500;

impl crate::backend::bench::sim::SimSettings<IdecSim> {
    /// A CPU that holds `type_code` in D8002.
    pub fn idec(manifest: Manifest, variant: impl Into<String>, type_code: u16) -> Self {
        Self::with_link(manifest, variant, IdecSim { type_code })
    }
}

impl FaultRule {
    /// A fault rule of the Modbus server: `10:3:drop` closes the connection on the third
    /// write of several registers (function codes in hexadecimal: 01, 03, 06, 10).
    pub fn modbus(text: &str) -> Result<FaultRule, LiveError> {
        FaultRule::parse(text, &FUNCTIONS)
    }
}

/// M8000 on while the CPU runs.
fn show_state(cpu: &mut Cpu) {
    let running = cpu.running;
    cpu.set_bit(&format!("M{START_CONTROL}"), running);
}

/// A running simulated IDEC CPU; dropping it stops it.
pub struct IdecSimulator {
    address: SocketAddr,
    shared: Arc<Program<IdecSim>>,
    threads: Vec<JoinHandle<()>>,
}

impl IdecSimulator {
    /// Starts the server and the scan thread.
    pub fn start(
        settings: IdecSimSettings,
        profile: Arc<Profile>,
        model: Arc<dyn Backend>,
    ) -> Result<IdecSimulator, LiveError> {
        let type_code = settings.link.type_code;
        let shared = Program::new(
            settings,
            profile,
            model,
            &super::ADDRESSING,
            &[("D", REGISTERS)],
            show_state,
        )?;
        shared
            .lock()
            .set_word(&Device::new("D", TYPE_CODE), type_code);
        let (address, threads) = shared.start(serve)?;
        Ok(IdecSimulator {
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
        self.shared.set_running(&mut cpu, run);
    }

    /// A word of device memory (0 for one the CPU does not have).
    pub fn read(&self, device: &Device) -> u16 {
        self.shared.lock().word(device).unwrap_or(0)
    }

    /// Adds a fault rule while running.
    pub fn add_fault(&self, rule: FaultRule) {
        self.shared.lock().add_fault(rule);
    }

    /// Keeps the error flag on whatever the program does, as a CPU on which a user program
    /// cannot reset it would (whether the FC4A's can is unconfirmed).
    pub fn hold_error_flag(&self, held: bool) {
        let flag = self.shared.settings.manifest.error.flag.clone();
        self.shared.lock().hold(&flag, held);
    }
}

impl Drop for IdecSimulator {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::SeqCst);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

/// Reads one whole request by its MBAP length; `None` when the connection ends or the header
/// is not Modbus TCP (a server drops such a connection).
fn read_request(shared: &Program<IdecSim>, stream: &mut TcpStream) -> Option<Vec<u8>> {
    let mut header = [0u8; 6];
    shared.fill(stream, &mut header, 0)?;
    let total = frame::message_len(&header).ok()?;
    let mut buf = header.to_vec();
    buf.resize(total, 0);
    shared.fill(stream, &mut buf, 6)?;
    Some(buf)
}

fn serve(shared: &Program<IdecSim>, mut stream: TcpStream) {
    while let Some(bytes) = read_request(shared, &mut stream) {
        let Ok((tid, unit, decoded)) = frame::decode_request(&bytes) else {
            return;
        };
        let (function, head) = match &decoded {
            Decoded::Request(r) => (r.function(), first_device(r)),
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

/// The data register a register request starts at.
fn first_device(request: &Request) -> Option<Device> {
    match request {
        Request::ReadHolding { address, .. }
        | Request::WriteSingle { address, .. }
        | Request::WriteMultiple { address, .. } => Some(Device::new("D", u32::from(*address))),
        Request::ReadCoils { .. } => None,
    }
}

/// The special internal relay at a coil's wire address, if the map has one there.
fn relay(wire: u32) -> Option<u32> {
    let offset = wire.checked_sub(9000)?;
    let relay = 8000 + offset / 8 * 10 + offset % 8;
    (coil(relay) == Some(wire as u16)).then_some(relay)
}

/// Answers one request.
fn handle(shared: &Program<IdecSim>, request: &Request) -> Response {
    let illegal_address = |function: u8| Response::Exception { function, code: 2 };
    let function = request.function();
    let mut cpu = shared.lock();
    match request {
        Request::ReadCoils { address, count } => {
            let first = u32::from(*address);
            let relays: Option<Vec<u32>> = (first..first + u32::from(*count)).map(relay).collect();
            match relays {
                Some(relays) => {
                    Response::Coils(relays.iter().map(|r| cpu.bit(&format!("M{r}"))).collect())
                }
                None => illegal_address(function),
            }
        }
        Request::ReadHolding { address, count } => {
            let first = usize::from(*address);
            let words: Option<Vec<u16>> = (first..first + usize::from(*count))
                .map(|i| shared.read(&cpu, &Device::new("D", i as u32)))
                .collect();
            match words {
                Some(words) if first + usize::from(*count) <= REGISTERS => {
                    Response::Registers(words)
                }
                _ => illegal_address(function),
            }
        }
        Request::WriteSingle { address, value } => {
            if usize::from(*address) >= REGISTERS {
                return illegal_address(function);
            }
            shared.write(&mut cpu, &Device::new("D", u32::from(*address)), &[*value]);
            Response::WroteSingle {
                address: *address,
                value: *value,
            }
        }
        Request::WriteMultiple { address, values } => {
            if usize::from(*address) + values.len() > REGISTERS {
                return illegal_address(function);
            }
            shared.write(&mut cpu, &Device::new("D", u32::from(*address)), values);
            Response::WroteMultiple {
                address: *address,
                count: values.len() as u16,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_coils_wire_address_is_its_relay() {
        assert_eq!(relay(9000), Some(8000));
        assert_eq!(relay(9004), Some(8004));
        assert_eq!(relay(9008), Some(8010));
        assert_eq!(relay(9255), Some(8317));
        assert_eq!(relay(9256), None);
        assert_eq!(relay(8999), None);
    }

    #[test]
    fn fault_rules_name_function_codes() {
        let rule = FaultRule::modbus("10:3:drop").expect("drop");
        assert_eq!((rule.command, rule.nth), (0x10, 3));
        assert!(FaultRule::modbus("05:1:drop").is_err(), "05 is never sent");
    }
}
