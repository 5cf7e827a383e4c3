//! The sweep's white-box tests: deterministic from their seed, shrinking to minimal inputs that
//! still differ, split into shards whose union is the whole, stopped cleanly by the stop flag,
//! catching mutants no hand-written vector targets, and its rules equal to its models. The tests
//! that run the command line (emitting, merging, judged codecs, Ctrl-C) stay in `tests/sweep.rs`.
//!
//! The exhaustive tests (a whole space, the byte classes of every lowering derived) are ignored
//! under a plain `cargo test`, which stays about a minute: CI runs them,
//! `cargo test --lib --test sweep --test readme -- --ignored`.

#[cfg(test)]
use crate::test_support::{failing_trials, python, reference, root, session, xml_elements, Mutant};
use std::collections::BTreeSet;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::session::{BackendSource, Session};
use crate::sweep::classes::ByteClasses;
use crate::sweep::generate::{Digits, Generator};
use crate::sweep::group::{labels, Groups, Reply};
use crate::sweep::input::{Data, Point};
use crate::sweep::shrink::candidates;
use crate::sweep::target::Target;
use crate::sweep::{exhaustive, render, Results, Settings, Sweep};
use crate::Image;
use crate::Operation;
use crate::{Backend, Request};

fn no_stop() -> AtomicBool {
    AtomicBool::new(false)
}

fn operation(op: Operation) -> Target {
    Target::Operation { operation: op }
}

fn instruction(profile: &str, name: &str) -> Target {
    Target::Instruction {
        profile: profile.into(),
        instruction: name.into(),
    }
}

/// A random sweep of `op`, not shrunk.
fn random(op: Operation, count: u64, max_len: u32, seed: u64) -> Settings {
    let mut settings = Settings::new(operation(op), Generator::Random { count, max_len }, seed);
    settings.shrink = 0;
    settings
}

fn run(project: &Session, backends: &[Arc<dyn Backend>], settings: Settings) -> (Sweep, Results) {
    let sweep = Sweep::new(settings, &project.profiles, backends).expect("sweep sets up");
    let results = sweep.run(&no_stop(), &mut |_, _| {});
    (sweep, results)
}

/// What a run found, without its timing.
fn summary(r: &Results) -> Vec<String> {
    let mut out: Vec<String> = r
        .ordered()
        .iter()
        .map(|g| {
            format!(
                "{:?} {:?} {} {} {}",
                g.key.signature,
                g.key.features,
                g.inputs,
                g.representative.index,
                g.classes.len()
            )
        })
        .collect();
    out.extend(
        r.shrunk
            .iter()
            .map(|s| format!("{} -> {}", s.from.point, s.to.point)),
    );
    out
}

/// A mutant of a reference model that reads every byte `from` of the source as `to`.
fn reads_byte_as(
    name: &'static str,
    base: &Arc<dyn Backend>,
    instructions: &'static [&'static str],
    rewrite: fn(u16) -> u16,
) -> Arc<dyn Backend> {
    Mutant::new(name, base, move |req: &Request<'_>, base: &dyn Backend| {
        if !instructions.contains(&req.instruction) {
            return base.execute(req);
        }
        let words = req
            .memory
            .explicit()
            .iter()
            .map(|(d, w)| (d.clone(), u32::from(rewrite(*w as u16))))
            .collect();
        let image = Image::new(words, req.memory.fill());
        base.execute(&Request {
            memory: &image,
            ..*req
        })
    })
}

fn tilde_as_zero(w: u16) -> u16 {
    let [lo, hi] = w.to_le_bytes();
    let f = |b: u8| if b == b'~' { b'0' } else { b };
    u16::from_le_bytes([f(lo), f(hi)])
}

#[test]
fn the_same_seed_gives_the_same_results() {
    let project = session();
    let mut settings = Settings::new(
        operation(Operation::HexToValue),
        Generator::Random {
            count: 1000,
            max_len: 6,
        },
        11,
    );
    settings.jobs = 2;
    let (_, a) = run(&project, &project.backends, settings.clone());
    settings.jobs = 1;
    let (_, b) = run(&project, &project.backends, settings.clone());
    assert_eq!(summary(&a), summary(&b));
    settings.seed = 12;
    let (_, c) = run(&project, &project.backends, settings);
    assert_ne!(summary(&a), summary(&c), "another seed, other inputs");
}

