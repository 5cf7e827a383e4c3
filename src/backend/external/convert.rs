//! Version 5: a codec's conversions asked many to a message and answered in one line.
//!
//! A sweep asks a codec millions of texts. Asked one `result` line per case, the helper's
//! writing and the harness's reading of those lines cost many times the codec's own work; a
//! `convert` message of a few thousand texts answered by one `converted` line costs about what
//! the codec does. What a case-by-case exchange gives — the case a crash or a hang happened
//! on — is kept by asking such a message's questions again one case at a time.

use std::time::{Duration, Instant};

use super::process::Next;
use super::protocol::{
    BackendMessage, CodecRequest, Converted, ConvertedError, ConvertedUnsupported, HarnessMessage,
    Latin1, RunCase, CONVERT_VERSION,
};
use super::{closing, next_message, quote, with_stderr, ExternalBackend, State};
use super::{INTERRUPTED, MAX_LINE};
use crate::backend::{Fault, Question, Response};
use crate::model::cross_vendor::{Answer, Operation};

/// Questions per `convert` message for each case of a `run` message: the texts are a few bytes
/// each, where a case is a request with memory.
const ITEMS_PER_CASE: usize = 16;

/// How a `convert` message went.
enum Exchange {
    /// Every question answered.
    Answered(Vec<Result<Response, Fault>>),
    /// The process crashed or hung: asked again one case at a time, which finds the text.
    AskAgain,
    /// A fault the questions would not be asked again for (garbage, an interrupted run).
    Failed(Fault),
}

