//! The manifest of a generated test program: which rung runs which instruction on which
//! operands, where the mailbox is, which flags the mailbox's flag word sets, and the hash that
//! the program writes into the mailbox so that the PC knows the CPU runs this very program.
//!
//! The simulator and the live backend both read the rung table from here, so neither parses the
//! program text. A manifest whose hash does not match its content (edited by hand) is refused:
//! the program on the CPU would then say one thing and the table another.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::addressing::Addressing;
use super::fence::{parse_ranges, Kind};
use super::mailbox;
use crate::backend::bench::error::{refused, LiveError};
use crate::device::Device;
use crate::model::{Indirect, Operand};

/// The manifest format this harness reads and writes.
pub(crate) const FORMAT: u32 = 1;

/// One rung: an instruction on fixed operands, selected by its id.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rung {
    /// 1 upwards; 0 in the mailbox selects no rung.
    pub id: u16,
    pub instruction: String,
    /// Operand name -> `D100`, a constant as `K-1`, or `@D10` for indirect specification.
    pub operands: BTreeMap<String, String>,
    /// For each pointer of an `@` operand, the device whose address the rung stores in it
    /// (ADRSET) before the instruction.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub addresses: BTreeMap<String, String>,
}

/// An instruction and operands the corpus uses but the program cannot hold, with why.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Unrealisable {
    pub instruction: String,
    pub operands: BTreeMap<String, String>,
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub addresses: BTreeMap<String, String>,
    pub reason: String,
}

/// Where the program finds an operation error.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ErrorDevices {
    /// The flag an error turns on.
    pub flag: String,
    /// The register with the code; none where the profile signals errors with the flag
    /// alone (IDEC).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub register: Option<String>,
    /// A further register the profile says receives the code.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extra: Option<String>,
    /// The flag that resets the error state on its rising edge; the error flag itself where
    /// the program resets it directly (the profile's `bench.error_reset`).
    pub reset: String,
}

/// A generated program's manifest.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    pub format: u32,
    /// `plc-conformance <version>`.
    pub generator: String,
    /// The profile id.
    pub profile: String,
    /// The variants the rung table was collected for.
    pub variants: Vec<String>,
    /// The mailbox's first word.
    pub mailbox: String,
    pub layout: u16,
    /// The mailbox flag word: bit i sets `flags[i]` for the executed scan.
    pub flags: Vec<String>,
    pub error: ErrorDevices,
    pub rungs: Vec<Rung>,
    #[serde(default)]
    pub unrealisable: Vec<Unrealisable>,
    /// Every word a case window writes, merged: what a sandbox must at least allow.
    pub writes: Vec<String>,
    /// FNV-1a 64 of the program-defining fields, 16 hex digits.
    pub hash: String,
}

/// The fields that define the program, and the words its cases write: what the hash covers,
/// so that neither the program nor the sandbox `sandbox=manifest` takes can be edited by hand.
#[derive(Serialize)]
struct Program<'a> {
    profile: &'a str,
    mailbox: &'a str,
    layout: u16,
    flags: &'a [String],
    error: &'a ErrorDevices,
    rungs: &'a [Rung],
    writes: &'a [String],
}

/// The largest manifest read: a corpus's program is tens of kilobytes.
pub(crate) const MAX_BYTES: u64 = 16 << 20;

/// The highest device number the Q-compatible device form can carry (three bytes): no
/// mailbox word or write may lie past it.
pub(crate) const MAX_NUMBER: u32 = 0x00FF_FFFF;

fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// An instruction call as a program writes it: the operands (`K4`, `D100`, and `@D10` for one
/// given by indirect specification, so that such a call never shares the rung of the device it
/// addresses), and each pointer with the device whose address the rung stores in it first.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Call {
    pub operands: BTreeMap<String, String>,
    pub addresses: BTreeMap<String, String>,
}

impl Call {
    pub(crate) fn new(operands: &BTreeMap<String, Operand>, indirect: &Indirect) -> Call {
        let mut call = Call::default();
        for (name, value) in operands {
            let text = match (indirect.get(name), value) {
                (Some(pointer), Operand::Device(target)) => {
                    call.addresses
                        .insert(pointer.to_string(), target.to_string());
                    format!("@{pointer}")
                }
                _ => value.to_string(),
            };
            call.operands.insert(name.clone(), text);
        }
        call
    }

    /// The key a request and a rung share: the instruction and the call in one canonical
    /// text (`ASCI d=D200 n=K4 s=@D10 @D10=D100`).
    pub(crate) fn key(&self, instruction: &str) -> String {
        rung_key(instruction, &self.operands, &self.addresses)
    }
}

