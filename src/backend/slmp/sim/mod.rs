//! A simulated MELSEC CPU: an SLMP server on 127.0.0.1 over the simulated program
//! ([`crate::backend::bench::sim`]), which runs the generated test program's behaviour with a
//! reference model.
//!
//! The server answers 0101, 0401, 0403 and 1401 in 3E or 4E frames, binary code, in the frame
//! of each request; SD203 says whether the CPU runs. In ASCII code it answers 0101 and 0401
//! (what a protocol probe asks, `hil probe`), reading every field as the manual writes it:
//! capitals only, so a character the manual does not list — a lowercase letter included, which
//! no manual settles — is C050H, ASCII that cannot be converted.

#[cfg(test)]
mod remote;

#[cfg(test)]
pub(crate) use remote::RemoteProgram;

use std::io::Write;
use std::net::TcpStream;
use std::sync::Arc;

use super::ascii;
use super::frame::{
    self, decode_body, message_len, Code, Decoded, DeviceForm, DeviceRef, FrameKind, Request,
    Response,
};
use super::limits::{Family, Limits};
use crate::backend::bench::error::LiveError;
pub use crate::backend::bench::sim::FaultRule;
use crate::backend::bench::sim::{Cpu, FaultAction, Program, Running};
use crate::backend::Backend;
use crate::device::Device;
use crate::model::profile::Profile;

/// What the SLMP server adds to the simulated CPU.
#[derive(Debug, Clone)]
pub struct SlmpSim {
    /// What 0101 answers.
    pub type_name: String,
    pub model_code: u16,
    /// Whether the CPU takes the long device form (subcommand 0002); an FX5 does not.
    pub long_form: bool,
}

/// How the simulated MELSEC CPU is set up.
pub type SlmpSimSettings = crate::backend::bench::sim::SimSettings<SlmpSim>;

/// The commands the server answers, which a fault rule may name.
pub(crate) const COMMANDS: [u16; 4] = [
    frame::command::READ_TYPE_NAME,
    frame::command::READ,
    frame::command::RANDOM_READ,
    frame::command::WRITE,
];

impl crate::backend::bench::sim::SimSettings<SlmpSim> {
    /// A CPU of the manifest's family that names itself `type_name`.
    pub fn new(
        manifest: crate::backend::bench::manifest::Manifest,
        variant: impl Into<String>,
        type_name: impl Into<String>,
    ) -> Self {
        let long_form = manifest.profile != "mitsubishi-fx5";
        let type_name = type_name.into();
        let link = SlmpSim {
            model_code: model_code(&type_name).unwrap_or(0),
            type_name,
            long_form,
        };
        Self::with_link(manifest, variant, link)
    }
}

