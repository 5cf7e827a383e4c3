//! Which words a request sends: the "window" of memory a case may touch.
//!
//! A reference model reads any word through [`crate::memory::Image`], which knows the fill; a
//! process on the other side of a pipe gets only what the request carries. The window is
//! generous so that a backend never has to compute the fill: from every device operand on, at
//! least [`OPERAND_SPAN`] words (more when a constant the profile marks as a length, `count:
//! true`, asks for a longer run, as FX5 character counts do), and around every word the case sets. Ranges are clipped to the words
//! that exist on the variant and merged. A backend that still reads past the window can compute
//! the word from the fill formula in `docs/protocol.md`.

use std::collections::BTreeMap;

use super::protocol::MemoryRange;
use crate::backend::Request;
use crate::device::Device;
use crate::model::Operand;

/// Words sent from each device operand on.
pub(crate) const OPERAND_SPAN: u32 = 64;
/// Words sent from each word the case sets on.
pub(crate) const SET_SPAN: u32 = 16;
/// The most words a constant operand can add to a span.
const CONSTANT_LIMIT: u32 = 4096;
/// Ranges closer than this are sent as one.
const MERGE_GAP: u32 = 8;

/// A code's spans `(first, last)`, and a device of the code whose numbering its heads take.
type Spans<'a> = (&'a Device, Vec<(u32, u32)>);

/// The ranges of a request's window, per device code in ascending order: `(head, last)`, the
/// units from `head` to the number `last` a unit apart ([`Device::points`]: every number for a
/// plain device, every 16th for `K4M`). The head is numbered as the case's devices are.
pub(crate) fn ranges(req: &Request<'_>) -> Vec<(Device, u32)> {
    // Only a constant the profile calls a length reaches past the operands: a value (HTOA's
    // S1 = K65535) would otherwise spread one case over thousands of words.
    let definition = req.profile.instructions.get(req.instruction);
    let is_count = |name: &str| {
        definition
            .and_then(|d| d.operands.get(name))
            .is_some_and(|o| o.count)
    };
    let longest_constant = req
        .operands
        .iter()
        .filter_map(|(name, o)| match o {
            Operand::Constant(k) if is_count(name) => u32::try_from(k.unsigned_abs()).ok(),
            _ => None,
        })
        .map(|k| k.min(CONSTANT_LIMIT))
        .max()
        .unwrap_or(0);
    let operand_span = OPERAND_SPAN + longest_constant;
    let mut spans: BTreeMap<&str, Spans<'_>> = BTreeMap::new();
    let operands = req.operands.values().filter_map(|o| match o {
        Operand::Device(d) => Some((d, operand_span)),
        Operand::Constant(_) => None,
    });
    let set = req.memory.explicit().keys().map(|d| (d, SET_SPAN));
    for (d, len) in operands.chain(set) {
        let last = d.index.saturating_add((len - 1).saturating_mul(d.points()));
        spans
            .entry(d.code())
            .or_insert_with(|| (d, Vec::new()))
            .1
            .push((d.index, last));
    }
    let mut out = Vec::new();
    for (code, (device, list)) in spans {
        let Some(ranges) = req.profile.ranges(req.variant, code) else {
            continue;
        };
        let step = device.points();
        // Clip every span to each range the device has (a gap between ranges holds no word),
        // keeping its units on their grid and whole inside the range.
        let mut pieces: Vec<(u32, u32)> = list
            .iter()
            .flat_map(|&(first, last)| {
                ranges.iter().filter_map(move |r| {
                    let first = first + r.first.saturating_sub(first).div_ceil(step) * step;
                    let end = last.min(r.last.checked_sub(step - 1)?);
                    let last = first + end.checked_sub(first)? / step * step;
                    Some((first, last))
                })
            })
            .collect();
        pieces.sort_unstable();
        let mut merged: Vec<(u32, u32)> = Vec::new();
        for (first, last) in pieces {
            match merged.last_mut() {
                Some((start, end))
                    if first <= end.saturating_add(MERGE_GAP * step)
                        && (first - *start) % step == 0 =>
                {
                    *end = (*end).max(last);
                }
                _ => merged.push((first, last)),
            }
        }
        out.extend(merged.into_iter().map(|(f, l)| (device.with_index(f), l)));
    }
    out
}