/// A shrink step asks its candidates simplest first and in batches, stopping at the first
/// batch that holds one that behaves the same: the step is still the one asking them all would
/// take, the simplest that behaves the same, step after step.
#[test]
fn a_shrink_step_is_the_simplest_candidate_that_behaves_the_same() {
    let project = session();
    let mut settings = random(Operation::HexToValue, 300, 8, 3);
    settings.shrink = 2;
    let (sweep, results) = run(&project, &project.backends, settings);
    assert!(results.shrunk.len() > 10, "{}", results.shrunk.len());
    let counted = sweep.counted();
    let behaviour = |p: &Point, r: &[Reply]| (labels(r), p.features(counted));
    for s in &results.shrunk {
        let wanted = behaviour(&s.from.point, &s.from.replies);
        let mut here = s.from.point.clone();
        loop {
            let simpler: Vec<(u64, Point)> = candidates(&here, counted)
                .into_iter()
                .filter(|p| p.simplicity() < here.simplicity())
                .map(|p| (0, p))
                .collect();
            let answers = sweep.answers(&simpler, &no_stop());
            let step = (simpler.into_iter().zip(answers))
                .filter_map(|((_, p), r)| (behaviour(&p, &r?) == wanted).then_some(p))
                .min_by_key(Point::simplicity);
            match step {
                Some(p) => here = p,
                None => break,
            }
        }
        assert_eq!(here, s.to.point, "shrunk from {}", s.from.point);
    }
}

#[test]
fn the_shards_of_a_sweep_are_the_whole_sweep() {
    let project = session();
    let mut settings = random(Operation::ValueToHex, 2000, 0, 3);
    let (_, whole) = run(&project, &project.backends, settings.clone());
    let mut merged = Groups::new(settings.max_classes);
    let mut swept = 0;
    for k in 1..=3 {
        settings.shard = (k, 3);
        let (_, part) = run(&project, &project.backends, settings.clone());
        swept += part.swept;
        merged.merge(part.groups);
    }
    assert_eq!(swept, whole.swept);
    let count = |g: &Groups| -> BTreeSet<String> {
        g.by_key
            .values()
            .map(|g| {
                format!(
                    "{:?} {:?} {} {}",
                    g.key,
                    g.inputs,
                    g.representative.index,
                    g.classes.len()
                )
            })
            .collect()
    };
    assert_eq!(count(&merged), count(&whole.groups));
}

#[test]
fn a_stopped_sweep_reports_what_it_found() {
    let project = session();
    let settings = Settings::new(
        operation(Operation::HexToValue),
        Generator::Random {
            count: 300_000,
            max_len: 5,
        },
        9,
    );
    let sweep = Sweep::new(settings, &project.profiles, &project.backends).expect("sweep");
    let stop = AtomicBool::new(false);
    let results = sweep.run(&stop, &mut |done, _| {
        if done > 0 {
            stop.store(true, Ordering::Relaxed);
        }
    });
    assert!(results.interrupted);
    assert!(results.swept > 0 && results.swept < results.shard_inputs);
    let found: u64 = results.groups.by_key.values().map(|g| g.inputs).sum();
    assert_eq!(found, results.swept);
    assert!(render::text(&results).contains("(interrupted)"));
}

/// A round holds a bounded amount of text, not a fixed count of inputs: with texts of up to a
/// million bytes, a stop set after the first round leaves most of a 200-input sweep unasked
/// (rounds of 65,536 inputs asked all 200 before the stop was read).
#[test]
fn a_stop_is_honoured_within_a_round_of_long_texts() {
    let project = session();
    let settings = random(Operation::HexToValue, 200, 1_000_000, 3);
    let sweep = Sweep::new(settings, &project.profiles, &project.backends).expect("sweep");
    let stop = AtomicBool::new(false);
    let mut rounds = 0;
    let results = sweep.run(&stop, &mut |done, _| {
        if done > 0 {
            rounds += 1;
            stop.store(true, Ordering::Relaxed);
        }
    });
    assert!(results.interrupted);
    assert_eq!(rounds, 1);
    assert!(
        results.swept > 0 && results.swept < 50,
        "{} of 200 inputs swept in the first round",
        results.swept
    );
}

/// The cross-vendor corpus's behaviours, as the built-in models give them.
fn corpus_behaviours(project: &Session, op: Operation) -> BTreeSet<Vec<String>> {
    let generator = match op {
        Operation::HexToValue => Generator::Random {
            count: 1,
            max_len: 1,
        },
        _ => Generator::Values { bits: 16 },
    };
    let settings = Settings::new(operation(op), generator, 0);
    let sweep = Sweep::new(settings, &project.profiles, &project.backends).expect("sweep");
    let points: Vec<(u64, Point)> = project
        .corpus
        .cross_vendor
        .iter()
        .filter(|c| c.operation == op)
        .map(|c| match op {
            Operation::HexToValue => (0, Point::text(&c.text, c.digits)),
            _ => (0, Point::value(c.value, c.digits)),
        })
        .collect();
    sweep
        .answers(&points, &no_stop())
        .into_iter()
        .map(|r| labels(&r.expect("answered")))
        .collect()
}

