//! Lifting a vendor's outcome back to a cross-vendor [`Answer`]: the value its destination
//! holds, the text it wrote, or the class of its error.

use crate::backend::Outcome;
use crate::memory::Image;
use crate::model::cross_vendor::{Answer, Lowering, Operation, TextLayout};
use crate::model::profile::Profile;

/// The answer an outcome gives to a cross-vendor case asked with `digits` digits.
pub fn lift(
    profile: &Profile,
    lowering: &Lowering,
    digits: u32,
    outcome: &Outcome,
    memory: &Image,
) -> Answer {
    if let Some(signal) = &outcome.error {
        return profile.cross_vendor.classify(signal);
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
        Operation::HexToValue => {
            let words = digits.div_ceil(4).clamp(1, 4);
            let value = (0..words)
                .filter_map(|i| destination.offset(i))
                .enumerate()
                .fold(0u64, |acc, (i, d)| acc | u64::from(read(&d)) << (16 * i));
            Answer::Value(value)
        }
        Operation::ValueToHex => {
            let mut text = Vec::new();
            for k in 0..digits {
                let ch = match lowering.text {
                    TextLayout::Packed => destination.offset(k / 2).map(|d| {
                        let w = read(&d);
                        if k % 2 == 0 {
                            w as u8
                        } else {
                            (w >> 8) as u8
                        }
                    }),
                    TextLayout::Words => destination.offset(k).map(|d| read(&d) as u8),
                };
                match ch {
                    Some(0) | None => break,
                    Some(c) => text.push(c),
                }
            }
            Answer::Text(text)
        }
    }
}