impl FaultRule {
    /// A fault rule of the SLMP server, read as `hil sim --fault` takes it (`1401:3:drop`).
    pub fn slmp(text: &str) -> Result<FaultRule, LiveError> {
        FaultRule::parse(text, &COMMANDS)
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

/// SD203: 0 in the low four bits for RUN, 2 for STOP.
fn show_state(_: &SlmpSimSettings, cpu: &mut Cpu) {
    let v = if cpu.running { 0x0000 } else { 0x0002 };
    cpu.set_word(&Device::new("SD", 203), v);
}

/// A running simulated MELSEC CPU; dropping it stops it.
pub type SlmpSimulator = Running<SlmpSim>;

impl Running<SlmpSim> {
    /// Starts the server and the scan thread.
    pub fn start(
        settings: SlmpSimSettings,
        profile: Arc<Profile>,
        model: Arc<dyn Backend>,
    ) -> Result<SlmpSimulator, LiveError> {
        Running::serve(program(settings, profile, model)?, serve)
    }
}

/// The program on a MELSEC CPU's memory: the profile's devices, and the special registers
/// (SD0, SD203, SD8067 and their neighbours) and link registers every MELSEC CPU has though a
/// profile may not name them (iQ-R's default allocation: W0-W1FFF, SW0-SW7FF).
pub(super) fn program(
    settings: SlmpSimSettings,
    profile: Arc<Profile>,
    model: Arc<dyn Backend>,
) -> Result<Arc<Program<SlmpSim>>, LiveError> {
    Program::new(
        settings,
        profile,
        model,
        &super::ADDRESSING,
        &[("SD", 12288), ("W", 0x2000), ("SW", 0x800)],
        show_state,
    )
}

/// A device as the CPU's memory names it.
fn device(d: DeviceRef) -> Option<Device> {
    let letters = frame::device_letters(d.code)?;
    Some(match frame::hex_numbered(letters) {
        true => Device::hexadecimal(letters, d.number),
        false => Device::new(letters, d.number),
    })
}

/// `count` words from `d`, or the end code of a device the CPU does not have.
fn device_words(cpu: &Cpu, d: DeviceRef, count: usize) -> Result<&[u16], u16> {
    let letters = frame::device_letters(d.code).ok_or(0xC05C_u16)?;
    let words = cpu.words.get(letters).ok_or(0xC05C_u16)?;
    let first = d.number as usize;
    words.get(first..first + count).ok_or(0xC056)
}

/// Reads one whole request, polling the stop flag, in the code its first character says
/// (`5000`/`5400` in ASCII, 50H/54H in binary); `None` when the connection ends.
fn read_request(shared: &Program<SlmpSim>, stream: &mut TcpStream) -> Option<(Vec<u8>, Code)> {
    let mut buf = vec![0u8; 4];
    shared.fill(stream, &mut buf[..2], 0)?;
    if buf[0] == b'5' {
        shared.fill(stream, &mut buf, 2)?;
        let frame = match &buf[..] {
            b"5400" => FrameKind::E4,
            _ => FrameKind::E3,
        };
        let header = ascii::header_len(frame);
        buf.resize(header, 0);
        shared.fill(stream, &mut buf, 4)?;
        let total = ascii::message_len(frame, &buf).ok()?;
        buf.resize(total, 0);
        shared.fill(stream, &mut buf, header)?;
        return Some((buf, Code::Ascii));
    }
    buf.truncate(2);
    let frame = FrameKind::of_request(buf[0]).unwrap_or(FrameKind::E3);
    let header = frame.header_len();
    buf.resize(header, 0);
    shared.fill(stream, &mut buf, 2)?;
    let total = message_len(frame, &buf).ok()?;
    buf.resize(total, 0);
    shared.fill(stream, &mut buf, header)?;
    Some((buf, Code::Binary))
}

fn serve(shared: &Program<SlmpSim>, mut stream: TcpStream) {
    while let Some((bytes, code)) = read_request(shared, &mut stream) {
        // A binary request that does not decode gets no answer, as a CPU stays silent on a
        // frame it does not take; an ASCII one that does not convert is answered C050H (the
        // manual's strictest reading: capitals only, docs/live-cpu.md).
        let request = match code {
            Code::Binary => match Request::decode(&bytes) {
                Ok(request) => request,
                Err(_) => continue,
            },
            Code::Ascii => match ascii::decode_request(&bytes) {
                (_, _, _, Ok(request)) => request,
                (frame, serial, route, Err(refusal)) => {
                    let answer = Response {
                        frame,
                        serial,
                        route,
                        end_code: refusal.end_code(),
                        data: Vec::new(),
                    };
                    if stream
                        .write_all(&ascii::encode_response(&answer, 0))
                        .is_err()
                    {
                        return;
                    }
                    continue;
                }
            },
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
            cpu.take_fault(request.command, head.and_then(device).as_ref())
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
                    Ok(decoded) => handle(shared, &request, code, decoded),
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
                shared.set_running(&mut cpu, false);
            }
            _ => {}
        }
        let answer = match code {
            Code::Binary => response.encode(),
            Code::Ascii => ascii::encode_response(&response, request.command),
        };
        if stream.write_all(&answer).is_err() {
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

/// What a request may carry on this CPU: the limits of its family in the code the request came
/// in (ASCII halves some), for the device form it uses.
fn limits(shared: &Program<SlmpSim>, request: &Request, code: Code) -> Limits {
    let form = match request.subcommand {
        0x0002 => DeviceForm::Long,
        _ => DeviceForm::Short,
    };
    super::limits::limits(
        Family::of_profile(&shared.settings.manifest.profile),
        code,
        form,
    )
}

/// Answers one decoded request: (end code, data).
fn handle(
    shared: &Program<SlmpSim>,
    request: &Request,
    code: Code,
    decoded: Decoded,
) -> (u16, Vec<u8>) {
    if request.subcommand == 0x0002 && !shared.settings.link.long_form {
        return (0xC059, Vec::new());
    }
    let mut cpu = shared.lock();
    match decoded {
        Decoded::TypeName => (
            0,
            frame::type_name_data(
                &shared.settings.link.type_name,
                shared.settings.link.model_code,
            ),
        ),
        Decoded::Read { head, count } => {
            if count == 0 || count > limits(shared, request, code).batch_words {
                return (0xC051, Vec::new());
            }
            match device_words(&cpu, head, count) {
                Ok(words) => (0, words.iter().flat_map(|w| w.to_le_bytes()).collect()),
                Err(code) => (code, Vec::new()),
            }
        }
        Decoded::RandomRead { devices } => {
            if devices.is_empty() || devices.len() > limits(shared, request, code).random_points {
                return (0xC054, Vec::new());
            }
            let mut data = Vec::with_capacity(2 * devices.len());
            for d in devices {
                match device_words(&cpu, d, 1) {
                    Ok(w) => {
                        let word = device(d)
                            .and_then(|d| shared.read(&cpu, &d))
                            .unwrap_or(w[0]);
                        data.extend_from_slice(&word.to_le_bytes());
                    }
                    Err(code) => return (code, Vec::new()),
                }
            }
            (0, data)
        }
        Decoded::Write { head, words } => {
            if words.is_empty() || words.len() > limits(shared, request, code).batch_words {
                return (0xC051, Vec::new());
            }
            if let Err(code) = device_words(&cpu, head, words.len()) {
                return (code, Vec::new());
            }
            let Some(head) = device(head) else {
                return (0xC05C, Vec::new());
            };
            shared.write(&mut cpu, &head, &words);
            (0, Vec::new())
        }
        Decoded::Other { .. } => (0xC059, Vec::new()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn fault_rules_read_from_the_command_line() {
        let rule = FaultRule::slmp("1401:3:drop").expect("drop");
        assert_eq!(
            (rule.command, rule.nth, rule.action),
            (0x1401, 3, FaultAction::Drop)
        );
        let rule = FaultRule::slmp("0403:2:delay=3000").expect("delay");
        assert_eq!(rule.action, FaultAction::Delay(Duration::from_secs(3)));
        let rule = FaultRule::slmp("0401:1:end=C051").expect("end code");
        assert_eq!(rule.action, FaultAction::EndCode(0xC051));
        for bad in [
            "1401:0:drop",
            "1402:1:drop",
            "1401:1:explode",
            "1401:1",
            "0401:1:end=0",
        ] {
            assert!(FaultRule::slmp(bad).is_err(), "{bad}");
        }
        assert_eq!(model_code("FX5U-32MT/DS"), Some(0x4A49));
        assert_eq!(model_code("R04CPU"), Some(0x4800));
    }
}
