//! Requests and answers as the protocol writes them: a case turned into its `run` message, and a
//! `result` line turned back into an outcome or a codec answer. Kept apart from the process so
//! that what a backend's answer may say is judged in one place, whatever started the process.

use std::collections::BTreeMap;

use serde::Serialize;

use super::protocol::{
    CaseRequest, ErrorReport, FillName, HarnessMessage, MemoryRange, OperandValue,
    ProtocolViolation, RunCase, SignalReport,
};
use super::window;
use crate::backend::{Outcome, Request};
use crate::device::Device;
use crate::memory::{Fill, Unit, Value};
use crate::model::cross_vendor::Answer;
use crate::model::{ErrorSignal, Operand};

/// How much of an offending line a protocol error quotes.
const QUOTE: usize = 200;

/// The request for one case: everything the backend needs, fill included.
pub(crate) fn case_request(req: &Request<'_>, id: u64) -> CaseRequest {
    let ignored_flags = req
        .variant
        .ignores_flags
        .iter()
        .map(|f| (f.clone(), req.profile.flag_default(f)))
        .collect();
    CaseRequest {
        id,
        case: req.case_id.to_string(),
        instruction: req.instruction.to_string(),
        profile: req.profile.id.clone(),
        variant: req.variant.id.clone(),
        flags: req.all_flags(),
        ignored_flags,
        operands: req
            .operands
            .iter()
            .map(|(k, v)| {
                let value = match (v, req.indirect.get(k)) {
                    (Operand::Device(_), Some(pointer)) => {
                        OperandValue::Device(format!("@{pointer}"))
                    }
                    (Operand::Device(d), None) => OperandValue::Device(d.to_string()),
                    (Operand::Constant(k), _) => OperandValue::Constant(*k),
                };
                (k.clone(), value)
            })
            .collect(),
        addresses: req
            .indirect
            .iter()
            .filter_map(|(name, pointer)| match req.operands.get(name) {
                Some(Operand::Device(d)) => Some((pointer.to_string(), d.to_string())),
                _ => None,
            })
            .collect(),
        fill: match req.memory.fill() {
            Fill::A => FillName::A,
            Fill::B => FillName::B,
        },
        memory: window::memory(req),
        hexadecimal: req.profile.devices.hexadecimal_codes(),
    }
}

/// Turns a `result` into an outcome: every reported word is a write, except words of `memory`
/// that kept their value (an echoed window is not a list of writes).
pub(super) fn outcome(
    case: &CaseRequest,
    unit: Unit,
    memory: Vec<MemoryRange>,
    writes: BTreeMap<String, Value>,
    error: Option<ErrorReport>,
) -> Result<Outcome, ProtocolViolation> {
    let device = |name: &str| {
        case.device(name)
            .map_err(|e| ProtocolViolation(format!("bad device in the answer: {e}")))
    };
    // Only an echoed window needs the words before; a list of writes is taken as it is.
    let before: BTreeMap<Device, Value> = if memory.is_empty() {
        BTreeMap::new()
    } else {
        case.memory
            .iter()
            .filter_map(|r| {
                let start = case.device(&r.start).ok()?;
                Some((start, r.values(unit).ok()?))
            })
            .flat_map(|(d, values)| {
                values
                    .into_iter()
                    .enumerate()
                    .filter_map(move |(i, w)| d.offset(i as u32).map(|d| (d, w)))
            })
            .collect()
    };
    let mut out = Outcome::default();
    // A pointer's words hold the address in the backend's own encoding: not judged.
    let pointers = case.pointer_words();
    // One word given two values in one answer is no answer: which one would count?
    let mut in_memory: BTreeMap<Device, String> = BTreeMap::new();
    for range in memory {
        let start = device(&range.start)?;
        for (i, word) in range.values(unit)?.into_iter().enumerate() {
            let d = start.offset(i as u32).ok_or_else(|| {
                ProtocolViolation(format!(
                    "memory from {start} runs past the last device number"
                ))
            })?;
            if let Some(first) = in_memory.insert(d.clone(), range.start.clone()) {
                return Err(ProtocolViolation(format!(
                    "{d} is given twice in `memory` (in the ranges from {first} and from {})",
                    range.start
                )));
            }
            if before.get(&d) != Some(&word) && !pointers.contains(&d) {
                out.writes.insert(d, word);
            }
        }
    }
    let mut in_writes: BTreeMap<Device, String> = BTreeMap::new();
    for (name, word) in writes {
        let d = device(&name)?;
        if word > unit.max() {
            return Err(ProtocolViolation(format!(
                "`{name}` in `writes` is {word}, past a {} ({} at most)",
                unit.name(),
                unit.max()
            )));
        }
        if let Some(first) = in_writes.insert(d.clone(), name.clone()) {
            return Err(ProtocolViolation(format!(
                "`{first}` and `{name}` in `writes` are the same word, {d}"
            )));
        }
        if !pointers.contains(&d) {
            out.writes.insert(d, word);
        }
    }
    out.error = match error {
        None => None,
        Some(ErrorReport::Signal(SignalReport::Code(c))) => Some(ErrorSignal::Code(c)),
        Some(ErrorReport::Signal(SignalReport::Flag(f))) => Some(ErrorSignal::Flag(device(&f)?)),
        Some(ErrorReport::Class(c)) => {
            return Err(ProtocolViolation(format!(
                "an error class (`{c}`) answers a codec question, not an instruction request"
            )))
        }
    };
    Ok(out)
}

