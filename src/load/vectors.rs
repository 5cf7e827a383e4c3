//! Reading vector files into the validated corpus, checked against their profiles.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::checks::{check_cite, check_expect_optional, check_id, text_bytes, unknown};
use super::{read_file, yaml_files, FileContext, LoadError, LoadErrorKind, LoadErrors};
use crate::device::{code_matches, Device};
use crate::memory::{Unit, Value};
use crate::model::profile::{Profile, Profiles, SignalKind};
use crate::model::{Case, Citation, Corpus, ErrorSignal, Expectation, Indirect, Location, Operand};
use crate::spec::vectors::{
    CaseSpec, ExpectSpec, FlagSpec, ScalarSpec, SourceSpec, ValueSpec, VectorFileSpec,
};
use crate::value::{parse_bits, parse_number, parse_word, to_bits};

/// Loads every vector file under the given paths (files or folders).
///
/// Files are read side by side, each on its own (a file's cases depend only on its text and the
/// profiles), and their cases are then taken in file order, so that a repeated id is reported at
/// the same place however the reading went: `--list`, which nextest runs before every run,
/// loads the whole corpus (docs/performance.md, "Start-up of the test binary").
pub fn load_corpus(paths: &[PathBuf], profiles: &Profiles) -> Result<Corpus, LoadErrors> {
    let mut builder = CorpusBuilder::default();
    let mut files = Vec::new();
    for path in paths {
        match yaml_files(path) {
            Ok(found) if found.is_empty() => builder.errors.push(LoadError {
                file: path.clone(),
                line: None,
                key: None,
                kind: LoadErrorKind::Invalid("no vector file (*.yaml) found".into()).into(),
            }),
            Ok(found) => files.extend(found),
            Err(e) => builder.errors.push(e),
        }
    }
    for read in read_side_by_side(&files, profiles) {
        builder.take(read);
    }
    builder.finish()
}

/// Reads the files on as many threads as the machine has cores (at most one per file), each
/// taking the next unread file; the results come back in the files' order.
fn read_side_by_side(files: &[PathBuf], profiles: &Profiles) -> Vec<FileRead> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Mutex;
    let read_one = |file: &PathBuf| match read_file(file) {
        Ok(text) => FileRead::new(file, &text, profiles),
        Err(e) => FileRead {
            errors: vec![e],
            ..FileRead::default()
        },
    };
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(files.len());
    if threads <= 1 {
        return files.iter().map(read_one).collect();
    }
    let next = AtomicUsize::new(0);
    let slots: Vec<Mutex<Option<FileRead>>> = files.iter().map(|_| Mutex::new(None)).collect();
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let (Some(file), Some(slot)) = (files.get(i), slots.get(i)) else {
                    break;
                };
                let read = read_one(file);
                *slot.lock().unwrap_or_else(|poisoned| poisoned.into_inner()) = Some(read);
            });
        }
    });
    // Every slot is filled: a reader that panicked has ended the scope with its panic.
    slots
        .into_iter()
        .map(|slot| {
            slot.into_inner()
                .unwrap_or_else(|poisoned| poisoned.into_inner())
                .unwrap_or_default()
        })
        .collect()
}

/// One file's cases and problems, before their ids are checked against the other files'.
#[derive(Default)]
struct FileRead {
    cases: Vec<(String, Case)>,
    cross_vendor: Vec<(String, crate::model::cross_vendor::CrossVendorCase)>,
    protocol_fields: Vec<(String, crate::model::cross_vendor::CrossVendorCase)>,
    errors: Vec<LoadError>,
}

impl FileRead {
    fn new(file: &Path, text: &str, profiles: &Profiles) -> Self {
        let mut read = FileRead::default();
        // One context for either kind of file: the text checked and its lines indexed once
        // (a text refused by the check has no lines, and reads as no document).
        let mut cx = FileContext::new(file, text, &mut read.errors);
        if super::protocols::is_protocol_file(&cx.index) {
            read.protocol_fields = super::protocols::read_file(text, profiles, &mut cx);
            return read;
        }
        if super::cross_vendor::is_cross_vendor(&cx.index) {
            read.cross_vendor = super::cross_vendor::read_file(text, profiles, &mut cx);
            return read;
        }
        let Some(spec) = super::parse_document::<VectorFileSpec>(text, &mut cx) else {
            return read;
        };
        let Some(header) = read_header(&spec, profiles, &mut cx) else {
            return read;
        };
        read.cases = super::checks::read_cases(&spec.cases, &mut cx, |key, case, cx| {
            read_case(key, case, &header, cx)
        });
        read
    }
}