impl ExternalBackend {
    /// Whether codec questions travel in `convert` messages: the backend speaks version 5 in
    /// one process for the session, and no message has hung or crashed it yet.
    pub(super) fn converts(&self) -> bool {
        self.version >= CONVERT_VERSION
            && self.settings.persistent
            && self.codec.is_some()
            && self.converting.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Answers `questions` through `convert` messages, a message ahead of the one being read so
    /// that both processes stay busy. A message that crashes or hangs the process is asked
    /// again case by case (and `convert` is not used again: a codec slow enough to miss the
    /// time limit of a whole message is asked case by case from then on).
    pub(super) fn convert_all(
        &self,
        questions: &[Question<'_>],
        answered: &mut dyn FnMut(usize),
    ) -> Vec<Result<Response, Fault>> {
        let mut state = match self.state.lock() {
            Ok(s) => s,
            Err(poisoned) => poisoned.into_inner(),
        };
        let size = self.settings.batch.max(1) * ITEMS_PER_CASE;
        let chunks = chunks(questions, size);
        let mut out: Vec<Result<Response, Fault>> = Vec::with_capacity(questions.len());
        let mut queued: Option<u64> = None;
        for (k, chunk) in chunks.iter().enumerate() {
            let done = out.len();
            if !self.converts() {
                out.extend(self.case_by_case(&mut state, chunk, &mut |n| answered(done + n)));
                continue;
            }
            let exchange = match self.live_process(&mut state) {
                Err(fault) => Exchange::Failed(fault),
                Ok(()) => {
                    let id = match queued.take() {
                        Some(id) => id,
                        None => send(&mut state, chunk),
                    };
                    if let Some(next) = chunks.get(k + 1) {
                        queued = Some(send(&mut state, next));
                    }
                    self.read_converted(&mut state, id, chunk)
                }
            };
            match exchange {
                Exchange::Answered(answers) => {
                    state.breaker.answered();
                    out.extend(answers);
                    answered(out.len());
                }
                Exchange::AskAgain => {
                    queued = None;
                    self.converting
                        .store(false, std::sync::atomic::Ordering::Relaxed);
                    out.extend(self.case_by_case(&mut state, chunk, &mut |n| answered(done + n)));
                }
                Exchange::Failed(fault) => {
                    queued = None;
                    out.extend(chunk.iter().map(|_| Err(fault.clone())));
                    answered(out.len());
                }
            }
        }
        out
    }

    /// The questions as `run` cases, through the case-by-case exchange.
    fn case_by_case(
        &self,
        state: &mut State,
        questions: &[Question<'_>],
        answered: &mut dyn FnMut(usize),
    ) -> Vec<Result<Response, Fault>> {
        let first = state.next_id;
        state.next_id += questions.len() as u64;
        let cases: Vec<RunCase> = questions
            .iter()
            .enumerate()
            .map(|(i, q)| codec_case(q, first + i as u64))
            .collect();
        self.run_chunk(state, &cases, false, |_| false, answered).0
    }

    /// The process, started again if a fault ended it; the fault when it cannot be.
    fn live_process(&self, state: &mut State) -> Result<(), Fault> {
        self.start_again(state);
        match &state.down {
            Some(why) => Err(Fault::Unreachable(why.clone())),
            None => Ok(()),
        }
    }

    /// Reads the `converted` line answering message `id`; a fault ends the process.
    fn read_converted(&self, state: &mut State, id: u64, questions: &[Question<'_>]) -> Exchange {
        let Some(process) = state.process.as_mut() else {
            return Exchange::Failed(Fault::Unreachable("the process is not running".into()));
        };
        let mark = process.stderr_mark();
        let which = || {
            format!(
                "convert message {id} ({} questions, cases {} to {})",
                questions.len(),
                questions.first().map_or("", |q| q.case_id),
                questions.last().map_or("", |q| q.case_id),
            )
        };
        let exchange = match next_message(process, Instant::now() + self.settings.timeout) {
            Next::Line(line) => match BackendMessage::from_line(&line) {
                Ok(BackendMessage::Converted {
                    id: theirs,
                    answers,
                }) if theirs == id => match read_answers(questions, answers) {
                    Ok(answers) => return Exchange::Answered(answers),
                    Err(what) => Exchange::Failed(Fault::Protocol(format!(
                        "the answer to {}: {what}",
                        which()
                    ))),
                },
                Ok(_) => Exchange::Failed(Fault::Protocol(format!(
                    "while waiting for the answer to {}: {}",
                    which(),
                    quote(&line)
                ))),
                Err(e) => Exchange::Failed(Fault::Protocol(format!(
                    "the answer to {} is not a protocol message ({e}): {}",
                    which(),
                    quote(&line)
                ))),
            },
            Next::Oversized { head, length } => Exchange::Failed(Fault::Protocol(format!(
                "while waiting for the answer to {}: a line of {length} bytes, over the {} KiB \
                 limit; it starts: {}",
                which(),
                MAX_LINE / 1024,
                quote(&head)
            ))),
            Next::Timeout | Next::Closed(_) if closing() => {
                Exchange::Failed(Fault::Unreachable(INTERRUPTED.into()))
            }
            Next::Timeout | Next::Closed(_) => Exchange::AskAgain,
        };
        if let Some(mut p) = state.process.take() {
            p.kill();
            let stderr = p.stderr_since(mark, Duration::from_millis(300));
            if let Exchange::Failed(fault) = exchange {
                if closing() {
                    state.down = Some(INTERRUPTED.into());
                }
                return Exchange::Failed(with_stderr(fault, &stderr));
            }
        }
        exchange
    }
}

/// Consecutive questions of one operation, at most `size` to a message.
fn chunks<'q, 'a>(questions: &'q [Question<'a>], size: usize) -> Vec<&'q [Question<'a>]> {
    let mut out = Vec::new();
    let mut rest = questions;
    while let Some(first) = rest.first() {
        let n = rest
            .iter()
            .take(size)
            .take_while(|q| q.operation == first.operation)
            .count();
        let (chunk, tail) = rest.split_at(n);
        out.push(chunk);
        rest = tail;
    }
    out
}

/// Sends one `convert` message; returns its id.
fn send(state: &mut State, questions: &[Question<'_>]) -> u64 {
    let id = state.next_id;
    state.next_id += 1;
    let operation = questions
        .first()
        .map_or(Operation::HexToValue, |q| q.operation);
    let text = operation == Operation::HexToValue;
    let message = HarnessMessage::Convert {
        id,
        operation,
        digits: questions.iter().map(|q| q.digits).collect(),
        texts: text.then(|| questions.iter().map(|q| Latin1(q.text.to_vec())).collect()),
        values: (!text).then(|| questions.iter().map(|q| q.value).collect()),
    };
    if let Some(p) = state.process.as_mut() {
        p.send(serde_json::to_vec(&message).unwrap_or_default());
    }
    id
}

/// Why a `converted` line is not the answers to its questions.
#[derive(Debug)]
enum Garbled {
    Count {
        answers: usize,
        questions: usize,
    },
    Kind {
        given: &'static str,
        case: String,
        operation: Operation,
    },
}

impl std::fmt::Display for Garbled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Garbled::Count { answers, questions } => {
                write!(f, "{answers} answers to {questions} questions")
            }
            Garbled::Kind {
                given,
                case,
                operation,
            } => write!(f, "{given} answers {case} ({operation})"),
        }
    }
}