#[test]
#[ignore = "exhaustive: sweeps every text of up to 5 characters of 7 kinds (CI runs it: -- --ignored)"]
fn a_sweep_of_the_built_in_models_finds_every_behaviour_of_the_cross_vendor_corpus() {
    let project = session();
    let sweeps = [
        (
            Operation::HexToValue,
            vec![
                // Each kind of character around the digits, up to five of them, with every
                // count.
                (
                    Generator::Text {
                        alphabet: b"\x00/0A8fG".to_vec(),
                        max_len: 5,
                    },
                    Digits::Each((0..=6).collect()),
                ),
                // Six characters: an even count past four digits is where S7 ATH (two
                // characters a byte) meets FX5 HEXA; a digit, a letter, an invalid character
                // and the terminator are enough there.
                (
                    Generator::Text {
                        alphabet: b"\x000AG".to_vec(),
                        max_len: 6,
                    },
                    Digits::Each((0..=6).collect()),
                ),
                // Eight digits of two kinds: where Panasonic F72's whole words (an even number
                // of bytes) read byte-swapped past four digits.
                (
                    Generator::Text {
                        alphabet: b"0A".to_vec(),
                        max_len: 8,
                    },
                    Digits::Each(vec![8]),
                ),
            ],
        ),
        (
            Operation::ValueToHex,
            vec![(
                Generator::Values { bits: 16 },
                Digits::Each((0..=6).collect()),
            )],
        ),
    ];
    for (op, runs) in sweeps {
        let mut found: BTreeSet<Vec<String>> = BTreeSet::new();
        let mut groups = Vec::new();
        for (generator, digits) in runs {
            let mut settings = Settings::new(operation(op), generator, 1);
            settings.digits = digits;
            settings.shrink = 0;
            let (_, results) = run(&project, &project.backends, settings);
            found.extend(results.groups.by_key.keys().map(|k| k.signature.clone()));
            groups.extend(results.ordered().into_iter().map(|g| {
                (
                    g.inputs,
                    g.key.signature.clone(),
                    g.representative.point.to_string(),
                )
            }));
        }
        let wanted = corpus_behaviours(&project, op);
        let missing: Vec<_> = wanted.difference(&found).collect();
        assert!(
            missing.is_empty(),
            "{op}: not found by the sweep: {missing:?}"
        );
        assert!(
            found.len() > wanted.len(),
            "{op}: nothing beyond the corpus"
        );
        for (inputs, signature, example) in groups {
            if !wanted.contains(&signature) {
                eprintln!("{op}: beyond the corpus: {inputs} inputs {signature:?}, e.g. {example}");
            }
        }
    }
}

#[test]
fn a_bounded_sweep_catches_mutants_the_corpus_does_not_target() {
    let project = session();
    let cases = [
        (
            "mitsubishi-iqr",
            "HABIN",
            reads_byte_as(
                "habin-reads-7eh-as-0",
                &reference(&project, "mitsubishi-iqr"),
                &["HABIN", "HABINP"],
                tilde_as_zero,
            ),
        ),
        (
            "mitsubishi-fx5",
            "HEXA",
            reads_byte_as(
                "hexa-reads-7eh-as-0",
                &reference(&project, "mitsubishi-fx5"),
                &["HEXA", "HEXAP"],
                tilde_as_zero,
            ),
        ),
        (
            "idec-fc4a",
            "ATOH",
            reads_byte_as(
                "atoh-reads-7eh-as-0",
                &reference(&project, "idec-fc4a"),
                &["ATOH"],
                tilde_as_zero,
            ),
        ),
    ];
    for (profile, name, mutant) in cases {
        assert!(
            failing_trials(&project, &mutant).is_empty(),
            "{}: the corpus already catches it; pick a mutant it does not target",
            mutant.name()
        );
        let mut settings = Settings::new(
            instruction(profile, name),
            Generator::Random {
                count: 20_000,
                max_len: 6,
            },
            1,
        );
        settings.shrink = 1;
        let (_, results) = run(
            &project,
            &[reference(&project, profile), mutant.clone()],
            settings,
        );
        assert!(results.differs(), "{} survives the sweep", mutant.name());
        let shown: Vec<String> = results
            .shrunk
            .iter()
            .map(|s| s.to.point.to_string())
            .collect();
        eprintln!("{}: caught; shrunk to {shown:?}", mutant.name());
    }
}

/// The built-in models asked directly answer exactly what they answer as trials.
#[test]
fn the_direct_path_gives_the_replies_of_the_trial_path() {
    let project = session();
    for (target, generator) in [
        (
            operation(Operation::HexToValue),
            Generator::Random {
                count: 3000,
                max_len: 9,
            },
        ),
        (
            operation(Operation::ValueToHex),
            Generator::Random {
                count: 3000,
                max_len: 0,
            },
        ),
        (
            instruction("mitsubishi-iqr", "DHABIN"),
            Generator::Random {
                count: 2000,
                max_len: 10,
            },
        ),
        (
            instruction("mitsubishi-iqr", "BINHA"),
            Generator::Random {
                count: 2000,
                max_len: 0,
            },
        ),
        (
            instruction("mitsubishi-fx5", "HEXA"),
            Generator::Random {
                count: 2000,
                max_len: 9,
            },
        ),
        (
            instruction("mitsubishi-fx5", "ASCI"),
            Generator::Random {
                count: 2000,
                max_len: 0,
            },
        ),
        (
            instruction("idec-fc4a", "ATOH"),
            Generator::Random {
                count: 2000,
                max_len: 6,
            },
        ),
        (
            instruction("idec-fc4a", "HTOA"),
            Generator::Random {
                count: 2000,
                max_len: 0,
            },
        ),
    ] {
        let mut settings = Settings::new(target.clone(), generator, 4);
        // A codec too (in process here; one in another process is asked the same way).
        let mut backends = project.backends.clone();
        backends.push(crate::codec_backend(Lenient));
        let direct = Sweep::new(settings.clone(), &project.profiles, &backends).expect("sweep");
        settings.direct = false;
        let trials = Sweep::new(settings, &project.profiles, &backends).expect("sweep");
        let points: Vec<(u64, Point)> = (0..direct.space.total())
            .map(|i| (i, direct.space.point(i)))
            .collect();
        let a = direct.answers(&points, &no_stop());
        let b = trials.answers(&points, &no_stop());
        for ((i, p), (x, y)) in points.iter().zip(a.iter().zip(&b)) {
            assert_eq!(x, y, "{target}: input {i}, {p}");
        }
    }
}