/// Accumulates cases from vector files, checking ids across the whole corpus.
#[derive(Default)]
pub(crate) struct CorpusBuilder {
    cases: Vec<Arc<Case>>,
    cross_vendor: Vec<Arc<crate::model::cross_vendor::CrossVendorCase>>,
    protocol_fields: Vec<Arc<crate::model::cross_vendor::CrossVendorCase>>,
    ids: HashMap<String, Location>,
    errors: Vec<LoadError>,
}

impl CorpusBuilder {
    /// Adds one vector file given as text; `file` is the name errors will show.
    pub(crate) fn add_file(&mut self, file: &Path, text: &str, profiles: &Profiles) {
        self.take(FileRead::new(file, text, profiles));
    }

    fn take(&mut self, read: FileRead) {
        self.errors.extend(read.errors);
        for (key, case) in read.cross_vendor {
            if self.claim_id(&key, &case.id, &case.location) {
                self.cross_vendor.push(Arc::new(case));
            }
        }
        for (key, case) in read.protocol_fields {
            if self.claim_id(&key, &case.id, &case.location) {
                self.protocol_fields.push(Arc::new(case));
            }
        }
        for (key, case) in read.cases {
            if self.claim_id(&key, &case.id, &case.location) {
                self.cases.push(Arc::new(case));
            }
        }
    }

    /// Records an id; a repeat is an error at the repeat, naming the first use.
    fn claim_id(&mut self, key: &str, id: &str, at: &Location) -> bool {
        match self.ids.get(id) {
            Some(first) => {
                self.errors.push(LoadError {
                    file: at.file.clone(),
                    line: Some(at.line),
                    key: Some(format!("{key}.id")),
                    kind: LoadErrorKind::DuplicateId {
                        id: id.to_string(),
                        first: first.clone(),
                    }
                    .into(),
                });
                false
            }
            None => {
                self.ids.insert(id.to_string(), at.clone());
                true
            }
        }
    }

    pub(crate) fn finish(self) -> Result<Corpus, LoadErrors> {
        if self.errors.is_empty() {
            Ok(Corpus {
                cases: self.cases,
                cross_vendor: self.cross_vendor,
                protocol_fields: self.protocol_fields,
            })
        } else {
            Err(LoadErrors(self.errors))
        }
    }
}

/// What a file says for all its cases.
struct Header<'p> {
    instructions: Arc<[String]>,
    profiles: Vec<&'p Profile>,
    /// What a device of these profiles holds (they must agree).
    unit: Unit,
    profile_ids: Arc<[String]>,
    source: SourceSpec,
}

impl Header<'_> {
    /// A device name read with the profiles' numbering (`W1A` where W is hexadecimal).
    fn device(&self, text: &str) -> Result<Device, crate::device::DeviceSyntaxError> {
        Device::parse_numbered(text, |code| {
            self.profiles.iter().any(|p| p.devices.is_hexadecimal(code))
        })
    }
}

fn read_header<'p>(
    spec: &VectorFileSpec,
    profiles: &'p Profiles,
    cx: &mut FileContext<'_>,
) -> Option<Header<'p>> {
    let before = cx.errors.len();
    if spec.profiles.is_empty() {
        cx.error(
            "profiles",
            LoadErrorKind::Missing("profile: name at least one"),
        );
    }
    if spec.instructions.is_empty() {
        cx.error(
            "instructions",
            LoadErrorKind::Missing("instruction: name at least one"),
        );
    }
    let mut found = Vec::new();
    for (i, id) in spec.profiles.iter().enumerate() {
        match profiles.get(id) {
            Some(p) => found.push(p.as_ref()),
            None => cx.error(
                format!("profiles[{i}]"),
                unknown("profile", id, &profiles.ids()),
            ),
        }
    }
    for p in &found {
        for (i, instr) in spec.instructions.iter().enumerate() {
            if !p.instructions.contains_key(instr) {
                let known: Vec<String> = p.instructions.keys().cloned().collect();
                cx.error(
                    format!("instructions[{i}]"),
                    unknown("instruction", instr, &known),
                );
            }
        }
    }
    let unit = found.first().map_or(Unit::Word, |p| p.unit);
    if let Some(other) = found.iter().find(|p| p.unit != unit) {
        cx.error(
            "profiles",
            LoadErrorKind::Invalid(format!(
                "`{}` is {}-addressed and `{}` {}-addressed: one file's memory is in one unit",
                found[0].id,
                unit.name(),
                other.id,
                other.unit.name()
            )),
        );
    }
    check_source("source", &spec.source, &found, cx);
    (cx.errors.len() == before).then(|| Header {
        instructions: spec.instructions.clone().into(),
        profiles: found,
        unit,
        profile_ids: spec.profiles.clone().into(),
        source: spec.source.clone(),
    })
}

