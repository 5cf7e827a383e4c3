//! Lowering a cross-vendor case onto a profile's instruction: the operands, flags and memory
//! that ask the vendor's instruction the case's question. (Lifting the answer back is the
//! judge's part.)

use std::collections::BTreeMap;

use super::Input;
use crate::device::Device;
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
    Input {
        instruction: lowering.instruction.clone(),
        flags: lowering.flags.clone(),
        operands: operands(lowering, case.digits),
        indirect: Indirect::new(),
        before: memory(lowering, case),
    }
}

/// Where the count of a lowering that takes one comes from for a number of digits.
struct Count<'l> {
    /// The operand that takes it.
    name: &'l String,
    /// A constant, or, when the instruction cannot take the count as a constant, a register
    /// holding it, as a program would have to give it.
    operand: Operand,
    /// The register and the count it holds, for a count given in one.
    word: Option<(Device, Value)>,
}

fn count(lowering: &Lowering, digits: u32) -> Option<Count<'_>> {
    let name = lowering.count.as_ref()?;
    Some(match (&lowering.count_register, lowering.count_constants) {
        (Some(register), Some(range)) if !range.contains(i64::from(digits)) => Count {
            name,
            operand: Operand::Device(register.clone()),
            word: Some((register.clone(), digits as Value)),
        },
        _ => Count {
            name,
            operand: Operand::Constant(i64::from(digits)),
            word: None,
        },
    })
}

/// The operands of `lowering` for a case of `digits` digits: the same for every case of that
/// count, so a sweep makes them once.
pub(crate) fn operands(lowering: &Lowering, digits: u32) -> BTreeMap<String, Operand> {
    let mut operands = lowering.operands.clone();
    if let Some(count) = count(lowering, digits) {
        operands.insert(count.name.clone(), count.operand);
    }
    operands
}

/// The memory `lowering` sets for `case`: the text or the value at the source, and the count's
/// register when the count is given in one.
pub(crate) fn memory(lowering: &Lowering, case: &CrossVendorCase) -> BTreeMap<Device, Value> {
    let words: Vec<Value> = match lowering.operation {
        // A lowering of a check operation is refused when its profile loads.
        Operation::HexToValue | Operation::Check | Operation::Verify => {
            lowering.text.units(lowering.unit, &case.text)
        }
        Operation::ValueToHex => {
            let digits = lowering.width.unwrap_or(case.digits);
            value_memory(case.value, digits, 1, lowering.unit, lowering.order)
        }
    };
    let mut before = BTreeMap::new();
    for (i, w) in words.into_iter().enumerate() {
        if let Some(d) = lowering.source.offset(i as u32) {
            before.insert(d, w);
        }
    }
    if let Some((register, value)) = count(lowering, case.digits).and_then(|c| c.word) {
        before.insert(register, value);
    }
    before
}