/// The group whose signature is `signature`, column by column.
fn inputs_with(r: &Results, signature: &[&str]) -> u64 {
    r.groups
        .by_key
        .values()
        .filter(|g| g.key.signature == signature)
        .map(|g| g.inputs)
        .sum()
}

/// A full sweep of hex-to-value, text by text or (`by_class`) class by class, from `seed`,
/// shrinking `shrink` steps.
fn full(by_class: bool, seed: u64, shrink: usize) -> Settings {
    let mut settings = Settings::new(
        operation(Operation::HexToValue),
        Generator::Full { by_class },
        seed,
    );
    settings.shrink = shrink;
    settings
}

fn full_by_class(check: u64) -> Settings {
    let mut settings = full(true, 5, 0);
    settings.class_check = check;
    settings
}

#[test]
#[ignore = "exhaustive: sweeps all 2^32 texts by class (CI runs it: -- --ignored)"]
fn the_full_sweep_by_class_counts_every_four_byte_text_exactly() {
    let project = session();
    // The families whose groups are counted by hand below; others only add columns.
    let counted = [
        "mitsubishi-iqr",
        "mitsubishi-fx5",
        "idec-fc4a",
        "siemens-s7-1200",
        "omron-cs-cj",
    ];
    let backends: Vec<_> = project
        .backends
        .iter()
        .filter(|b| counted.contains(&b.profile()))
        .cloned()
        .collect();
    let (sweep, r) = run(&project, &backends, full_by_class(1 << 16));
    let classes = r
        .classes
        .as_ref()
        .expect("a sweep by class reports its classes");
    assert!(classes.mismatch.is_none(), "{:?}", classes.mismatch);
    assert_eq!(classes.checked, 1 << 16);
    // 26 kinds of byte, with lowercase a-f split into its six letters: the S7-1200 ATH reads
    // each as a digit of its own value.
    assert_eq!(classes.classes.len(), 31, "{:?}", classes.classes);
    assert_eq!(classes.tuples, 31u64.pow(4));
    assert_eq!(r.swept, 1 << 32);
    assert_eq!(
        r.groups.by_key.values().map(|g| g.inputs).sum::<u64>(),
        1 << 32
    );
    let names: Vec<&str> = sweep.columns.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "iqr/habin-fixed",
            "iqr/habin-terminated",
            "fx5/hexa-16bit",
            "fx5/hexa-8bit",
            "fc4a/atoh",
            "s7/ath",
            "omron/hex"
        ]
    );
    // Counted by hand: every text of four hex digits, and every text that HABIN with SM705 on
    // ends at a 00H after one to three digits (whatever follows the 00H; S7 ATH reads the 00H
    // as an invalid character, converts it as 0 and goes on). Omron HEX reads the text back to front: it agrees on the 16 * 16
    // texts that read the same both ways, and gives another value for the rest.
    assert_eq!(inputs_with(&r, &["value#1"; 7]), 16 * 16);
    let mut reversed = ["value#1"; 7];
    reversed[6] = "value#2";
    assert_eq!(inputs_with(&r, &reversed), 16u64.pow(4) - 16 * 16);
    assert_eq!(
        inputs_with(
            &r,
            &[
                "invalid-digit",
                "value#1",
                "invalid-digit",
                "invalid-digit",
                "error",
                "invalid-digit and value#1",
                "error"
            ]
        ),
        16 * 256 * 256 + 16 * 16 * 256 + 16 * 16 * 16
    );
}

#[test]
fn classes_that_do_not_hold_fail_their_check() {
    let project = session();
    // 00H put with the control characters: HABIN with SM705 on tells them apart.
    let iqr = [reference(&project, "mitsubishi-iqr")];
    let mut sweep = Sweep::new(full_by_class(1 << 14), &project.profiles, &iqr).expect("sweep");
    let mut classes: Vec<Vec<u8>> = ByteClasses::by_kind().classes().to_vec();
    let nul = classes.iter().position(|c| c == &[0]).expect("00H alone");
    classes.remove(nul);
    classes
        .iter_mut()
        .find(|c| c.contains(&1))
        .expect("control")
        .push(0);
    sweep.space.classes = Some(Arc::new(ByteClasses::new(classes).expect("a partition")));
    let r = sweep.run(&no_stop(), &mut |_, _| {});
    let report = r.classes.as_ref().expect("reported");
    let m = report
        .mismatch
        .as_ref()
        .expect("the check finds a text unlike its class");
    assert_ne!(m.text.replies, m.representative.replies);
    assert!(render::text(&r).contains("CHECK FAILED"));
}

