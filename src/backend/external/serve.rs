//! The other side of the protocol: a built-in backend served over stdin/stdout.
//!
//! `plc-conformance serve --profile ID` answers the protocol with the profile's reference model.
//! Run as an external backend against the corpus it must conform everywhere the model does: that
//! proves the whole protocol path (window, flags, fill, answers) end to end, and it is the
//! native adapter the protocol benchmarks measure.

use std::collections::BTreeMap;
use std::io::{BufRead, Write};

use super::protocol::{
    BackendInfo, BackendMessage, Capabilities, CaseRequest, Converted, ConvertedUnsupported,
    ErrorReport, FillName, HarnessMessage, OperandValue, RunCase, SignalReport, PROTOCOL_VERSION,
};
use crate::backend::{Backend, Request, Response};
use crate::memory::{Fill, Image};
use crate::model::profile::Profile;
use crate::model::{ErrorSignal, Operand};

/// Why serving ended early.
#[derive(Debug)]
pub(crate) enum ServeError {
    Read(std::io::Error),
    Write(std::io::Error),
    /// A line that is not a message of the harness, with the start of it.
    NotHarness {
        error: String,
        line: String,
    },
}

impl std::fmt::Display for ServeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ServeError::Read(_) => write!(f, "stdin could not be read"),
            ServeError::Write(_) => write!(f, "stdout could not be written"),
            ServeError::NotHarness { error, line } => {
                write!(f, "not a harness message ({error}): {line}")
            }
        }
    }
}

impl std::error::Error for ServeError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            ServeError::Read(e) | ServeError::Write(e) => Some(e),
            ServeError::NotHarness { .. } => None,
        }
    }
}

/// Serves one backend until `shutdown` or the end of input. Errors are I/O errors and messages
/// that are not the harness's; both end the session.
pub(crate) fn serve(
    backend: &dyn Backend,
    profile: &Profile,
    input: impl BufRead,
    mut output: impl Write,
) -> Result<(), ServeError> {
    let mut input = input;
    let mut line = String::new();
    loop {
        line.clear();
        let read = input.read_line(&mut line).map_err(ServeError::Read)?;
        if read == 0 {
            return Ok(());
        }
        if line.trim().is_empty() {
            continue;
        }
        let message =
            HarnessMessage::from_line(line.as_bytes()).map_err(|e| ServeError::NotHarness {
                error: e.to_string(),
                line: line.chars().take(200).collect(),
            })?;
        match message {
            HarnessMessage::Hello { protocol, .. } => {
                // The version the harness asks for, up to the newest this server speaks.
                let version = protocol.clamp(1, PROTOCOL_VERSION);
                write_message(&mut output, &hello(backend, profile, version))?;
            }
            HarnessMessage::Run { cases } => {
                for case in &cases {
                    let message = match case {
                        RunCase::Instruction(case) => answer(backend, profile, case),
                        RunCase::Codec(case) => BackendMessage::Unsupported {
                            id: case.id,
                            reason: "this server answers at the instruction level".into(),
                        },
                    };
                    write_message(&mut output, &message)?;
                }
            }
            HarnessMessage::Convert { id, digits, .. } => {
                let unsupported = || {
                    Converted::Unsupported(ConvertedUnsupported {
                        unsupported: "this server answers at the instruction level".into(),
                    })
                };
                let answers = digits.iter().map(|_| unsupported()).collect();
                write_message(&mut output, &BackendMessage::Converted { id, answers })?;
            }
            HarnessMessage::Shutdown => return Ok(()),
        }
        output.flush().map_err(ServeError::Write)?;
    }
}

fn write_message(output: &mut impl Write, message: &BackendMessage) -> Result<(), ServeError> {
    serde_json::to_writer(&mut *output, message)
        .map_err(std::io::Error::from)
        .and_then(|()| output.write_all(b"\n"))
        .map_err(ServeError::Write)
}

