//! The fault language of `hil sim --fault`: a rule says which request a simulated CPU answers
//! the way a failing port would, kept apart so that parsing a rule needs no running CPU.

use std::time::Duration;

use crate::backend::bench::error::{refused, LiveError};
use crate::device::Device;

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
