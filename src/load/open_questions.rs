//! Loading `docs/open-questions.yaml` and checking it against the profiles and the corpus: a
//! question whose probe is not a case of the corpus could never be settled.

use std::collections::BTreeSet;
use std::path::Path;

use super::{LoadErrorKind, LoadErrors};
use crate::model::open_questions::{Decides, OpenQuestion};
use crate::model::profile::Profiles;
use crate::model::Corpus;
use crate::spec::open_questions::OpenQuestionsSpec;

/// Where a project keeps its open questions.
pub(crate) const OPEN_QUESTIONS: &str = "docs/open-questions.yaml";

pub(crate) fn load_open_questions(
    file: &Path,
    profiles: &Profiles,
    corpus: &Corpus,
) -> Result<Vec<OpenQuestion>, LoadErrors> {
    super::load_document(file, |spec: OpenQuestionsSpec, cx| {
        let case_ids: BTreeSet<&str> = corpus
            .cases
            .iter()
            .map(|c| c.id.as_str())
            .chain(corpus.cross_vendor.iter().map(|c| c.id.as_str()))
            .chain(corpus.protocol_fields.iter().map(|c| c.id.as_str()))
            .collect();
        let mut seen = BTreeSet::new();
        let mut out = Vec::new();
        for (i, q) in spec.questions.into_iter().enumerate() {
            let key = |k: &str| format!("questions[{i}].{k}");
            let invalid = |m: String| LoadErrorKind::Invalid(m);
            if !seen.insert(q.id.clone()) {
                cx.error(
                    key("id"),
                    invalid(format!("question `{}` is listed twice", q.id)),
                );
            }
            let profile = match (&q.profile, &q.protocol) {
                (Some(p), None) => {
                    if q.instructions.is_empty() {
                        cx.error(
                            key("instructions"),
                            invalid(
                                "a question of a profile names the instructions it is about".into(),
                            ),
                        );
                    }
                    profiles.get(p).ok_or(p)
                }
                (None, Some(protocol)) => {
                    if profiles.protocols.get(protocol).is_none() {
                        cx.error(
                            key("protocol"),
                            super::checks::unknown("protocol", protocol, &profiles.protocols.ids()),
                        );
                    }
                    if !q.instructions.is_empty() || q.variants.is_some() {
                        cx.error(
                            key("instructions"),
                            invalid("a protocol's question has no instructions or variants".into()),
                        );
                    }
                    if q.model_takes != "none" {
                        cx.error(
                            key("model_takes"),
                            invalid(
                                "no reference model answers a protocol: `model_takes: none`".into(),
                            ),
                        );
                    }
                    Err(&String::new())
                }
                _ => {
                    cx.error(
                        key("profile"),
                        invalid(
                            "a question is about a `profile` (and its `instructions`) or a `protocol`"
                                .into(),
                        ),
                    );
                    Err(&String::new())
                }
            };
            match profile {
                Err(p) if p.is_empty() => {}
                Err(p) => cx.error(
                    key("profile"),
                    super::checks::unknown("profile", p, &profiles.ids()),
                ),
                Ok(p) => {
                    for (j, instr) in q.instructions.iter().enumerate() {
                        if !p.instructions.contains_key(instr) {
                            let known: Vec<String> = p.instructions.keys().cloned().collect();
                            cx.error(
                                format!("questions[{i}].instructions[{j}]"),
                                super::checks::unknown("instruction", instr, &known),
                            );
                        }
                    }
                    for (j, v) in q.variants.iter().flatten().enumerate() {
                        if p.variant(v).is_none() {
                            let known: Vec<String> =
                                p.variants.iter().map(|v| v.id.clone()).collect();
                            cx.error(
                                format!("questions[{i}].variants[{j}]"),
                                super::checks::unknown("variant", v, &known),
                            );
                        }
                    }
                }
            }
            let readings: Vec<String> = q.readings.iter().map(|r| r.id.clone()).collect();
            if readings.len() < 2 {
                cx.error(
                    key("readings"),
                    invalid("a question has at least two readings to tell apart".into()),
                );
            }
            if q.model_takes != "none" && !readings.contains(&q.model_takes) {
                cx.error(
                    key("model_takes"),
                    super::checks::unknown("reading", &q.model_takes, &readings),
                );
            }
            for (j, o) in q.observed.iter().enumerate() {
                if !readings.contains(&o.reading) {
                    cx.error(
                        format!("questions[{i}].observed[{j}].reading"),
                        super::checks::unknown("reading", &o.reading, &readings),
                    );
                }
            }
            if q.probes.is_empty() {
                cx.error(
                    key("probes"),
                    invalid("a question needs a probe: a case whose outcome settles it".into()),
                );
            }
            for (j, probe) in q.probes.iter().enumerate() {
                if !case_ids.contains(probe.as_str()) {
                    cx.error(
                        format!("questions[{i}].probes[{j}]"),
                        invalid(format!("`{probe}` is not a case id of the corpus")),
                    );
                }
            }
            let decides = q.decides.map(|d| {
                if !q.probes.contains(&d.probe) {
                    cx.error(
                        key("decides.probe"),
                        invalid(format!("`{}` is not one of the question's probes", d.probe)),
                    );
                }
                for id in d.outcomes.keys().filter(|id| !readings.contains(id)) {
                    cx.error(
                        format!("questions[{i}].decides.outcomes.{id}"),
                        super::checks::unknown("reading", id, &readings),
                    );
                }
                let mut outcomes = Vec::new();
                for r in &readings {
                    match d.outcomes.get(r) {
                        None => cx.error(
                            key("decides.outcomes"),
                            invalid(format!(
                                "reading `{r}` has no outcome: the probe must tell every reading apart"
                            )),
                        ),
                        Some(o) => {
                            if let Some((same, _)) = outcomes.iter().find(|(_, x)| x == o) {
                                cx.error(
                                    format!("questions[{i}].decides.outcomes.{r}"),
                                    invalid(format!(
                                        "readings `{same}` and `{r}` predict the same outcome `{o}`: \
                                         the probe cannot tell them apart"
                                    )),
                                );
                            }
                            outcomes.push((r.clone(), o.clone()));
                        }
                    }
                }
                Decides {
                    probe: d.probe,
                    outcomes,
                }
            });
            out.push(OpenQuestion {
                location: cx.location(&format!("questions[{i}]")),
                id: q.id,
                title: q.title,
                profile: q.profile.unwrap_or_default(),
                protocol: q.protocol,
                variants: q.variants,
                readings,
                model_takes: q.model_takes,
                probes: q.probes,
                decides,
            });
        }
        out
    })
}
