//! Lifting a vendor's outcome back to a cross-vendor [`Answer`]: the value its destination
//! holds, the text it wrote, or the class of its error.

use crate::backend::Outcome;
use crate::memory::Image;
use crate::model::cross_vendor::{Answer, Lowering, Operation};
use crate::model::profile::Profile;
use crate::plan::lowering::{units_for, units_value};

/// The answer an outcome gives to a cross-vendor case asked with `digits` digits.
pub(crate) fn lift(
    profile: &Profile,
    lowering: &Lowering,
    digits: u32,
    outcome: &Outcome,
    memory: &Image,
) -> Answer {
    let mut error = None;
    if let Some(signal) = &outcome.error {
        match profile.cross_vendor.classify(signal) {
            Answer::Error(class)
                if lowering.operation == Operation::HexToValue
                    && profile.cross_vendor.writes_on(signal) =>
            {
                error = Some(class)
            }
            answer => return answer,
        }
    }
    let read = |d: &crate::device::Device| {
        outcome
            .writes
            .get(d)
            .copied()
            .unwrap_or_else(|| memory.read(d))
    };
    let destination = &lowering.destination;
    let digits = lowering.width.unwrap_or(digits);
    match lowering.operation {
        // The text inputs; a lowering of a check operation is refused when its profile loads.
        Operation::HexToValue | Operation::Check | Operation::Verify => {
            let units = units_for(digits, 1, lowering.unit);
            let values = (0..units)
                .filter_map(|i| destination.offset(i))
                .map(|d| read(&d));
            let value = units_value(values, lowering.unit, lowering.order);
            match error {
                Some(class) => Answer::ErrorAndValue(class, value),
                None => Answer::Value(value),
            }
        }
        Operation::ValueToHex => {
            let mut text = Vec::new();
            for k in 0..digits {
                let ch = (lowering.text).char_at(lowering.unit, k, |i| {
                    destination.offset(i).map(|d| read(&d))
                });
                match ch {
                    Some(0) | None => break,
                    Some(c) => text.push(c),
                }
            }
            Answer::Text(text)
        }
    }
}