#[test]
fn a_column_that_reads_one_byte_apart_splits_its_class() {
    let project = session();
    let iqr = reference(&project, "mitsubishi-iqr");
    let mutant = reads_byte_as("tilde-as-zero", &iqr, &["HABIN"], tilde_as_zero);
    let backends = vec![iqr, mutant];
    let sweep = Sweep::new(full_by_class(1 << 12), &project.profiles, &backends).expect("sweep");
    let (classes, asked) = crate::sweep::classes::derive(&sweep, &no_stop()).expect("not stopped");
    assert!(asked > 0);
    assert!(
        classes.classes().contains(&vec![b'~']),
        "{:?}",
        classes.describe()
    );
    assert!(!classes
        .classes()
        .iter()
        .any(|c| c.len() > 1 && c.contains(&b'~')));
    assert_eq!(classes.len(), 27);
}

#[test]
fn the_html_results_are_a_well_formed_report_page_with_every_group() {
    let project = session();
    let (_, r) = run(
        &project,
        &project.backends,
        random(Operation::HexToValue, 2000, 6, 4),
    );
    let html = render::html(&r);
    let elements = xml_elements(html.trim_start_matches("<!DOCTYPE html>\n"));
    let rows = elements.iter().filter(|(n, _)| n == "tr").count();
    assert_eq!(
        rows,
        r.groups.by_key.len() + 1,
        "a header and a row per group"
    );
    assert!(elements
        .iter()
        .any(|(n, a)| n == "table" && a.iter().any(|(k, v)| k == "id" && v == "groups")));
    assert!(elements
        .iter()
        .all(|(n, _)| !matches!(n.as_str(), "script" | "link" | "img" | "iframe")));
    assert!(html.contains("<style>"), "the report's own style");
}

#[test]
#[ignore = "exhaustive: sweeps all 2^33 HABIN inputs by class (CI runs it: -- --ignored)"]
fn a_full_sweep_by_class_of_an_instruction_covers_every_flag_setting() {
    let project = session();
    let mut settings = full_by_class(1 << 14);
    settings.target = instruction("mitsubishi-iqr", "HABIN");
    let (_, r) = run(&project, &project.backends, settings);
    let classes = r.classes.as_ref().expect("by class");
    assert!(classes.mismatch.is_none(), "{:?}", classes.mismatch);
    assert_eq!(r.swept, 2 << 32, "every text under SM705 off and on");
    let pairs = render::pairs(&r);
    assert_eq!(pairs.len(), 1, "{pairs:?}");
    // Only SM705 on tells the variants apart: a 00H after one to three digits.
    assert_eq!(
        pairs[0].inputs,
        16 * 256 * 256 + 16 * 16 * 256 + 16 * 16 * 16
    );
}

/// Each built-in hex-to-value lowering's rule ([`exhaustive::answer`]) is what its model answers
/// through the plan's lowering: on every 4-byte text over the class boundaries and on random
/// texts, the same value, or an error where the model errs — always the same error per lowering
/// — or, for S7-1200 ATH, the error with the value it writes all the same.
#[test]
fn the_lowerings_rules_are_their_models_answers() {
    let project = session();
    let settings = full(false, 1, 0);
    let sweep = Sweep::new(settings, &project.profiles, &project.backends).expect("sweep");
    let rules: Vec<exhaustive::Rule> = sweep
        .columns
        .iter()
        .map(|c| {
            let key = c.name.as_str();
            exhaustive::rule(key).unwrap_or_else(|| panic!("{key} has no rule"))
        })
        .collect();
    let alphabet = crate::sweep::generate::BOUNDARIES;
    let mut texts: Vec<[u8; 4]> = Vec::new();
    for a in alphabet {
        for b in alphabet {
            for c in alphabet {
                for d in alphabet {
                    texts.push([a, b, c, d]);
                }
            }
        }
    }
    let mut x = 0x2545_F491_4F6C_DD1Du64;
    for _ in 0..200_000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        texts.push((x as u32).to_be_bytes());
    }
    let points: Vec<(u64, Point)> = texts
        .iter()
        .enumerate()
        .map(|(i, t)| (i as u64, Point::text(t, 4)))
        .collect();
    let mut errors: Vec<Option<crate::sweep::group::Reply>> = vec![None; sweep.columns.len()];
    let mut seen_error = vec![false; sweep.columns.len()];
    for (chunk, answers) in points
        .chunks(1 << 16)
        .map(|c| (c, sweep.answers(c, &no_stop())))
    {
        for ((_, point), replies) in chunk.iter().zip(answers) {
            let replies = replies.expect("answered");
            let Data::Text(t) = &point.data else {
                unreachable!()
            };
            let text: [u8; 4] = t.as_slice().try_into().expect("4 bytes");
            for (c, reply) in replies.iter().enumerate() {
                let code = exhaustive::answer(rules[c], text);
                assert!(
                    exhaustive::agrees(code, reply),
                    "{}: {point}: the rule says {code:#x}, the model {reply}",
                    sweep.columns[c].name
                );
                if code >= exhaustive::ERROR {
                    seen_error[c] = true;
                }
                if code == exhaustive::ERROR {
                    let first = errors[c].get_or_insert_with(|| reply.clone());
                    assert_eq!(first, reply, "{}: two errors", sweep.columns[c].name);
                }
            }
        }
    }
    assert!(seen_error.iter().all(|s| *s));
}

