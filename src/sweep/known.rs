//! Known differences in a sweep: the entries of a judged backend's known-differences file that
//! name their cause by the classes of its input (`input: [lowercase, sign, ...]`) cover the
//! generated inputs of those classes too, so a codec's author can sweep in CI and fail only on
//! what is not yet listed; an entry for every case (`cases: ['*']`) covers any input, values
//! included. An entry covers a group of a column when it covers the group's first input and
//! the first input of each of its classes, with the column's instruction (or lowering, or
//! `codec`) and variant; a case entry never covers a generated input. A sweep
//! does not report stale entries: it asks what its generator makes, not every case a cause
//! names.

use std::collections::{BTreeMap, HashMap};

use super::group::{Key, KnownColumn};
use super::input::Data;
use super::{ColumnInfo, Results};
use crate::model::known::{Entry, KnownDifferences, Subject};

/// Moves every covered column of every group from `differing` to `known`; `known` holds the
/// known-differences files by backend name. A value (of a value-to-hex sweep) has no input
/// class, so only an entry for every case (`cases: ['*']`) covers it; the answer is whether a
/// value group still differs on a backend that has a known-differences file, which the caller
/// says, so that no entry seems to be ignored silently.
pub(crate) fn apply(results: &mut Results, known: &BTreeMap<String, KnownDifferences>) -> bool {
    let mut values_uncovered = false;
    if known.is_empty() {
        return values_uncovered;
    }
    // Shrunk inputs name their group by its place in the sorted order, which puts differing
    // groups first: remember the order to renumber them after.
    let order: Vec<Key> = results
        .groups
        .sorted()
        .iter()
        .map(|g| g.key.clone())
        .collect();
    let columns = &results.columns;
    for group in results.groups.by_key.values_mut() {
        let texts: Vec<Option<&[u8]>> = std::iter::once(&group.representative)
            .chain(group.classes.values().map(|c| &c.first))
            .map(|f| match &f.point.data {
                Data::Text(t) => Some(t.as_slice()),
                Data::Value(_) => None,
            })
            .collect();
        let mut covered = Vec::new();
        group.differing.retain(|name| {
            let entry = columns
                .iter()
                .find(|c| &c.name == name)
                .and_then(|c| Some((c, known.get(&c.backend)?)))
                .and_then(|(c, k)| covering(k, c, &texts));
            match entry {
                Some(e) => {
                    covered.push(KnownColumn {
                        column: name.clone(),
                        reason: e.reason.clone(),
                        location: e.location.clone(),
                    });
                    false
                }
                None => true,
            }
        });
        values_uncovered |= texts.iter().any(Option::is_none)
            && group.differing.iter().any(|name| {
                columns
                    .iter()
                    .any(|c| &c.name == name && known.contains_key(&c.backend))
            });
        group.known.extend(covered);
    }
    let place: HashMap<&Key, usize> = results
        .groups
        .sorted()
        .into_iter()
        .enumerate()
        .map(|(i, g)| (&g.key, i))
        .collect();
    let wholly_known = |key: &Key| {
        results
            .groups
            .by_key
            .get(key)
            .is_some_and(|g| g.differing.is_empty() && !g.known.is_empty())
    };
    // A wholly known group's shrunk inputs are not new: nothing to emit.
    let shrunk = std::mem::take(&mut results.shrunk);
    results.shrunk = shrunk
        .into_iter()
        .filter_map(|mut s| {
            let key = order.get(s.group)?;
            s.group = *place.get(key)?;
            (!wholly_known(key)).then_some(s)
        })
        .collect();
    values_uncovered
}

/// The entry that covers every input for the column, if one does: a text by its classes, a
/// value (`None`) only by a pattern that takes any case.
fn covering<'k, 't>(
    known: &'k KnownDifferences,
    column: &ColumnInfo,
    texts: &[Option<&'t [u8]>],
) -> Option<&'k Entry> {
    let subject = |text: &Option<&'t [u8]>| Subject {
        case: "",
        text: *text,
        instruction: &column.check,
        variant: &column.variant,
    };
    let first = known.entry(&subject(texts.first()?))?;
    (first.case().is_none() && texts.iter().all(|t| first.matches(&subject(t)))).then_some(first)
}