/// The capabilities of a built-in backend: every instruction it claims on some variant.
fn hello(backend: &dyn Backend, profile: &Profile, protocol: u32) -> BackendMessage {
    let instructions = profile
        .instructions
        .keys()
        .filter(|i| profile.variants.iter().any(|v| backend.claims(i, &v.id)))
        .cloned()
        .collect();
    BackendMessage::Hello {
        protocol,
        backend: BackendInfo {
            name: format!("plc-conformance serve ({})", backend.name()),
            version: env!("CARGO_PKG_VERSION").to_string(),
        },
        capabilities: Capabilities {
            profile: profile.id.clone(),
            instructions,
            codec: None,
            operands: BTreeMap::new(),
            device_ranges: None,
            variants: None,
            flags: BTreeMap::new(),
        },
    }
}

fn answer(backend: &dyn Backend, profile: &Profile, case: &CaseRequest) -> BackendMessage {
    let unsupported = |reason: String| BackendMessage::Unsupported {
        id: case.id,
        reason,
    };
    if case.profile != profile.id {
        return unsupported(format!("this server implements {}", profile.id));
    }
    let Some(variant) = profile.variant(&case.variant) else {
        return unsupported(format!("no variant {} in {}", case.variant, profile.id));
    };
    let (mut operands, mut indirect) = (BTreeMap::new(), BTreeMap::new());
    for (name, value) in &case.operands {
        let operand = match value {
            OperandValue::Device(d) => match case.operand_device(d) {
                Ok((d, pointer)) => {
                    if let Some(pointer) = pointer {
                        indirect.insert(name.clone(), pointer);
                    }
                    Operand::Device(d)
                }
                Err(e) => return unsupported(crate::error_chain::chain(&e)),
            },
            OperandValue::Constant(k) => Operand::Constant(*k),
        };
        operands.insert(name.clone(), operand);
    }
    let fill = match case.fill {
        FillName::A => Fill::A,
        FillName::B => Fill::B,
    };
    // Only words that differ from the fill need to be explicit: the image reads the fill for
    // the rest, inside the window and past it alike.
    let mut words = BTreeMap::new();
    for range in &case.memory {
        let Ok(mut device) = case.device(&range.start) else {
            return unsupported(format!("bad device `{}` in memory", range.start));
        };
        let values = match range.values(profile.unit) {
            Ok(values) => values,
            Err(e) => return unsupported(e.0),
        };
        let (first, step) = (device.index, device.points());
        for (i, word) in values.into_iter().enumerate() {
            let Some(index) = (i as u32)
                .checked_mul(step)
                .and_then(|apart| first.checked_add(apart))
            else {
                return unsupported(format!(
                    "memory from {} runs past the last device number",
                    range.start
                ));
            };
            device.index = index;
            if fill.value(&device, profile.unit) != word {
                words.insert(device.clone(), word);
            }
        }
    }
    let memory = Image::of_units(words, fill, profile.unit);
    let request = Request {
        profile,
        variant,
        instruction: &case.instruction,
        case_id: &case.case,
        flags: &case.flags,
        operands: &operands,
        indirect: &indirect,
        memory: &memory,
    };
    match backend.execute(&request) {
        Ok(Response::Done(outcome)) => BackendMessage::Result {
            id: case.id,
            memory: Vec::new(),
            // The error registers are words the model writes, as an emulator reports them.
            writes: (outcome.writes.iter().chain(&outcome.registers))
                .map(|(d, v)| (d.to_string(), *v))
                .collect(),
            error: outcome.error.map(|e| {
                ErrorReport::Signal(match e {
                    ErrorSignal::Code(c) => SignalReport::Code(c),
                    ErrorSignal::Flag(d) => SignalReport::Flag(d.to_string()),
                })
            }),
            value: None,
            text: None,
            accepted: None,
        },
        Ok(Response::Unsupported(reason)) => unsupported(reason),
        Ok(Response::Answer(_)) => unsupported("a codec answer to an instruction request".into()),
        Err(fault) => unsupported(format!("the built-in backend failed: {fault}")),
    }
}