fn check_source(key: &str, source: &SourceSpec, profiles: &[&Profile], cx: &mut FileContext<'_>) {
    for p in profiles {
        if !p.manuals.contains_key(&source.manual) {
            let known: Vec<String> = p.manuals.keys().cloned().collect();
            cx.error(
                format!("{key}.manual"),
                unknown("manual", &source.manual, &known),
            );
        }
    }
}

/// A `manual` expectation holds for the variants its manuals cover: every manual of the
/// profile the cite names (`s7-1200-2011 p.253: ...; s7-1200-2014 p.305`), and the file's
/// source when the cite does not open with a manual; together they must cover every variant
/// the case runs on. What one CPU's page states is
/// only an inference for another CPU, and a manual of other CPUs (`covers: []`) covers none.
fn check_manual_covers(
    key: &str,
    cite: Option<&str>,
    source: &SourceSpec,
    variants: Option<&BTreeSet<String>>,
    h: &Header<'_>,
    cx: &mut FileContext<'_>,
) {
    let words: Vec<&str> = cite
        .unwrap_or_default()
        .split(|c: char| c.is_whitespace() || matches!(c, ',' | ':' | ';' | '(' | ')'))
        .filter(|w| !w.is_empty())
        .collect();
    for p in &h.profiles {
        let mut named: Vec<&str> = (words.iter().copied())
            .filter(|w| p.manuals.contains_key(*w))
            .collect();
        // A cite that does not open with a manual quotes the file's source.
        if words.first().is_none_or(|w| !p.manuals.contains_key(*w)) {
            named.push(&source.manual);
        }
        named.sort_unstable();
        named.dedup();
        let covered = |variant: &str| {
            named.iter().any(|id| {
                p.manuals
                    .get(*id)
                    .is_some_and(|m| m.covers.iter().any(|c| c == variant))
            })
        };
        let uncovered: Vec<&str> = (p.variants.iter())
            .map(|v| v.id.as_str())
            .filter(|v| variants.is_none_or(|list| list.contains(*v)))
            .filter(|v| !covered(v))
            .collect();
        if !uncovered.is_empty() {
            let covering: BTreeSet<&str> = (named.iter())
                .filter_map(|id| p.manuals.get(*id))
                .flat_map(|m| m.covers.iter().map(String::as_str))
                .collect();
            let covering: Vec<&str> = covering.into_iter().collect();
            cx.error(
                format!("{key}.basis"),
                LoadErrorKind::Invalid(format!(
                    "`basis: manual` rests on {}, {}, and the case also runs on {}: restrict it \
                     with `variants: [{}]` and give the other variants an `inferred` case of \
                     their own",
                    named.join(", "),
                    match covering.is_empty() {
                        true => "which covers no variant of this profile".to_string(),
                        false => format!("the manual of {}", covering.join(", ")),
                    },
                    uncovered.join(", "),
                    covering.join(", ")
                )),
            );
        }
    }
}

