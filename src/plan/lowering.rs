//! Lowering a cross-vendor case onto a profile's instruction: the operands, flags and memory
//! that ask the vendor's instruction the case's question. (Lifting the answer back is the
//! judge's part.)

use super::Input;
use crate::model::cross_vendor::{CrossVendorCase, Lowering, Operation, TextLayout};
use crate::model::Operand;
use crate::text::pack_low_first;

/// The input that runs `case` through `lowering`.
pub fn input(lowering: &Lowering, case: &CrossVendorCase) -> Input {
    let mut operands = lowering.operands.clone();
    let mut count_word = None;
    if let Some(count) = &lowering.count {
        let digits = i64::from(case.digits);
        // A count the instruction cannot take as a constant is read from a register, as a
        // program would have to give it.
        match (&lowering.count_register, lowering.count_constants) {
            (Some(register), Some(range)) if !range.contains(digits) => {
                operands.insert(count.clone(), Operand::Device(register.clone()));
                count_word = Some((register.clone(), case.digits as u16));
            }
            _ => {
                operands.insert(count.clone(), Operand::Constant(digits));
            }
        }
    }
    let words: Vec<u16> = match lowering.operation {
        Operation::HexToValue => {
            let mut chars = case.text.clone();
            chars.push(0);
            match lowering.text {
                TextLayout::Packed => pack_low_first(&chars),
                TextLayout::Words => chars.iter().map(|c| u16::from(*c)).collect(),
            }
        }
        Operation::ValueToHex => {
            // As many words as the value needs or the digits read, the upper ones zero, so that
            // an instruction reading past the value reads zeros, not the fill.
            let v = case.value;
            let digits = lowering.width.unwrap_or(case.digits);
            let needed = if v > 0xFFFF { 2 } else { 1 };
            let count = digits.div_ceil(4).clamp(needed, 4);
            (0..count).map(|i| (v >> (16 * i)) as u16).collect()
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
        before,
    }
}