fn rung_key(
    instruction: &str,
    operands: &BTreeMap<String, String>,
    addresses: &BTreeMap<String, String>,
) -> String {
    let mut key = instruction.to_string();
    for (name, value) in operands {
        key.push_str(&format!(" {name}={value}"));
    }
    for (pointer, target) in addresses {
        key.push_str(&format!(" @{pointer}={target}"));
    }
    key
}

impl Rung {
    pub fn key(&self) -> String {
        rung_key(&self.instruction, &self.operands, &self.addresses)
    }
}

impl Unrealisable {
    pub fn key(&self) -> String {
        rung_key(&self.instruction, &self.operands, &self.addresses)
    }
}

/// Reads an operand as the manifest writes it; `hexadecimal` says which codes are numbered in
/// hexadecimal (a rung's devices as the CPU numbers them, an unrealisable one's as the profile
/// does).
pub(crate) fn parse_operand(
    text: &str,
    hexadecimal: &dyn Fn(&str) -> bool,
) -> Result<Operand, LiveError> {
    // An indirect operand (`@D10`) is read as its pointer: only an unrealisable rung names one.
    let text = text.strip_prefix('@').unwrap_or(text);
    // Constants are written `K<decimal>`, as [`Operand`]'s display does; a device that starts
    // with K is a digit designation (`K4M0`), which is no number.
    let device = || Device::parse_numbered(text, hexadecimal).map(Operand::Device);
    if text.starts_with('K') {
        return crate::value::parse_number(text)
            .map(Operand::Constant)
            .or_else(|number| device().map_err(|_| LiveError::within(text, number)));
    }
    device().map_err(|e| LiveError::within(text, e))
}

impl Manifest {
    /// The hash of the program-defining fields.
    pub fn compute_hash(&self) -> String {
        let program = Program {
            profile: &self.profile,
            mailbox: &self.mailbox,
            layout: self.layout,
            flags: &self.flags,
            error: &self.error,
            rungs: &self.rungs,
            writes: &self.writes,
        };
        let bytes = serde_json::to_vec(&program).unwrap_or_default();
        format!("{:016X}", fnv1a64(&bytes))
    }

    /// The low 32 bits of the hash: what the program writes into the mailbox.
    pub fn hash32(&self) -> u32 {
        u64::from_str_radix(&self.hash, 16).map_or(0, |h| h as u32)
    }

    /// The mailbox head, where a mailbox may be: in a data register the link reaches (where a
    /// sandbox may be, never a special, bit or timer device), all 32 words within the device
    /// numbers.
    pub fn mailbox_head(&self, addressing: &dyn Addressing) -> Result<Device, LiveError> {
        let head = mailbox::head(&self.mailbox, addressing)
            .map_err(|e| LiveError::within("`mailbox`", e))?;
        if addressing.kind(&head) != Kind::Data || addressing.unaddressable(&head).is_some() {
            return Err(refused!(
                "`mailbox`: {head} is not a {}: the mailbox lies where a sandbox may be",
                addressing.data_devices()
            ));
        }
        let fits = (head.index.checked_add(mailbox::WORDS - 1)).is_some_and(|l| l <= MAX_NUMBER);
        if !fits {
            return Err(refused!(
                "`mailbox`: {head} leaves no room for its {} words below {}{MAX_NUMBER}",
                mailbox::WORDS,
                head.code()
            ));
        }
        // Every word, not the head alone: on an IDEC CPU whose D runs on into its special
        // registers, D7990 would put the program's words on D8000 on (D8002: the identity the
        // interlock reads).
        let special = (1..mailbox::WORDS)
            .map(|i| head.with_index(head.index + i))
            .find(|w| addressing.kind(w) != Kind::Data || addressing.unaddressable(w).is_some());
        if let Some(word) = special {
            return Err(refused!(
                "`mailbox`: {head} runs into {word}, which is not a {}: every one of its {} \
                 words lies where a sandbox may be",
                addressing.data_devices(),
                mailbox::WORDS
            ));
        }
        Ok(head)
    }

    /// What the program writes into the mailbox's signature words.
    pub fn signature(&self) -> mailbox::Signature {
        mailbox::Signature::expected(self.hash32(), self.rungs.len() as u16)
    }

    /// The rungs by [`rung_key`].
    pub fn rung_index(
        &self,
        addressing: &dyn Addressing,
    ) -> Result<HashMap<String, u16>, LiveError> {
        let mut index = HashMap::new();
        for rung in &self.rungs {
            let texts = (rung.operands.iter())
                .chain(rung.addresses.iter().flat_map(|(p, t)| [(p, p), (p, t)]));
            for (k, v) in texts {
                parse_operand(v, &|code| addressing.hex_numbered(code))
                    .map_err(|e| LiveError::within(format!("rung {} operand `{k}`", rung.id), e))?;
            }
            if index.insert(rung.key(), rung.id).is_some() {
                return Err(refused!(
                    "rung {} repeats an earlier rung's instruction and operands",
                    rung.id
                ));
            }
        }
        Ok(index)
    }