/// Every text of a shard asked through the rules gives exactly the results of asking each
/// through the models: the same groups, counts, first inputs and classes.
#[test]
#[ignore = "exhaustive: derives the byte classes of 14 columns twice (CI runs it: -- --ignored)"]
fn each_text_through_the_rules_is_each_text_through_the_models() {
    let project = session();
    let mut settings = full(false, 1, 1);
    settings.shard = (5, 1 << 15);
    let (_, fast) = run(&project, &project.backends, settings.clone());
    settings.exhaustive = false;
    let (_, slow) = run(&project, &project.backends, settings);
    let report = fast.exhaustive.as_ref().expect("asked through the rules");
    assert!(report.disagreement.is_none());
    assert!(slow.exhaustive.is_none());
    assert_eq!(fast.swept, 1 << 17);
    assert_eq!(fast.swept, slow.swept);
    assert_eq!(summary(&fast), summary(&slow));
    let classes = |r: &Results| -> Vec<String> {
        r.ordered()
            .iter()
            .flat_map(|g| {
                g.classes_by_size()
                    .into_iter()
                    .map(|c| format!("{} {} {}", c.name, c.inputs, c.first.index))
                    .collect::<Vec<_>>()
            })
            .collect()
    };
    assert_eq!(classes(&fast), classes(&slow));
}

/// A model that no longer answers as its rule (here, the FX5 model reading `~` as `0`, standing
/// in as the FX5 reference model) is caught by the check of an each-text sweep: the first text
/// of a tuple asked through the models is not answered as the rules said.
#[test]
#[ignore = "exhaustive: derives the byte classes of 14 columns (CI runs it: -- --ignored)"]
fn a_model_unlike_its_rule_stops_an_each_text_sweep() {
    let project = session();
    let mutant = reads_byte_as(
        "fx5",
        &reference(&project, "mitsubishi-fx5"),
        &["HEXA", "HEXAP"],
        tilde_as_zero,
    );
    let backends: Vec<Arc<dyn Backend>> = project
        .backends
        .iter()
        .map(|b| {
            if b.name() == "fx5" {
                mutant.clone()
            } else {
                b.clone()
            }
        })
        .collect();
    let mut settings = full(false, 1, 0);
    settings.shard = (1, 4096);
    let (_, r) = run(&project, &backends, settings);
    let report = r.exhaustive.as_ref().expect("asked through the rules");
    let found = report.disagreement.as_ref().expect("the check catches it");
    let Data::Text(t) = &found.point.data else {
        unreachable!()
    };
    assert!(t.contains(&b'~'), "{}", found.point);
}

/// A codec written in Rust that parts from the vendors in every way a code can: lowercase
/// accepted, `unsupported` for texts opening with `Z`, a text (no value) for `~~~~`, and a
/// blank-skipping field that skips texts with a blank between pairs; and it writes values
/// without leading zeros.
struct Lenient;

impl crate::Codec for Lenient {
    fn name(&self) -> &str {
        "lenient"
    }
    fn abilities(&self) -> crate::CodecAbilities {
        let mut field = crate::OperationAbilities {
            digits: Some(vec![4]),
            ..Default::default()
        };
        let write = field.clone();
        field.shape.blanks_between_pairs = true;
        crate::CodecAbilities {
            hex_to_value: Some(field),
            value_to_hex: Some(write),
            ..Default::default()
        }
    }
    fn convert(&self, q: &crate::Question<'_>) -> Result<crate::Answer, crate::Unsupported> {
        use crate::{Answer, ErrorClass, Operation, Unsupported};
        if q.operation == Operation::ValueToHex {
            // No leading zeros, though the field does not say so.
            return Ok(Answer::Text(format!("{:X}", q.value).into_bytes()));
        }
        if q.text.first() == Some(&b'Z') {
            return Err(Unsupported("no Z".into()));
        }
        if q.text == b"~~~~" {
            return Ok(Answer::Text(b"?".to_vec()));
        }
        Ok(std::str::from_utf8(q.text)
            .ok()
            .and_then(|t| u16::from_str_radix(t, 16).ok())
            .map_or(Answer::Error(ErrorClass::InvalidDigit), |v| {
                Answer::Value(u64::from(v))
            }))
    }
}