/// A codec answer: exactly one of a value, a text or an error class, and nothing of the
/// instruction level.
pub(super) fn codec_answer(
    memory: Vec<MemoryRange>,
    writes: BTreeMap<String, Value>,
    error: Option<ErrorReport>,
    value: Option<i64>,
    text: Option<Vec<u8>>,
    accepted: Option<bool>,
) -> Result<Answer, ProtocolViolation> {
    if !memory.is_empty() || !writes.is_empty() {
        return Err(ProtocolViolation(
            "`memory` or `writes` in the answer to a codec question".into(),
        ));
    }
    match accepted {
        Some(true) if value.is_none() && text.is_none() && error.is_none() => {
            return Ok(Answer::Accepted)
        }
        Some(true) => {
            return Err(ProtocolViolation(
                "`accepted` and a `value`, `text` or `error` in one codec answer".into(),
            ))
        }
        Some(false) => {
            return Err(ProtocolViolation(
                "`accepted: false` in a codec answer; a mismatch is `\"error\": \"bad-check\"`"
                    .into(),
            ))
        }
        None => {}
    }
    match (value, text, error) {
        // A negative value (some libraries return one) is an answer that differs, not garbage.
        (Some(v), None, None) => Ok(Answer::Value(v as u64)),
        (None, Some(t), None) => Ok(Answer::Text(
            t.into_iter().take_while(|b| *b != 0).collect(),
        )),
        (None, None, Some(ErrorReport::Class(c))) => Ok(Answer::Error(c)),
        (None, None, Some(ErrorReport::Signal(_))) => Err(ProtocolViolation(
            "a vendor's error signal answers a codec question; give an error class".into(),
        )),
        (None, None, None) => Err(ProtocolViolation(
            "no `value`, `text` or `error` in a codec answer".into(),
        )),
        _ => Err(ProtocolViolation(
            "more than one of `value`, `text` and `error` in a codec answer".into(),
        )),
    }
}

pub(super) fn run_message(cases: &[RunCase]) -> Vec<u8> {
    #[derive(Serialize)]
    struct Run<'a> {
        #[serde(rename = "type")]
        kind: &'static str,
        cases: &'a [RunCase],
    }
    // Sized for the usual request, so that neither the encoding nor the newline reallocates.
    let mut out = Vec::with_capacity(cases.len() * 1536 + 64);
    match serde_json::to_writer(&mut out, &Run { kind: "run", cases }) {
        Ok(()) => out,
        Err(_) => Vec::new(),
    }
}

pub(super) fn shutdown_message() -> Vec<u8> {
    serde_json::to_vec(&HarnessMessage::Shutdown).unwrap_or_default()
}