fn read_case(key: &str, spec: &CaseSpec, h: &Header<'_>, cx: &mut FileContext<'_>) -> Option<Case> {
    let before_count = cx.errors.len();
    check_id(key, &spec.id, cx);
    let cite = check_cite(key, spec.basis, spec.cite.as_deref(), cx);
    if spec.provenance.is_some() && spec.basis != crate::model::Basis::Observed {
        cx.error(
            format!("{key}.provenance"),
            LoadErrorKind::Invalid(format!(
                "provenance belongs to an `observed` expectation, not a `{}` one",
                spec.basis
            )),
        );
    }
    if let Some(source) = &spec.source {
        check_source(&format!("{key}.source"), source, &h.profiles, cx);
    }
    let source = spec.source.as_ref().unwrap_or(&h.source);

    let variants = spec.variants.as_ref().map(|list| {
        if list.is_empty() {
            cx.error(
                format!("{key}.variants"),
                LoadErrorKind::Invalid(
                    "an empty list runs the case on no variant; name at least one, or leave \
                     `variants` out to run it on every variant"
                        .into(),
                ),
            );
        }
        let known: Vec<String> = h
            .profiles
            .iter()
            .flat_map(|p| p.variants.iter().map(|v| v.id.clone()))
            .collect();
        for (i, v) in list.iter().enumerate() {
            if !known.contains(v) {
                cx.error(
                    format!("{key}.variants[{i}]"),
                    unknown("variant", v, &known),
                );
            }
        }
        list.iter().cloned().collect::<BTreeSet<String>>()
    });

    if spec.basis == crate::model::Basis::Manual {
        check_manual_covers(key, cite.as_deref(), source, variants.as_ref(), h, cx);
    }
    let flags = read_flags(key, &spec.flags, h, cx);
    let (operands, indirect) = read_operands(key, spec, h, cx);
    let before = read_memory(&format!("{key}.before"), &spec.before, h, cx);
    let expect = match &spec.expect {
        Some(e) => Some(read_expect(&format!("{key}.expect"), e, h, cx)),
        None => {
            check_expect_optional(key, spec.basis, cx);
            None
        }
    };
    check_pointer_words(key, &indirect, &before, expect.as_ref(), cx);

    check_digit_grids(key, spec, h, cx);

    (cx.errors.len() == before_count).then(|| Case {
        id: spec.id.clone(),
        basis: spec.basis,
        citation: Citation {
            manual: source.manual.clone(),
            page: source.page.to_string(),
            text: cite,
        },
        location: cx.location(key),
        instructions: h.instructions.clone(),
        profiles: h.profile_ids.clone(),
        variants,
        flags,
        operands,
        indirect,
        before,
        expect,
        note: spec.note.clone(),
    })
}

fn read_flags(
    key: &str,
    spec: &BTreeMap<String, FlagSpec>,
    h: &Header<'_>,
    cx: &mut FileContext<'_>,
) -> BTreeMap<String, bool> {
    let mut out = BTreeMap::new();
    for (name, value) in spec {
        let fkey = format!("{key}.flags.{name}");
        for p in &h.profiles {
            let read = h.instructions.iter().all(|i| {
                p.instructions
                    .get(i)
                    .is_some_and(|def| def.flags.iter().any(|f| f == name))
            });
            if !read {
                let known: BTreeSet<String> = h
                    .instructions
                    .iter()
                    .filter_map(|i| p.instructions.get(i))
                    .flat_map(|d| d.flags.iter().cloned())
                    .collect();
                let what = "flag for these instructions";
                cx.error(
                    &fkey,
                    unknown(what, name, &known.into_iter().collect::<Vec<_>>()),
                );
            }
        }
        let on = match value {
            FlagSpec::Bool(b) => Some(*b),
            FlagSpec::Number(0) => Some(false),
            FlagSpec::Number(1) => Some(true),
            FlagSpec::Text(t) if t.eq_ignore_ascii_case("on") => Some(true),
            FlagSpec::Text(t) if t.eq_ignore_ascii_case("off") => Some(false),
            _ => None,
        };
        match on {
            Some(on) => {
                out.insert(name.clone(), on);
            }
            None => cx.error(
                &fkey,
                LoadErrorKind::Invalid("expected `on` or `off` (or true/false, 1/0)".into()),
            ),
        }
    }
    out
}