/// A codec in process sweeps every text at its own speed (each text a `convert` call, tallied
/// with the rules), with exactly the groups, counts, first inputs and classes of asking each text
/// through the general path; and a codec whose answer no tuple can share (a text) keeps those
/// texts apart rather than counting them with their tuple.
#[test]
#[ignore = "exhaustive: derives the byte classes of 15 columns twice (CI runs it: -- --ignored)"]
fn a_codec_in_process_sweeps_each_text_as_the_general_path_does() {
    let project = session();
    let mut backends = project.backends.clone();
    backends.push(crate::codec_backend(Lenient));
    let mut settings = full(false, 1, 1);
    // The shard that holds "~~~~", the one text answered with a text.
    let tilde = u64::from(exhaustive::unscramble(u32::from_be_bytes(*b"~~~~")));
    settings.shard = (tilde % (1 << 15) + 1, 1 << 15);
    let (_, fast) = run(&project, &backends, settings.clone());
    settings.exhaustive = false;
    let (_, slow) = run(&project, &backends, settings.clone());
    let report = fast
        .exhaustive
        .as_ref()
        .expect("asked through the rules and the codec");
    assert!(report.apart >= 1, "{report:?}");
    assert!(report.disagreement.is_none());
    assert!(slow.exhaustive.is_none());
    assert_eq!(fast.swept, slow.swept);
    assert_eq!(summary(&fast), summary(&slow));
    let lenient = |r: &Results| -> BTreeSet<String> {
        r.ordered()
            .iter()
            .map(|g| g.key.signature.last().cloned().unwrap_or_default())
            .collect()
    };
    for label in [
        "value#1",
        "invalid-digit",
        "skipped",
        "unsupported",
        "text#",
    ] {
        assert!(
            lenient(&fast).iter().any(|l| l.starts_with(label)),
            "{label}: {:?}",
            lenient(&fast)
        );
    }
}

/// The reply of `backend`, alone in a hex-to-value sweep, to each text with a count of 4,
/// asked directly.
fn replies_to(
    project: &Session,
    backend: Arc<dyn Backend>,
    texts: &[&[u8]],
) -> Vec<crate::sweep::group::Reply> {
    let sweep = Sweep::new(
        random(Operation::HexToValue, 10, 4, 1),
        &project.profiles,
        &[backend],
    )
    .expect("sweep");
    let points: Vec<(u64, Point)> = texts
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let mut p = sweep.space.point(0);
            p.data = Data::Text(t.to_vec());
            p.digits = 4;
            (i as u64, p)
        })
        .collect();
    sweep
        .answers(&points, &no_stop())
        .into_iter()
        .map(|r| r.and_then(|r| r.last().cloned()).expect("answered"))
        .collect()
}

/// A codec that crashes or hangs on one text of a bulk `convert` message faults on that text
/// alone: the message's questions are asked again one case at a time, so every other text is
/// answered and the fault is the outcome of the text that caused it.
#[test]
fn a_codec_that_crashes_or_hangs_on_one_text_of_a_bulk_message_faults_that_text_alone() {
    use crate::model::project::{ExternalSettings, Launch};
    use crate::sweep::group::Reply;
    if !python() {
        return;
    }
    let script = root().join("tests/fixtures/external/faulty_codec.py");
    let texts: [&[u8]; 6] = [b"5A8D", b"1G34", b"0000", b"5a8D", b"12G4", b"FFFF"];
    for (mode, label) in [("crash-on-g", "crashed"), ("hang-on-g", "timeout")] {
        let mut project = session();
        let mut settings = ExternalSettings::new(
            "faulty",
            Launch::Exec(vec![
                "python3".into(),
                script.display().to_string(),
                mode.into(),
            ]),
        );
        // The hang costs this once for the message and once for each text holding a G.
        settings.timeout = std::time::Duration::from_secs(2);
        let codec = project
            .add(BackendSource::Process(settings), false)
            .expect("the codec starts")[0]
            .clone();
        let replies = replies_to(&project, codec, &texts);
        for (text, reply) in texts.iter().zip(&replies) {
            let shown = String::from_utf8_lossy(text);
            match reply {
                Reply::Failed { label: l, .. } => {
                    assert!(
                        text.contains(&b'G') && l == label,
                        "{mode}: {shown}: {reply}"
                    )
                }
                _ => assert!(!text.contains(&b'G'), "{mode}: {shown}: {reply}"),
            }
        }
        let shown: Vec<String> = replies.iter().map(ToString::to_string).collect();
        assert_eq!(
            shown,
            ["5A8DH", label, "0000H", "invalid-digit", label, "FFFFH"],
            "{mode}"
        );
    }
}

