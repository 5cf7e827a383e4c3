//! Lowering a cross-vendor case onto a profile's instruction: the operands, flags and memory
//! that ask the vendor's instruction the case's question. (Lifting the answer back is the
//! judge's part.)

use super::Input;
use crate::memory::{Unit, Value};
use crate::model::cross_vendor::{CrossVendorCase, Lowering, Operation, ValueOrder};
use crate::model::{Indirect, Operand};
use crate::text::significant_digits;

/// A value spread over `count` units of memory, in `order`.
pub(crate) fn value_units(value: u64, unit: Unit, order: ValueOrder, count: u32) -> Vec<Value> {
    let bits = unit.bits();
    let part = |i: u32| (value.checked_shr(bits * i).unwrap_or(0) & u64::from(unit.max())) as Value;
    match order {
        ValueOrder::LowFirst => (0..count).map(part).collect(),
        ValueOrder::HighFirst => (0..count).rev().map(part).collect(),
    }
}

/// The value `units` hold, read in `order`.
pub(crate) fn units_value(
    units: impl Iterator<Item = Value>,
    unit: Unit,
    order: ValueOrder,
) -> u64 {
    let bits = unit.bits();
    match order {
        ValueOrder::LowFirst => units
            .enumerate()
            .fold(0, |acc, (i, u)| acc | u64::from(u) << (bits * i as u32)),
        ValueOrder::HighFirst => units.fold(0, |acc, u| acc << bits | u64::from(u)),
    }
}

/// A value as an instruction reading `digits` digits finds it at its source, in at least
/// `min_units` units. Low first, as many units as the value needs or the digits read, the upper
/// ones zero, so that an instruction reading past the value reads zeros, not the fill; high
/// first, the units the digits read, ending with the least significant.
pub(crate) fn value_memory(
    value: u64,
    digits: u32,
    min_units: u32,
    unit: Unit,
    order: ValueOrder,
) -> Vec<Value> {
    let needed = match order {
        ValueOrder::LowFirst => significant_digits(value)
            .div_ceil(unit.digits())
            .max(min_units),
        ValueOrder::HighFirst => 1,
    };
    value_units(value, unit, order, units_for(digits, needed, unit))
}

/// How many units hold a value of `digits` hex digits, and at least the `needed` ones.
pub(crate) fn units_for(digits: u32, needed: u32, unit: Unit) -> u32 {
    digits
        .div_ceil(unit.digits())
        .max(needed)
        .clamp(1, 64 / unit.bits())
}

/// The input that runs `case` through `lowering`.
pub(crate) fn input(lowering: &Lowering, case: &CrossVendorCase) -> Input {
    let mut operands = lowering.operands.clone();
    let mut count_word = None;
    if let Some(count) = &lowering.count {
        let digits = i64::from(case.digits);
        // A count the instruction cannot take as a constant is read from a register, as a
        // program would have to give it.
        match (&lowering.count_register, lowering.count_constants) {
            (Some(register), Some(range)) if !range.contains(digits) => {
                operands.insert(count.clone(), Operand::Device(register.clone()));
                count_word = Some((register.clone(), case.digits as Value));
            }
            _ => {
                operands.insert(count.clone(), Operand::Constant(digits));
            }
        }
    }
    let words: Vec<Value> = match lowering.operation {
        Operation::HexToValue => lowering.text.units(lowering.unit, &case.text),
        Operation::ValueToHex => {
            let digits = lowering.width.unwrap_or(case.digits);
            value_memory(case.value, digits, 1, lowering.unit, lowering.order)
        }
    };
    let mut before: std::collections::BTreeMap<_, _> = words
        .into_iter()
        .enumerate()
        .filter_map(|(i, w)| lowering.source.offset(i as u32).map(|d| (d, w)))
        .collect();
    before.extend(count_word);
    Input {
        instruction: lowering.instruction.clone(),
        flags: lowering.flags.clone(),
        operands,
        indirect: Indirect::new(),
        before,
    }
}