/// The operands, with those given by indirect specification (`@D10`) holding the device their
/// pointer addresses (from `addresses`), and the pointers of those.
fn read_operands(
    key: &str,
    case: &CaseSpec,
    h: &Header<'_>,
    cx: &mut FileContext<'_>,
) -> (BTreeMap<String, Operand>, Indirect) {
    let spec = &case.operands;
    let addresses = read_addresses(key, &case.addresses, h, cx);
    let mut out = BTreeMap::new();
    let mut indirect = Indirect::new();
    for p in &h.profiles {
        for instr in h.instructions.iter() {
            let Some(def) = p.instructions.get(instr) else {
                continue;
            };
            let names: Vec<String> = def.operands.keys().cloned().collect();
            for name in spec.keys().filter(|n| !def.operands.contains_key(*n)) {
                cx.error(
                    format!("{key}.operands.{name}"),
                    unknown("operand", name, &names),
                );
            }
            for name in names.iter().filter(|n| !spec.contains_key(*n)) {
                cx.error(
                    format!("{key}.operands"),
                    LoadErrorKind::Invalid(format!("missing operand `{name}` of {instr}")),
                );
            }
        }
    }
    for (name, value) in spec {
        let okey = format!("{key}.operands.{name}");
        let operand = match value {
            ScalarSpec::Number(n) => Operand::Constant(*n),
            ScalarSpec::Text(t) if t.starts_with('@') => {
                match read_pointer(&okey, name, &t[1..], &addresses, h, cx) {
                    Some((pointer, target)) => {
                        indirect.insert(name.clone(), pointer);
                        Operand::Device(target)
                    }
                    None => continue,
                }
            }
            ScalarSpec::Text(t) => match parse_number(t) {
                Ok(n) => Operand::Constant(n),
                Err(_) => match h.device(t) {
                    Ok(d) => Operand::Device(d),
                    Err(e) => {
                        cx.error(&okey, LoadErrorKind::Device(e));
                        continue;
                    }
                },
            },
        };
        for p in &h.profiles {
            for instr in h.instructions.iter() {
                let Some(def) = p.instructions.get(instr).and_then(|d| d.operands.get(name)) else {
                    continue;
                };
                match &operand {
                    Operand::Constant(k)
                        if def.constant && def.constants.is_some_and(|r| !r.contains(*k)) =>
                    {
                        let r = def
                            .constants
                            .unwrap_or(crate::spec::profile::ConstantRange { min: *k, max: *k });
                        cx.error(
                            &okey,
                            LoadErrorKind::Invalid(format!(
                                "K{k} cannot be programmed: {instr} operand `{name}` takes \
                                 constants {}-{} only ({}); give the value in a register \
                                 (e.g. `{name}: D10` with D10 set in `before`)",
                                r.min, r.max, p.id
                            )),
                        )
                    }
                    Operand::Device(d)
                        if def
                            .limits
                            .get(d.code())
                            .is_some_and(|r| !r.contains(d.index)) =>
                    {
                        let r = def.limits[d.code()];
                        cx.error(
                            &okey,
                            LoadErrorKind::Invalid(format!(
                                "{d} cannot be programmed: {instr} operand `{name}` takes {0}{1}-{0}{2} only ({3})",
                                d.code(), r.first, r.last, p.id
                            )),
                        )
                    }
                    Operand::Constant(_) if !def.constant => cx.error(
                        &okey,
                        LoadErrorKind::Invalid(format!(
                            "{instr} operand `{name}` takes a device ({}), not a constant",
                            def.devices.join(", ")
                        )),
                    ),
                    Operand::Device(d)
                        if !def.devices.iter().any(|c| code_matches(c, d.code())) =>
                    {
                        cx.error(
                            &okey,
                            unknown("device for this operand", d.code(), &def.devices),
                        )
                    }
                    Operand::Device(d) if !p.word_exists_anywhere(d) => {
                        cx.error(&okey, missing_word(p, d));
                    }
                    _ => {}
                }
            }
        }
        out.insert(name.clone(), operand);
    }
    let named: BTreeSet<Device> = (spec.values())
        .filter_map(|v| match v {
            ScalarSpec::Text(t) => h.device(t.strip_prefix('@')?).ok(),
            ScalarSpec::Number(_) => None,
        })
        .collect();
    for (pointer, (akey, _)) in &addresses {
        if !named.contains(pointer) {
            cx.error(
                akey,
                LoadErrorKind::Invalid(format!(
                    "no operand is `@{pointer}`: an address is given for the pointer of an \
                     operand written with indirect specification"
                )),
            );
        }
    }
    (out, indirect)
}