/// A codec in process that panics on a question has crashed on that case, as a process that
/// exits would have: the other questions are answered, in a sweep as in a run.
#[test]
fn a_codec_in_process_that_panics_has_crashed_on_that_case() {
    use crate::sweep::group::Reply;
    struct Panicky;
    impl crate::Codec for Panicky {
        fn name(&self) -> &str {
            "panicky"
        }
        fn abilities(&self) -> crate::CodecAbilities {
            crate::CodecAbilities {
                hex_to_value: Some(Default::default()),
                ..Default::default()
            }
        }
        fn convert(&self, q: &crate::Question<'_>) -> Result<crate::Answer, crate::Unsupported> {
            assert!(q.text != b"PANIC", "a text it cannot take");
            Ok(crate::Answer::Value(q.text.len() as u64))
        }
    }
    let project = session();
    let sweep = Sweep::new(
        random(Operation::HexToValue, 10, 4, 1),
        &project.profiles,
        &[crate::codec_backend(Panicky)],
    )
    .expect("sweep");
    let points: Vec<(u64, Point)> = [&b"12"[..], b"PANIC", b"123"]
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let mut p = sweep.space.point(0);
            p.data = Data::Text(t.to_vec());
            p.digits = t.len() as u32;
            (i as u64, p)
        })
        .collect();
    let replies: Vec<String> = sweep
        .answers(&points, &no_stop())
        .into_iter()
        .map(|r| match r.and_then(|r| r.last().cloned()) {
            Some(Reply::Failed { label, detail }) => {
                assert!(detail.contains("a text it cannot take"), "{detail}");
                label
            }
            other => format!("{:?}", other.map(|r| r.to_string())),
        })
        .collect();
    assert_eq!(replies, ["Some(\"0002H\")", "crashed", "Some(\"0003H\")"]);
}

/// A codec in process that panics on texts holding a `Z`.
struct PanicsOnZ;

impl crate::Codec for PanicsOnZ {
    fn name(&self) -> &str {
        "panics-on-z"
    }
    fn abilities(&self) -> crate::CodecAbilities {
        let field = crate::OperationAbilities {
            digits: Some(vec![4]),
            ..Default::default()
        };
        crate::CodecAbilities {
            hex_to_value: Some(field),
            ..Default::default()
        }
    }
    fn convert(&self, q: &crate::Question<'_>) -> Result<crate::Answer, crate::Unsupported> {
        assert!(!q.text.contains(&b'Z'), "no Z here");
        Ok(
            u16::from_str_radix(std::str::from_utf8(q.text).unwrap_or("?"), 16)
                .map_or(crate::Answer::Error(crate::ErrorClass::InvalidDigit), |v| {
                    crate::Answer::Value(u64::from(v))
                }),
        )
    }
}

/// A codec in process that panics is that case's crash, with where it panicked, and nothing
/// else: the panic hook a command installs prints nothing for it (a codec that panics on many
/// texts would flood the terminal) and kills no backend process (an external backend asked
/// afterwards still answers). The hook is process-wide, so the check runs in a child process of
/// this test binary.
#[test]
fn a_codec_panic_is_its_cases_crash_and_nothing_else() {
    use crate::model::project::{ExternalSettings, Launch};
    use crate::sweep::group::Reply;
    const CHILD: &str = "PLC_CONFORMANCE_PANIC_CHILD";
    const NAME: &str = "sweep::white_box::a_codec_panic_is_its_cases_crash_and_nothing_else";
    if !python() {
        return;
    }
    if std::env::var_os(CHILD).is_none() {
        let out = std::process::Command::new(std::env::current_exe().expect("this test binary"))
            .args(["--exact", NAME, "--nocapture", "--test-threads=1"])
            .env(CHILD, "1")
            .output()
            .expect("the child runs");
        let (stdout, stderr) = (
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr),
        );
        assert!(out.status.success(), "{stdout}\n{stderr}");
        assert!(stdout.contains("child: checked"), "{stdout}\n{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        return;
    }
    crate::interrupt::install_panic_hook(true);
    let mut project = session();
    let script = root().join("tests/fixtures/external/faulty_codec.py");
    let settings = ExternalSettings::new(
        "strict",
        Launch::Exec(vec![
            "python3".into(),
            script.display().to_string(),
            "crash-on-g".into(),
        ]),
    );
    // Started before the panics: a hook that killed every backend would kill it.
    let external = project
        .add(BackendSource::Process(settings), false)
        .expect("the codec starts")[0]
        .clone();
    let texts: [&[u8]; 4] = [b"5A8D", b"Z000", b"0000", b"1Z34"];
    let panics = crate::codec_backend(PanicsOnZ);
    for (text, reply) in texts.iter().zip(replies_to(&project, panics, &texts)) {
        match &reply {
            Reply::Failed { label, detail } if text.contains(&b'Z') => {
                assert_eq!(label, "crashed", "{reply}");
                assert!(detail.contains("no Z here"), "{detail}");
                assert!(detail.contains("src/sweep/white_box.rs:"), "{detail}");
            }
            _ => assert!(
                !text.contains(&b'Z') && !matches!(reply, Reply::Failed { .. }),
                "{reply}"
            ),
        }
    }
    for reply in replies_to(&project, external, &texts) {
        assert!(!matches!(reply, Reply::Failed { .. }), "{reply}");
    }
    println!("child: checked");
}
