//! A simulated CPU's memory: its words and bits, the addresses ADRSET stored and the operands
//! read through them, the fault rules still to fire, what it audited. Apart from the program,
//! so that a link's server reads and writes it as it would a CPU's memory.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

use super::fault::{FaultAction, FaultRule};
use crate::backend::bench::error::{refused, LiveError};
use crate::device::Device;
use crate::memory::Value;
use crate::model::Operand;

/// What the simulator received and did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Audit {
    /// Requests by command code.
    pub commands: BTreeMap<u16, usize>,
    /// Words written outside the manifest's `writes` and the mailbox's PC words.
    pub stray_writes: Vec<String>,
    /// Rung executions.
    pub executions: usize,
    /// Things the program could not do (a rung the model does not implement, ...).
    pub anomalies: Vec<String>,
    pub connections: usize,
}

pub(crate) struct Cpu {
    pub(crate) words: BTreeMap<String, Vec<u16>>,
    /// `words` as the models read them, each device named as the profile numbers it (`W1A`):
    /// built at the first execution, then kept up by [`Cpu::set_word`]. Building it for each
    /// execution cost most of a simulated run.
    pub(super) image: Option<Arc<BTreeMap<Device, Value>>>,
    pub(super) bits: BTreeMap<Device, bool>,
    pub(crate) running: bool,
    pub(super) prev: Vec<bool>,
    pub(super) prev_reset: bool,
    pub(crate) audit: Audit,
    pub(super) faults: Vec<(FaultRule, usize)>,
    /// The devices ADRSET has stored an address of: this CPU's address of a device is its
    /// place here, with [`ADDRESS_TAG`] in the pointer's second word.
    pub(super) addressed: Vec<Device>,
    /// Triggers written so far, and (with `premature_ack`) the last one kept from the program.
    pub(super) triggers: usize,
    pub(super) withheld: Option<u16>,
    /// Bits nothing turns off: a CPU whose program cannot reset its error flag.
    pub(super) held: BTreeSet<Device>,
}

/// The second word of an address as this simulated CPU's ADRSET stores it: an encoding of its
/// own, since the manuals the project quotes do not give the real one.
const ADDRESS_TAG: u16 = 0xADD5;

/// One rung of the program as the simulated CPU runs it.
pub(super) struct SimRung {
    pub(super) id: u16,
    pub(super) instruction: String,
    /// Operands, an indirect one as its pointer.
    pub(super) operands: BTreeMap<String, Operand>,
    /// The operands given by indirect specification.
    pub(super) indirect: BTreeSet<String>,
    /// ADRSET before the instruction: (pointer, the device whose address it stores).
    pub(super) addresses: Vec<(Device, Device)>,
    pub(super) pulse: bool,
}

impl Cpu {
    /// ADRSET: stores the address of `target` in `pointer` and the word after it.
    pub(super) fn adrset(&mut self, target: &Device, pointer: &Device) {
        let place = match self.addressed.iter().position(|d| d == target) {
            Some(place) => place,
            None => {
                self.addressed.push(target.clone());
                self.addressed.len() - 1
            }
        };
        self.set_word(pointer, place as u16);
        if let Some(next) = pointer.offset(1) {
            self.set_word(&next, ADDRESS_TAG);
        }
    }

    /// A rung's operands with each indirect one read through its pointer, as the CPU does when
    /// the instruction runs.
    pub(super) fn resolve(&self, rung: &SimRung) -> Result<BTreeMap<String, Operand>, LiveError> {
        let mut operands = rung.operands.clone();
        for name in &rung.indirect {
            let Some(Operand::Device(pointer)) = rung.operands.get(name) else {
                continue;
            };
            let place = self.word(pointer);
            let tag = pointer.offset(1).and_then(|d| self.word(&d));
            let target = match (place, tag) {
                (Some(place), Some(ADDRESS_TAG)) => self.addressed.get(usize::from(place)),
                _ => None,
            };
            let Some(target) = target else {
                return Err(refused!(
                    "{}: @{pointer} holds no address ADRSET stored",
                    rung.instruction
                ));
            };
            operands.insert(name.clone(), Operand::Device(target.clone()));
        }
        Ok(operands)
    }

    pub(crate) fn word(&self, d: &Device) -> Option<u16> {
        self.words
            .get(d.code())
            .and_then(|w| w.get(d.index as usize))
            .copied()
    }