/// `addresses`, read: each pointer with its key and the device it addresses.
fn read_addresses(
    key: &str,
    spec: &BTreeMap<String, String>,
    h: &Header<'_>,
    cx: &mut FileContext<'_>,
) -> BTreeMap<Device, (String, Device)> {
    let mut out = BTreeMap::new();
    for (pointer, target) in spec {
        let akey = format!("{key}.addresses.{pointer}");
        match (h.device(pointer), h.device(target)) {
            (Ok(p), Ok(t)) => {
                out.insert(p, (akey, t));
            }
            (Err(e), _) | (_, Err(e)) => cx.error(&akey, LoadErrorKind::Device(e)),
        }
    }
    out
}

/// The pointer of `@pointer` and the device it addresses, checked against every profile:
/// the operand must take indirect specification through the pointer's code, and both of the
/// pointer's words must exist.
fn read_pointer(
    okey: &str,
    name: &str,
    pointer: &str,
    addresses: &BTreeMap<Device, (String, Device)>,
    h: &Header<'_>,
    cx: &mut FileContext<'_>,
) -> Option<(Device, Device)> {
    let pointer = h
        .device(pointer)
        .map_err(|e| cx.error(okey, LoadErrorKind::Device(e)))
        .ok()?;
    let before = cx.errors.len();
    for p in &h.profiles {
        for instr in h.instructions.iter() {
            let Some(def) = p.instructions.get(instr).and_then(|d| d.operands.get(name)) else {
                continue;
            };
            if !def.indirect.iter().any(|c| code_matches(c, pointer.code())) {
                let how = match def.indirect.as_slice() {
                    [] => "no indirect specification".to_string(),
                    codes => format!("indirect specification through {} only", codes.join(", ")),
                };
                cx.error(
                    okey,
                    LoadErrorKind::Invalid(format!(
                        "{instr} operand `{name}` takes {how} ({})",
                        p.id
                    )),
                );
            } else if let Some(missing) = [Some(pointer.clone()), pointer.offset(1)]
                .into_iter()
                .find(|w| !w.as_ref().is_some_and(|w| p.word_exists_anywhere(w)))
            {
                let word = missing.map_or_else(|| format!("{pointer}+1"), |w| w.to_string());
                cx.error(
                    okey,
                    LoadErrorKind::Invalid(format!(
                        "`@{pointer}` needs {pointer} and the word after it to hold an address, \
                         and {word} does not exist on any {} variant",
                        p.id
                    )),
                );
            }
        }
    }
    let Some((_, target)) = addresses.get(&pointer) else {
        cx.error(
            okey,
            LoadErrorKind::Invalid(format!(
                "`@{pointer}` is indirect specification: say which device {pointer} holds the \
                 address of in the case's `addresses` (`addresses: {{{pointer}: D100}}`)"
            )),
        );
        return None;
    };
    (cx.errors.len() == before).then(|| (pointer, target.clone()))
}

/// Refuses a case that sets or expects a word of a pointer: the two words hold an address in
/// ADRSET's encoding, which no page the project quotes gives.
fn check_pointer_words(
    key: &str,
    indirect: &Indirect,
    before: &BTreeMap<Device, Value>,
    expect: Option<&Expectation>,
    cx: &mut FileContext<'_>,
) {
    for pointer in indirect.values() {
        for word in crate::model::pointer_words([pointer]) {
            let mut places = vec![(format!("{key}.before"), before)];
            if let Some(e) = expect {
                places.push((format!("{key}.expect.after"), &e.after));
            }
            for (at, memory) in places {
                if memory.contains_key(&word) {
                    cx.error(
                        &at,
                        LoadErrorKind::Invalid(format!(
                            "{word} is a word of the pointer `@{pointer}`: it holds an address \
                             as ADRSET stores it, which the manuals do not give, so a case \
                             cannot set or expect it; move the pointer away from the words \
                             the case names"
                        )),
                    );
                }
            }
        }
    }
}