/// The answers of a `converted` line as responses: one per question, each of the kind its
/// operation gives.
fn read_answers(
    questions: &[Question<'_>],
    answers: Vec<Converted>,
) -> Result<Vec<Result<Response, Fault>>, Garbled> {
    if answers.len() != questions.len() {
        return Err(Garbled::Count {
            answers: answers.len(),
            questions: questions.len(),
        });
    }
    questions
        .iter()
        .zip(answers)
        .map(|(q, a)| {
            Ok(Ok(match (q.operation, a) {
                // A negative value (some libraries return one) is an answer that differs.
                (Operation::HexToValue, Converted::Value(v)) => {
                    Response::Answer(Answer::Value(v as u64))
                }
                (Operation::ValueToHex, Converted::Text(Latin1(t))) => Response::Answer(
                    Answer::Text(t.into_iter().take_while(|b| *b != 0).collect()),
                ),
                (_, Converted::Error(ConvertedError { error })) => {
                    Response::Answer(Answer::Error(error))
                }
                (_, Converted::Unsupported(ConvertedUnsupported { unsupported })) => {
                    Response::Unsupported(unsupported)
                }
                (Operation::ValueToHex, Converted::Value(_)) => {
                    return Err(Garbled::Kind {
                        given: "a value",
                        case: q.case_id.to_string(),
                        operation: Operation::ValueToHex,
                    })
                }
                // A `convert` message asks conversions only (`convert_batch`).
                (operation, Converted::Text(_) | Converted::Value(_)) => {
                    return Err(Garbled::Kind {
                        given: "a text",
                        case: q.case_id.to_string(),
                        operation,
                    })
                }
            }))
        })
        .collect()
}

/// A codec question as a `run` case.
pub(super) fn codec_case(q: &Question<'_>, id: u64) -> RunCase {
    RunCase::Codec(CodecRequest {
        id,
        case: q.case_id.to_string(),
        operation: q.operation,
        text: (q.operation != Operation::ValueToHex).then(|| q.text.to_vec()),
        value: (q.operation == Operation::ValueToHex).then_some(q.value),
        digits: q.digits,
        field: (!q.field.is_empty()).then(|| q.field.to_string()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(case_id: &'static str, operation: Operation) -> Question<'static> {
        Question {
            case_id,
            operation,
            text: b"5A8D",
            value: 0x5A8D,
            digits: 4,
            field: "",
        }
    }

    #[test]
    fn a_message_holds_one_operation_and_at_most_its_size() {
        let h = Operation::HexToValue;
        let v = Operation::ValueToHex;
        let qs = [q("a", h), q("b", h), q("c", h), q("d", v), q("e", h)];
        let sizes: Vec<usize> = chunks(&qs, 2).iter().map(|c| c.len()).collect();
        assert_eq!(sizes, [2, 1, 1, 1]);
    }

    #[test]
    fn an_answer_of_the_wrong_kind_or_count_is_garbage() {
        let h = Operation::HexToValue;
        let ok = read_answers(
            &[q("a", h), q("b", h)],
            vec![
                Converted::Value(0x5A8D),
                Converted::Error(ConvertedError {
                    error: crate::model::cross_vendor::ErrorClass::InvalidDigit,
                }),
            ],
        )
        .expect("answers");
        assert!(matches!(ok[0], Ok(Response::Answer(Answer::Value(0x5A8D)))));
        let wrong = read_answers(&[q("a", h)], vec![Converted::Text(Latin1(b"5A".to_vec()))]);
        assert!(wrong.unwrap_err().to_string().contains("a text answers a"));
        let short = read_answers(&[q("a", h), q("b", h)], vec![Converted::Value(1)]);
        assert!(short
            .unwrap_err()
            .to_string()
            .contains("1 answers to 2 questions"));
    }

    #[test]
    fn a_text_travels_one_character_per_byte() {
        let line = serde_json::to_string(&Latin1(vec![b'5', 0x00, 0xE9, 0x7F])).expect("json");
        assert_eq!(line, "\"5\\u0000\u{e9}\u{7f}\"");
        let back: Latin1 = serde_json::from_str(&line).expect("back");
        assert_eq!(back.0, vec![b'5', 0x00, 0xE9, 0x7F]);
        assert!(serde_json::from_str::<Latin1>("\"\u{100}\"").is_err());
    }
}