    pub(crate) fn set_word(&mut self, d: &Device, value: u16) {
        if let Some(w) = self
            .words
            .get_mut(d.code())
            .and_then(|w| w.get_mut(d.index as usize))
        {
            *w = value;
            if let Some(image) = &mut self.image {
                // In place: no execution holds the image between scans.
                let image = Arc::make_mut(image);
                // The image names the word as the profile numbers its code.
                for named in [
                    Device::new(d.code(), d.index),
                    Device::hexadecimal(d.code(), d.index),
                ] {
                    if let Some(v) = image.get_mut(&named) {
                        *v = Value::from(value);
                        break;
                    }
                }
            }
        }
    }

    /// The image of every word device (see [`Cpu::image`]'s field).
    pub(super) fn image(
        &mut self,
        devices: &crate::model::profile::DeviceTable,
    ) -> Arc<BTreeMap<Device, Value>> {
        let words = &self.words;
        self.image
            .get_or_insert_with(|| {
                Arc::new(
                    words
                        .iter()
                        .flat_map(|(code, words)| {
                            let hexadecimal = devices.is_hexadecimal(code);
                            words.iter().enumerate().map(move |(i, w)| {
                                let device = match hexadecimal {
                                    true => Device::hexadecimal(code, i as u32),
                                    false => Device::new(code, i as u32),
                                };
                                (device, Value::from(*w))
                            })
                        })
                        .collect(),
                )
            })
            .clone()
    }

    pub(crate) fn bit(&self, name: &str) -> bool {
        name.parse::<Device>()
            .ok()
            .and_then(|d| self.bits.get(&d).copied())
            .unwrap_or(false)
    }

    pub(crate) fn set_bit(&mut self, name: &str, on: bool) {
        if let Ok(d) = name.parse::<Device>() {
            let on = on || self.held.contains(&d);
            self.bits.insert(d, on);
        }
    }

    /// Turns a bit on for good, or lets it go again.
    pub(crate) fn hold(&mut self, name: &str, held: bool) {
        if let Ok(d) = name.parse::<Device>() {
            match held {
                true => self.held.insert(d),
                false => self.held.remove(&d),
            };
        }
        if held {
            self.set_bit(name, true);
        }
    }

    pub(super) fn set_reg(&mut self, name: &str, value: u16) {
        if let Ok(d) = name.parse::<Device>() {
            self.set_word(&d, value);
        }
    }

    pub(super) fn reg(&self, name: &str) -> u16 {
        name.parse::<Device>()
            .ok()
            .and_then(|d| self.word(&d))
            .unwrap_or(0)
    }

    /// Adds a fault rule while running.
    pub(crate) fn add_fault(&mut self, rule: FaultRule) {
        self.faults.push((rule, 0));
    }

    /// The fault a request of `command` whose first device is `head` meets, if one fires now.
    pub(crate) fn take_fault(
        &mut self,
        command: u16,
        head: Option<&Device>,
    ) -> Option<FaultAction> {
        for (rule, seen) in self.faults.iter_mut() {
            if rule.command != command {
                continue;
            }
            if let Some(want) = &rule.head {
                if head != Some(want) {
                    continue;
                }
            }
            *seen += 1;
            if *seen == rule.nth {
                return Some(rule.action.clone());
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cpu() -> Cpu {
        Cpu {
            words: BTreeMap::from([("D".to_string(), vec![0; 400])]),
            image: None,
            bits: BTreeMap::new(),
            running: true,
            prev: Vec::new(),
            prev_reset: false,
            audit: Audit::default(),
            faults: Vec::new(),
            addressed: Vec::new(),
            triggers: 0,
            withheld: None,
            held: BTreeSet::new(),
        }
    }

    #[test]
    fn an_indirect_operand_is_read_through_the_address_adrset_stored() {
        let d = |i| Device::new("D", i);
        let rung = SimRung {
            id: 1,
            instruction: "ASCI".into(),
            operands: BTreeMap::from([
                ("s".to_string(), Operand::Device(d(10))),
                ("d".to_string(), Operand::Device(d(200))),
            ]),
            indirect: BTreeSet::from(["s".to_string()]),
            addresses: vec![(d(10), d(100))],
            pulse: false,
        };
        let mut cpu = cpu();
        let e = crate::error_chain::chain(&cpu.resolve(&rung).expect_err("no address stored yet"));
        assert!(e.contains("@D10"), "{e}");
        cpu.adrset(&d(300), &d(20));
        cpu.adrset(&d(100), &d(10));
        let operands = cpu.resolve(&rung).expect("resolved");
        assert_eq!(operands["s"], Operand::Device(d(100)));
        assert_eq!(operands["d"], Operand::Device(d(200)));
        assert_eq!(cpu.word(&d(11)), Some(ADDRESS_TAG));
        assert_ne!(
            cpu.word(&d(10)),
            cpu.word(&d(20)),
            "two devices, two addresses"
        );
    }
}