/// Refuses a case whose digit-designated words of one code are not 16 points apart
/// (`K4M0` with `K4M8`): such words share points, and the models keep each word on its own.
/// On one grid (`K4M100`, `K4M116`, ...) no two words of the case, or of what an instruction
/// reaches from its operands a unit at a time, ever overlap.
fn check_digit_grids(key: &str, spec: &CaseSpec, h: &Header<'_>, cx: &mut FileContext<'_>) {
    let operands = spec
        .operands
        .iter()
        .filter_map(|(name, value)| match value {
            ScalarSpec::Text(t) => Some((format!("{key}.operands.{name}"), t.as_str())),
            ScalarSpec::Number(_) => None,
        });
    // What an indirect operand addresses is an operand too.
    let addressed = spec
        .addresses
        .iter()
        .map(|(pointer, target)| (format!("{key}.addresses.{pointer}"), target.as_str()));
    let before = spec
        .before
        .keys()
        .map(|name| (format!("{key}.before.{name}"), name.as_str()));
    let after = spec.expect.iter().flat_map(|e| {
        e.after
            .keys()
            .map(|name| (format!("{key}.expect.after.{name}"), name.as_str()))
    });
    let mut grids: BTreeMap<String, Device> = BTreeMap::new();
    for (at, text) in operands.chain(addressed).chain(before).chain(after) {
        let Ok(device) = h.device(text) else {
            continue;
        };
        let points = device.points();
        if points == 1 {
            continue;
        }
        match grids.get(device.code()) {
            Some(first) if first.index % points != device.index % points => cx.error(
                &at,
                LoadErrorKind::Invalid(format!(
                    "{device} and {first} share points: a case's {} words must be {points} \
                     points apart ({first}, {}, ...), since each is modelled as a word of its own",
                    device.code(),
                    first.offset(1).map_or_else(String::new, |d| d.to_string()),
                )),
            ),
            Some(_) => {}
            None => {
                grids.insert(device.code().to_string(), device);
            }
        }
    }
}

/// Expands `device: value` entries into single words, rejecting a word set twice.
fn read_memory(
    key: &str,
    spec: &BTreeMap<String, ValueSpec>,
    h: &Header<'_>,
    cx: &mut FileContext<'_>,
) -> BTreeMap<Device, Value> {
    let mut out: BTreeMap<Device, Value> = BTreeMap::new();
    let mut set_by: BTreeMap<Device, String> = BTreeMap::new();
    for (name, value) in spec {
        let mkey = format!("{key}.{name}");
        let head = match h.device(name) {
            Ok(d) => d,
            Err(e) => {
                cx.error(&mkey, LoadErrorKind::Device(e));
                continue;
            }
        };
        let Some(words) = expand(&mkey, value, h.unit, cx) else {
            continue;
        };
        // Consecutive numbers of a bit device are not consecutive words: M0 and M1 share 15
        // of their 16 points. Such words are given one by one, by their heads.
        if words.len() > 1 {
            for p in &h.profiles {
                if let Some(def) = p
                    .devices
                    .get(head.code())
                    .filter(|d| d.points_per_word > head.points())
                {
                    cx.error(
                        &mkey,
                        LoadErrorKind::Invalid(format!(
                            "a word of {} is {} points from its head; give each word by its head instead of a list or text",
                            head.code(), def.points_per_word
                        )),
                    );
                }
            }
        }
        for (offset, word) in words.into_iter().enumerate() {
            let Some(device) = head.offset(offset as u32) else {
                break;
            };
            for p in &h.profiles {
                if !p.devices.contains_key(device.code()) {
                    let known: Vec<String> = p.devices.keys().cloned().collect();
                    cx.error(&mkey, unknown("device", device.code(), &known));
                } else if !p.word_exists_anywhere(&device) {
                    cx.error(&mkey, missing_word(p, &device));
                }
            }
            if let Some(first) = set_by.get(&device) {
                cx.error(
                    &mkey,
                    LoadErrorKind::Invalid(format!("{device} is set twice (also by `{first}`)")),
                );
            }
            set_by.insert(device.clone(), name.clone());
            out.insert(device, word);
        }
    }
    out
}

/// Why a word a vector names does not exist, in the profile's terms.
fn missing_word(p: &Profile, d: &Device) -> LoadErrorKind {
    LoadErrorKind::Invalid(match p.devices.get(d.code()) {
        Some(def) if def.numbering.point(d.index).is_none() => format!(
            "{d} is not a valid {} number: {}",
            d.code(),
            def.numbering.rule()
        ),
        Some(def) if def.points_per_word > 1 => format!(
            "{d} does not exist on any {} variant: a word of {} is the {} points from its head, and all of them must exist",
            p.id, d.code(), def.points_per_word
        ),
        _ => format!("{d} does not exist on any {} variant", p.id),
    })
}