/// A line as a protocol error shows it: lossy UTF-8, cut at [`QUOTE`] characters.
pub(super) fn quote(line: &[u8]) -> String {
    let text = String::from_utf8_lossy(line);
    let mut chars = text.chars();
    let shown: String = chars.by_ref().take(QUOTE).collect();
    if chars.next().is_some() {
        format!("`{shown}`… ({} bytes)", line.len())
    } else {
        format!("`{shown}`")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request() -> CaseRequest {
        CaseRequest {
            id: 1,
            case: "c".into(),
            instruction: "HABIN".into(),
            profile: "mitsubishi-iqr".into(),
            variant: "rcpu".into(),
            flags: BTreeMap::new(),
            ignored_flags: BTreeMap::new(),
            operands: BTreeMap::new(),
            addresses: BTreeMap::new(),
            fill: FillName::A,
            memory: vec![MemoryRange::new("D200".into(), Unit::Word, vec![0, 0])],
            hexadecimal: Vec::new(),
        }
    }

    /// The words of a pointer hold an address the backend encodes its own way: an answer
    /// that echoes them changed, or lists them as writes, says nothing the case can judge.
    #[test]
    fn an_answer_for_the_pointer_words_is_not_judged() {
        let mut case = request();
        case.operands
            .insert("s".into(), OperandValue::Device("@D10".into()));
        case.addresses.insert("D10".into(), "D100".into());
        assert_eq!(
            case.operand_device("@D10"),
            Ok((Device::new("D", 100), Some(Device::new("D", 10))))
        );
        assert!(case.operand_device("@D12").is_err(), "no address for D12");
        let writes = BTreeMap::from([
            ("D10".to_string(), 0x0064),
            ("D11".to_string(), 0),
            ("D12".to_string(), 7),
        ]);
        let out = outcome(&case, Unit::Word, Vec::new(), writes, None).expect("outcome");
        assert_eq!(out.writes, BTreeMap::from([(Device::new("D", 12), 7)]));
        let echoed = vec![
            MemoryRange::new("D10".into(), Unit::Word, vec![0x0064, 0]),
            MemoryRange::new("D200".into(), Unit::Word, vec![0, 5]),
        ];
        let out = outcome(&case, Unit::Word, echoed, BTreeMap::new(), None).expect("outcome");
        assert_eq!(out.writes, BTreeMap::from([(Device::new("D", 201), 5)]));
    }

    /// A code the request lists as hexadecimal is read so in the answer: `W1A` is the word
    /// after `W19`, and `W10` is W 16.
    #[test]
    fn an_answer_names_hexadecimal_devices_as_the_request_does() {
        let mut case = request();
        case.hexadecimal = vec!["W".into()];
        case.memory = vec![MemoryRange::new("W19".into(), Unit::Word, vec![0, 0])];
        let writes = BTreeMap::from([("W1A".to_string(), 7), ("D10".to_string(), 8)]);
        let o = outcome(&case, Unit::Word, Vec::new(), writes, None).expect("an outcome");
        assert_eq!(
            o.writes,
            BTreeMap::from([(Device::hexadecimal("W", 26), 7), (Device::new("D", 10), 8)])
        );
        let echoed = vec![MemoryRange::new("W19".into(), Unit::Word, vec![0, 5])];
        let o = outcome(&case, Unit::Word, echoed, BTreeMap::new(), None).expect("an outcome");
        assert_eq!(
            o.writes,
            BTreeMap::from([(Device::hexadecimal("W", 26), 5)])
        );
        let bad = BTreeMap::from([("W1G".to_string(), 7)]);
        assert!(outcome(&case, Unit::Word, Vec::new(), bad, None).is_err());
    }

    #[test]
    fn one_word_given_two_values_is_no_answer() {
        let range =
            |start: &str, words: Vec<Value>| MemoryRange::new(start.into(), Unit::Word, words);
        let e = outcome(
            &request(),
            Unit::Word,
            vec![range("D200", vec![1, 2]), range("D201", vec![3])],
            BTreeMap::new(),
            None,
        )
        .expect_err("two ranges over D201");
        assert!(e.0.contains("D201 is given twice in `memory`"), "{e}");
        let writes = BTreeMap::from([("D200".to_string(), 1), ("D0200".to_string(), 2)]);
        let e =
            outcome(&request(), Unit::Word, Vec::new(), writes, None).expect_err("D200 and D0200");
        assert!(
            e.0.contains("`D0200` and `D200` in `writes` are the same word, D200"),
            "{e}"
        );
        // `writes` wins over `memory` for a word in both, as documented.
        let writes = BTreeMap::from([("D200".to_string(), 7)]);
        let o = outcome(
            &request(),
            Unit::Word,
            vec![range("D200", vec![1])],
            writes,
            None,
        )
        .expect("ok");
        assert_eq!(o.writes.values().copied().collect::<Vec<_>>(), vec![7]);
    }

    /// A value past what the family's unit holds is no answer, and a range in another unit's
    /// field is refused with the field to use.
    #[test]
    fn a_value_wider_than_the_unit_is_no_answer() {
        let writes = BTreeMap::from([("D200".to_string(), 0x1_0000)]);
        let e = outcome(&request(), Unit::Word, Vec::new(), writes, None).expect_err("17 bits");
        assert!(
            e.0.contains("`D200` in `writes` is 65536, past a word"),
            "{e}"
        );
        let writes = BTreeMap::from([("D200".to_string(), 0x1_0000)]);
        outcome(&request(), Unit::Dword, Vec::new(), writes, None).expect("a 32-bit unit");
        let dwords = MemoryRange::new("D200".into(), Unit::Dword, vec![0x8000_0000]);
        let e = dwords
            .values(Unit::Word)
            .expect_err("dwords in word memory");
        assert!(e
            .0
            .contains("gives `dwords`, but the family's unit is a word: give `words`"));
        assert_eq!(
            dwords.values(Unit::Dword).expect("dwords"),
            vec![0x8000_0000]
        );
    }
}