    /// Checks what the file cannot: the format, the hash, the mailbox, rung ids 1..n in order.
    pub fn validate(&self, addressing: &dyn Addressing) -> Result<(), LiveError> {
        if self.format != FORMAT {
            return Err(refused!(
                "`format` is {}; this harness reads format {FORMAT}",
                self.format
            ));
        }
        if self.layout != mailbox::LAYOUT {
            return Err(refused!(
                "`layout` is {}; this harness speaks mailbox layout {}",
                self.layout,
                mailbox::LAYOUT
            ));
        }
        self.mailbox_head(addressing)?;
        for (i, rung) in self.rungs.iter().enumerate() {
            if usize::from(rung.id) != i + 1 {
                return Err(refused!(
                    "rung {} is at position {}; rungs are numbered 1, 2, ... in order",
                    rung.id,
                    i + 1
                ));
            }
        }
        if self.flags.len() > 16 {
            return Err(refused!(
                "more than 16 flags do not fit the mailbox flag word"
            ));
        }
        for range in parse_ranges(&self.writes.join(","), addressing)
            .map_err(|e| LiveError::within("`writes`", e))?
        {
            if range.last > MAX_NUMBER {
                return Err(refused!(
                    "`writes`: {range} runs past {}{MAX_NUMBER}",
                    range.code
                ));
            }
            if let Some(why) = super::fence::sandbox_refuses(&range, addressing) {
                return Err(refused!("`writes`: {why}"));
            }
        }
        self.rung_index(addressing)?;
        let computed = self.compute_hash();
        if computed != self.hash {
            return Err(refused!(
                "`hash` is {} but the content hashes to {computed}: the manifest was changed \
                 after it was generated; generate it again (and the program with it)",
                self.hash
            ));
        }
        Ok(())
    }

    /// Reads and validates a manifest file; errors name the file. Read as the YAML files are:
    /// a regular file only (a FIFO would block, a device never end), and at most
    /// [`MAX_BYTES`].
    pub fn load(path: &Path, addressing: &dyn Addressing) -> Result<Manifest, LiveError> {
        Manifest::read(path)?
            .validated(addressing)
            .map_err(|e| LiveError::within(path.display().to_string(), e))
    }

    /// The manifest, once [`Manifest::validate`] passed.
    pub fn validated(self, addressing: &dyn Addressing) -> Result<Manifest, LiveError> {
        self.validate(addressing)?;
        Ok(self)
    }