/// The window with its values before execution: explicit words and fill alike.
pub(crate) fn memory(req: &Request<'_>) -> Vec<MemoryRange> {
    let (fill, unit) = (req.memory.fill(), req.memory.unit());
    ranges(req)
        .into_iter()
        .map(|(head, last)| {
            let (first, step) = (head.index, head.points());
            let mut device = head.clone();
            let mut words = Vec::with_capacity(((last - first) / step + 1) as usize);
            for index in (first..=last).step_by(step as usize) {
                device.index = index;
                words.push(fill.value(&device, unit));
            }
            let end = head.with_index(last);
            for (d, value) in req.memory.explicit().range(&head..=&end) {
                if (d.index - first) % step == 0 {
                    words[((d.index - first) / step) as usize] = *value;
                }
            }
            MemoryRange::new(head.to_string(), unit, words)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::memory::{Fill, Image};
    use crate::model::profile::Profile;

    fn profile() -> Profile {
        let mut errors = Vec::new();
        crate::load::parse_profile(
            std::path::Path::new("p.yaml"),
            "id: p\nname: P\nshort: p\nmanuals: {}\nerrors: {signal: code, flag: SM0, register: SD0}\n\
             devices: {D: {first: 0, last: 1000}}\n\
             instructions: {X: {summary: x, operands: {s: {devices: [D]}, d: {devices: [D]}, \
             n: {devices: [D], constant: true, count: true}, v: {devices: [D], constant: true}}}}\n\
             variants: [{id: v, description: v}, {id: small, description: s, devices: {D: {first: 0, last: 120}}}]\n",
            &mut errors,
        )
        .expect("profile")
    }

    /// A request of instruction X of case `c` on the variant.
    fn request<'a>(
        profile: &'a Profile,
        variant: &str,
        flags: &'a BTreeMap<String, bool>,
        operands: &'a BTreeMap<String, Operand>,
        memory: &'a Image,
    ) -> Request<'a> {
        Request {
            profile,
            variant: profile.variant(variant).expect("variant"),
            instruction: "X",
            case_id: "c",
            flags,
            operands,
            indirect: crate::model::DIRECT,
            memory,
        }
    }

    fn request_ranges(
        profile: &Profile,
        variant: &str,
        operands: &[(&str, Operand)],
        set: &[u32],
    ) -> Vec<(String, u32, u32)> {
        let operands: BTreeMap<String, Operand> = operands
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect();
        let image = Image::new(
            set.iter().map(|i| (Device::new("D", *i), 0)).collect(),
            Fill::A,
        );
        let flags = BTreeMap::new();
        ranges(&request(profile, variant, &flags, &operands, &image))
            .into_iter()
            .map(|(head, last)| (head.code().to_string(), head.index, last))
            .collect()
    }

    fn dev(i: u32) -> Operand {
        Operand::Device(Device::new("D", i))
    }

    #[test]
    fn covers_operands_and_set_words_merged() {
        let p = profile();
        let r = request_ranges(&p, "v", &[("s", dev(100)), ("d", dev(200))], &[100, 101]);
        assert_eq!(
            r,
            vec![("D".into(), 100, 163), ("D".into(), 200, 263)],
            "the set words lie inside the operand span"
        );
        let r = request_ranges(&p, "v", &[("s", dev(100)), ("d", dev(150))], &[]);
        assert_eq!(r, vec![("D".into(), 100, 213)]);
    }

    #[test]
    fn a_count_operand_widens_the_span() {
        let p = profile();
        // A value (HTOA's S1 = K65535) is no length: the span stays the operand's.
        for (operand, constant, last) in [("n", 100, 163), ("v", 65535, 63)] {
            let r = request_ranges(
                &p,
                "v",
                &[("s", dev(0)), (operand, Operand::Constant(constant))],
                &[],
            );
            assert_eq!(r, vec![("D".into(), 0, last)], "{operand} = {constant}");
        }
    }

    #[test]
    fn a_digit_designation_sends_its_units_sixteen_points_apart() {
        let mut errors = Vec::new();
        let p = crate::load::parse_profile(
            std::path::Path::new("p.yaml"),
            "id: p\nname: P\nshort: p\nmanuals: {}\nerrors: {signal: code, flag: SM0, register: SD0}\n\
             devices: {K4M: {first: 0, last: 1023, points_per_word: 16}}\ninstructions: {}\n\
             variants: [{id: v, description: v}]\n",
            &mut errors,
        )
        .expect("profile");
        let head = Device::new("K4M", 100);
        let operands = BTreeMap::from([("s".to_string(), Operand::Device(head.clone()))]);
        let image = Image::new(BTreeMap::from([(Device::new("K4M", 116), 0x1234)]), Fill::B);
        let flags = BTreeMap::new();
        let req = request(&p, "v", &flags, &operands, &image);
        // K4M100 .. K4M996: the last whole 16 points end at M1011, before M1023.
        assert_eq!(ranges(&req), vec![(head.clone(), 996)]);
        let window = memory(&req);
        let range = serde_json::to_value(&window[0]).expect("json");
        let words = range["words"].as_array().expect("words");
        assert_eq!(range["start"], "K4M100");
        assert_eq!(words.len(), 57);
        assert_eq!(words[1], 0x1234, "K4M116 is the second unit");
        assert_eq!(words[0], Fill::B.word(&head));
    }

    #[test]
    fn clips_to_the_variant_range() {
        let p = profile();
        let ranges = p.ranges(p.variant("small").expect("v"), "D").expect("D");
        assert_eq!((ranges.first, ranges.last), (0, 120));
        let r = request_ranges(&p, "small", &[("s", dev(100))], &[]);
        assert_eq!(r, vec![("D".into(), 100, 120)]);
        let r = request_ranges(&p, "small", &[("s", dev(500))], &[]);
        assert!(r.is_empty(), "{r:?}");
    }
}