/// The units a value spec stands for. Text is stored as the family stores a string: two
/// characters per word, first in the low byte, in word memory; one per byte in byte memory.
fn expand(
    key: &str,
    value: &ValueSpec,
    unit: Unit,
    cx: &mut FileContext<'_>,
) -> Option<Vec<Value>> {
    let bits = unit.bits();
    let word = |s: &ScalarSpec| match s {
        ScalarSpec::Number(n) => to_bits(&n.to_string(), *n, bits).map(|w| w as Value),
        ScalarSpec::Text(t) => parse_bits(t, bits),
    };
    let words = match value {
        ValueSpec::Word(s) => vec![word(s)
            .map_err(|e| cx.error(key, LoadErrorKind::Value(e)))
            .ok()?],
        ValueSpec::Words(list) => {
            let mut out = Vec::new();
            for (i, s) in list.iter().enumerate() {
                match word(s) {
                    Ok(w) => out.push(w),
                    Err(e) => cx.error(format!("{key}[{i}]"), LoadErrorKind::Value(e)),
                }
            }
            if out.len() != list.len() {
                return None;
            }
            out
        }
        ValueSpec::Ascii(text) => unit.pack(&text_bytes(key, text, cx)?),
        ValueSpec::AsciiWords(text) => text_bytes(key, text, cx)?
            .into_iter()
            .map(Value::from)
            .collect(),
    };
    if words.is_empty() {
        cx.error(
            key,
            LoadErrorKind::Invalid("empty text sets no word".into()),
        );
        return None;
    }
    Some(words)
}

fn read_expect(
    key: &str,
    spec: &ExpectSpec,
    h: &Header<'_>,
    cx: &mut FileContext<'_>,
) -> Expectation {
    let after = read_memory(&format!("{key}.after"), &spec.after, h, cx);
    let ekey = format!("{key}.error");
    let error = match &spec.error {
        None => None,
        Some(ScalarSpec::Text(t)) if t == "none" => None,
        Some(value) => {
            let mut read = None;
            for p in &h.profiles {
                read = read_error(&ekey, value, p, cx);
            }
            read
        }
    };
    Expectation { after, error }
}

/// Reads an error expectation the way the profile signals errors.
fn read_error(
    key: &str,
    value: &ScalarSpec,
    p: &Profile,
    cx: &mut FileContext<'_>,
) -> Option<ErrorSignal> {
    let flag = p
        .errors
        .flag
        .as_ref()
        .map_or_else(|| "?".to_string(), ToString::to_string);
    let register = match (&p.errors.register, &p.errors.returned) {
        (Some(r), _) => r.to_string(),
        (None, Some(returned)) => returned.clone(),
        (None, None) => "?".to_string(),
    };
    match p.errors.signal {
        SignalKind::Code => {
            let code = match value {
                // The manuals write every code in hex (3401H); a bare number is almost always
                // that code without its H, and as decimal it would be another code entirely.
                // (0 is no code at all: said below.)
                ScalarSpec::Number(n) if *n != 0 => {
                    cx.error(
                        key,
                        LoadErrorKind::Invalid(format!(
                            "`{n}` is a decimal number, but error codes are written in hex as \
                             the manuals write them: did you mean `{n}H`?"
                        )),
                    );
                    return None;
                }
                ScalarSpec::Number(_) => Ok(0),
                ScalarSpec::Text(t) => parse_word(t),
            };
            match code {
                Ok(0) => {
                    cx.error(
                        key,
                        LoadErrorKind::Invalid(format!(
                            "`{value}` is not an error code: {} reports no error as 0 in \
                             {register}; write `none` for no error",
                            p.id
                        )),
                    );
                    None
                }
                Ok(c) => Some(ErrorSignal::Code(c)),
                Err(_) => {
                    cx.error(
                        key,
                        LoadErrorKind::Invalid(format!(
                            "`{value}` is not an error of {}: it reports errors as a code in {register}; expected `none` or a code like `3401H`",
                            p.id
                        )),
                    );
                    None
                }
            }
        }
        SignalKind::Flag => {
            if let Some(device) = p.errors.flag.as_ref().filter(|_| value.to_string() == flag) {
                Some(ErrorSignal::Flag(device.clone()))
            } else {
                cx.error(
                    key,
                    LoadErrorKind::Invalid(format!(
                        "`{value}` is not an error of {}: it signals errors with {flag} only, not with a code; expected `none` or `{flag}`",
                        p.id
                    )),
                );
                None
            }
        }
    }
}