    /// Reads a manifest file without validating it: for a caller that learns from its profile
    /// which link's addressing validates it.
    pub fn read(path: &Path) -> Result<Manifest, LiveError> {
        let unreadable = |e| LiveError::within(format!("{}: cannot be read", path.display()), e);
        let size = std::fs::metadata(path).map_err(unreadable)?.len();
        if size > MAX_BYTES {
            return Err(refused!(
                "{}: {size} bytes; a manifest is at most {MAX_BYTES}",
                path.display()
            ));
        }
        let bytes = crate::load::read_regular(path).map_err(unreadable)?;
        let text = String::from_utf8(bytes)
            .map_err(|e| LiveError::within(format!("{}: cannot be read", path.display()), e))?;
        let manifest: Manifest = serde_json::from_str(&text).map_err(|e| {
            LiveError::within(
                format!(
                    "{}:{}: not a plc-conformance manifest",
                    path.display(),
                    e.line()
                ),
                e,
            )
        })?;
        Ok(manifest)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::bench::addressing::Plain;

    /// An IDEC-like CPU whose D runs on into its special registers at D8000.
    struct SpecialFrom8000;

    impl Addressing for SpecialFrom8000 {
        fn hex_numbered(&self, _: &str) -> bool {
            false
        }
        fn kind(&self, device: &Device) -> Kind {
            match device.index {
                8000..=8499 => Kind::Special,
                _ => Kind::Data,
            }
        }
        fn unaddressable(&self, _: &Device) -> Option<String> {
            None
        }
        fn sandbox_devices(&self) -> &'static str {
            "D"
        }
        fn data_devices(&self) -> &'static str {
            "data register (D)"
        }
    }

    /// The head alone is not enough: a mailbox at D7990 would put the program's words on the
    /// special registers from D8000 (D8002 the identity the interlock reads).
    #[test]
    fn a_mailbox_running_into_special_registers_is_refused() {
        let mut m = sample();
        m.mailbox = "D7990".into();
        let e = m
            .mailbox_head(&SpecialFrom8000)
            .expect_err("runs into D8000");
        assert!(e.to_string().contains("D7990 runs into D8000"), "{e}");
        m.mailbox = "D7968".into();
        assert_eq!(
            m.mailbox_head(&SpecialFrom8000).ok(),
            Some(Device::new("D", 7968))
        );
    }

    pub(super) fn sample() -> Manifest {
        use crate::test_support::{manifest, rung};
        manifest(
            "mitsubishi-iqr",
            "rcpu",
            "D12000",
            ErrorDevices {
                flag: "SM0".into(),
                register: Some("SD0".into()),
                extra: None,
                reset: "SM50".into(),
            },
            vec![
                rung(1, "HABIN", &[("s", "D100"), ("d", "D200")]),
                rung(2, "BINHA", &[("s", "K-1"), ("d", "D200")]),
            ],
            &["D100-D263"],
            &["SM701", "SM705"],
        )
    }

    #[test]
    fn a_generated_manifest_validates_and_finds_its_rungs() {
        let m = sample();
        m.validate(&Plain).expect("valid");
        let index = m.rung_index(&Plain).expect("index");
        let ops = BTreeMap::from([
            ("s".to_string(), Operand::Constant(-1)),
            ("d".to_string(), Operand::Device(Device::new("D", 200))),
        ]);
        let key = Call::new(&ops, crate::model::DIRECT).key("BINHA");
        assert_eq!(index.get(&key), Some(&2));
        let indirect = BTreeMap::from([("d".to_string(), Device::new("D", 10))]);
        let key = Call::new(&ops, &indirect).key("BINHA");
        assert_eq!(
            key, "BINHA d=@D10 s=K-1 @D10=D200",
            "an indirect operand is written as such, with what its pointer addresses"
        );
        assert_eq!(index.get(&key), None);
    }

    #[test]
    fn an_edited_manifest_is_refused() {
        let mut m = sample();
        m.rungs[0].operands.insert("s".into(), "D101".into());
        let e = crate::error_chain::chain(&m.validate(&Plain).expect_err("stale hash"));
        assert!(e.contains("changed after it was generated"), "{e}");
        // The words the cases write are under the hash too: a sandbox taken from them cannot
        // be widened by hand.
        let mut m = sample();
        m.writes.push("D0".into());
        let e = crate::error_chain::chain(&m.validate(&Plain).expect_err("writes are hashed"));
        assert!(e.contains("changed after it was generated"), "{e}");
        // The generator's name is not.
        let mut m = sample();
        m.generator = "another".into();
        m.validate(&Plain).expect("the generator is not hashed");
    }

    /// A mailbox lies where a sandbox may be, with its 32 words within the device numbers:
    /// never at the end of the numbers (where its words would wrap), in special registers,
    /// outputs, relays or timers.
    #[test]
    fn a_mailbox_lies_where_a_sandbox_may_be() {
        for (mailbox, says) in [
            ("D16777200", "leaves no room"),
            ("D4294967290", "leaves no room"),
            ("SD0", "not a data or link register"),
            ("SM0", "not a data or link register"),
            ("Y0", "not a data or link register"),
            ("T0", "not a data or link register"),
        ] {
            let mut m = sample();
            m.mailbox = mailbox.into();
            m.hash = m.compute_hash();
            let e = crate::error_chain::chain(&m.validate(&Plain).expect_err(mailbox));
            assert!(e.contains(says), "{mailbox}: {e}");
        }
        let mut m = sample();
        m.mailbox = "W100".into();
        m.hash = m.compute_hash();
        m.validate(&Plain).expect("link registers take a mailbox");
    }

    #[test]
    fn writes_to_bit_devices_are_refused() {
        let mut m = sample();
        m.writes.push("Y0-Y17".into());
        m.hash = m.compute_hash();
        let e = crate::error_chain::chain(&m.validate(&Plain).expect_err("a bit device"));
        assert!(e.contains("word devices only"), "{e}");
    }

    #[test]
    fn operands_read_back() {
        assert_eq!(
            parse_operand("K-1", &|_| false).ok(),
            Some(Operand::Constant(-1))
        );
        assert_eq!(
            parse_operand("D100", &|_| false).ok(),
            Some(Operand::Device(Device::new("D", 100)))
        );
        assert!(parse_operand("x", &|_| false).is_err());
        assert_eq!(
            parse_operand("K4M0", &|_| false).ok(),
            Some(Operand::Device(Device::new("K4M", 0)))
        );
        assert_eq!(
            parse_operand("SWF", &|code| code == "SW").ok(),
            Some(Operand::Device(Device::hexadecimal("SW", 15)))
        );
    }
}
