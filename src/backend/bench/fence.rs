//! The write fence: the only way to build a write to a CPU, over any link.
//!
//! A live CPU's memory outside the words a bench user gave the harness may hold anything,
//! including what a machine depends on. Every batch write is therefore built here, from a
//! declared set of word ranges (the sandbox the case windows go to, and the mailbox words the PC
//! owns), and a write that touches one word outside them is refused while it is still a value in
//! memory: before any byte is encoded, let alone sent. [`FencedWrite`] has no other constructor,
//! and a link's only write method takes one.

use std::fmt;

use super::addressing::Addressing;
pub(crate) use super::addressing::Kind;
use crate::device::{Device, DeviceSyntaxError};

/// A run of words of one device code, both ends included: `D0-D11999`, or `D12000` alone.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct WordRange {
    pub code: String,
    pub first: u32,
    pub last: u32,
    /// The CPU numbers the code in hexadecimal (`W1A-W1F`).
    pub hex: bool,
}

impl WordRange {
    /// A range of a decimal-numbered code.
    pub fn new(code: &str, first: u32, last: u32) -> Self {
        WordRange {
            code: code.to_string(),
            first,
            last,
            hex: false,
        }
    }

    /// The words `first` to `last` of `head`'s code, numbered as `head` is.
    pub fn within(head: &Device, first: u32, last: u32) -> Self {
        WordRange {
            hex: head.is_hexadecimal(),
            ..WordRange::new(head.code(), first, last)
        }
    }

    /// The words `count` from `head` (at least one).
    pub fn of(head: &Device, count: u32) -> Self {
        WordRange::within(
            head,
            head.index,
            head.index.saturating_add(count.max(1) - 1),
        )
    }

    /// The first word, as a device.
    pub fn head(&self) -> Device {
        match self.hex {
            true => Device::hexadecimal(&self.code, self.first),
            false => Device::new(&self.code, self.first),
        }
    }

    pub fn contains(&self, other: &WordRange) -> bool {
        self.code == other.code && self.first <= other.first && other.last <= self.last
    }

    pub fn overlaps(&self, other: &WordRange) -> bool {
        self.code == other.code && self.first <= other.last && other.first <= self.last
    }

    pub fn len(&self) -> u32 {
        self.last - self.first + 1
    }

    pub fn is_empty(&self) -> bool {
        false
    }
}

/// Numbers as the CPU writes them: `W1A-W1F` for a hexadecimal-numbered device.
impl fmt::Display for WordRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (code, first, last) = (&self.code, self.first, self.last);
        match (self.hex, first == last) {
            (true, true) => write!(f, "{code}{first:X}"),
            (true, false) => write!(f, "{code}{first:X}-{code}{last:X}"),
            (false, true) => write!(f, "{code}{first}"),
            (false, false) => write!(f, "{code}{first}-{code}{last}"),
        }
    }
}

/// A range of words that does not read: its text, and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RangeError {
    text: String,
    problem: RangeProblem,
}

#[derive(Debug, Clone, PartialEq, Eq)]
enum RangeProblem {
    /// An end that is not a device.
    Device(DeviceSyntaxError),
    /// Ends of two different devices.
    Mixed(String, String),
    /// The first word after the last.
    Reversed,
}

impl fmt::Display for RangeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = &self.text;
        match &self.problem {
            RangeProblem::Device(_) => write!(
                f,
                "`{s}`: a range is written `D0-D11999`, `W0-W1FF` or `D12000`"
            ),
            RangeProblem::Mixed(a, b) => {
                write!(f, "`{s}`: both ends must be the same device ({a} and {b})")
            }
            RangeProblem::Reversed => write!(f, "`{s}`: the first word is after the last"),
        }
    }
}

impl std::error::Error for RangeError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &self.problem {
            RangeProblem::Device(e) => Some(e),
            _ => None,
        }
    }
}

impl WordRange {
    /// Reads `D0-D11999` or `D12000`, numbered as the link's CPU numbers the code.
    pub fn parse(s: &str, addressing: &dyn Addressing) -> Result<Self, RangeError> {
        let s = s.trim();
        let error = |problem| RangeError {
            text: s.to_string(),
            problem,
        };
        let parse = |t: &str| {
            Device::parse_numbered(t, |code: &str| addressing.hex_numbered(code))
                .map_err(|e| error(RangeProblem::Device(e)))
        };
        let (first, last) = match s.split_once('-') {
            Some((a, b)) => (parse(a)?, parse(b)?),
            None => (parse(s)?, parse(s)?),
        };
        if first.code() != last.code() {
            let (a, b) = (first.code().to_string(), last.code().to_string());
            return Err(error(RangeProblem::Mixed(a, b)));
        }
        if first.index > last.index {
            return Err(error(RangeProblem::Reversed));
        }
        Ok(WordRange::within(&first, first.index, last.index))
    }
}

/// Why a range cannot be part of a sandbox, if it cannot: a bit device (an output, a relay; a
/// word of one is 16 points) is never written, whatever the sandbox says.
pub(crate) fn sandbox_refuses(range: &WordRange, addressing: &dyn Addressing) -> Option<String> {
    (addressing.kind(&range.head()) == Kind::Bit).then(|| {
        format!(
            "{range}: a sandbox holds word devices only ({}); the live backend never writes a \
             bit device such as an output or a relay",
            addressing.sandbox_devices()
        )
    })
}

/// Reads a comma-separated list of ranges.
pub(crate) fn parse_ranges(
    text: &str,
    addressing: &dyn Addressing,
) -> Result<Vec<WordRange>, RangeError> {
    text.split(',')
        .filter(|t| !t.trim().is_empty())
        .map(|t| WordRange::parse(t, addressing))
        .collect()
}

/// Ranges sorted and merged where they touch or overlap.
pub(crate) fn merged(mut ranges: Vec<WordRange>) -> Vec<WordRange> {
    ranges.sort();
    let mut out: Vec<WordRange> = Vec::with_capacity(ranges.len());
    for r in ranges {
        match out.last_mut() {
            Some(prev) if prev.code == r.code && r.first <= prev.last.saturating_add(1) => {
                prev.last = prev.last.max(r.last);
            }
            _ => out.push(r),
        }
    }
    out
}

/// A write the fence refused.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refused {
    /// The words asked for.
    pub asked: WordRange,
    /// What the fence allows.
    pub allowed: Vec<WordRange>,
    /// Why, when it is not "outside" (a device the link cannot address, an encoding limit).
    pub detail: Option<String>,
}

impl fmt::Display for Refused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.detail {
            Some(d) => write!(f, "a write to {} is refused: {d}", self.asked),
            None => write!(
                f,
                "a write to {} is refused: it lies outside the words the harness may write ({})",
                self.asked,
                list(&self.allowed)
            ),
        }
    }
}

impl std::error::Error for Refused {}

/// Ranges as one line.
pub(crate) fn list(ranges: &[WordRange]) -> String {
    if ranges.is_empty() {
        return "none".into();
    }
    ranges
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The words the harness may write.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct WriteFence {
    allowed: Vec<WordRange>,
}

/// One write the fence let through: the words and where they go. A link encodes it; nothing
/// else can make one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FencedWrite {
    head: Device,
    words: Vec<u16>,
    range: WordRange,
}

impl FencedWrite {
    pub fn head(&self) -> &Device {
        &self.head
    }
    pub fn words(&self) -> &[u16] {
        &self.words
    }
    pub fn range(&self) -> &WordRange {
        &self.range
    }
}

impl WriteFence {
    pub(crate) fn new(allowed: Vec<WordRange>) -> Self {
        WriteFence {
            allowed: merged(allowed),
        }
    }

    #[cfg(test)]
    pub(crate) fn allowed(&self) -> &[WordRange] {
        &self.allowed
    }

    /// Whether every word of `asked` may be written.
    pub(crate) fn check(&self, asked: &WordRange) -> Result<(), Refused> {
        if self.allowed.iter().any(|r| r.contains(asked)) {
            Ok(())
        } else {
            Err(Refused {
                asked: asked.clone(),
                allowed: self.allowed.clone(),
                detail: None,
            })
        }
    }

    /// The writes of `words` from `head`, at most `batch` words each (the link's limit), once
    /// every word is inside the fence; nothing is built when one is not.
    pub(crate) fn writes(
        &self,
        batch: usize,
        head: &Device,
        words: &[u16],
    ) -> Result<Vec<FencedWrite>, Refused> {
        let asked = WordRange::of(head, words.len() as u32);
        let refuse = |detail: String| Refused {
            asked: asked.clone(),
            allowed: self.allowed.clone(),
            detail: Some(detail),
        };
        if words.is_empty() {
            return Err(refuse("no words".into()));
        }
        if u32::try_from(words.len()).is_err()
            || head.index.checked_add(words.len() as u32).is_none()
        {
            return Err(refuse("the range runs past the last device number".into()));
        }
        self.check(&asked)?;
        let batch = batch.max(1);
        Ok(words
            .chunks(batch)
            .enumerate()
            .map(|(i, chunk)| {
                let at = head.with_index(head.index + (i * batch) as u32);
                FencedWrite {
                    range: WordRange::of(&at, chunk.len() as u32),
                    head: at,
                    words: chunk.to_vec(),
                }
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    use crate::backend::bench::addressing::Plain;

    fn fence() -> WriteFence {
        WriteFence::new(
            parse_ranges("D0-D11999, D12008-D12011, D12100-D18431", &Plain).expect("ranges"),
        )
    }

    #[rstest]
    #[case("D0", 1, true)]
    #[case("D11999", 1, true)]
    #[case("D11999", 2, false)]
    #[case("D12000", 1, false)]
    #[case("D12008", 4, true)]
    #[case("D12008", 5, false)]
    #[case("D12007", 2, false)]
    #[case("D18431", 1, true)]
    #[case("D18432", 1, false)]
    #[case("R0", 1, false)]
    #[case("SD0", 1, false)]
    fn allows_only_inside(#[case] head: &str, #[case] count: usize, #[case] ok: bool) {
        let head: Device = head.parse().expect("device");
        let r = fence().writes(960, &head, &vec![0; count]);
        assert_eq!(r.is_ok(), ok, "{head} x{count}: {r:?}");
    }

    #[test]
    fn touching_ranges_merge_and_long_writes_split() {
        let f = WriteFence::new(parse_ranges("D0-D99,D100-D2000", &Plain).expect("ranges"));
        assert_eq!(f.allowed(), &[WordRange::new("D", 0, 2000)]);
        let writes = f
            .writes(960, &Device::new("D", 0), &[7; 2001])
            .expect("inside");
        let ranges: Vec<String> = writes.iter().map(|w| w.range().to_string()).collect();
        assert_eq!(ranges, ["D0-D959", "D960-D1919", "D1920-D2000"]);
        // A link that takes 480 words a request.
        let writes = f
            .writes(480, &Device::new("D", 0), &[7; 961])
            .expect("inside");
        let ranges: Vec<String> = writes.iter().map(|w| w.range().to_string()).collect();
        assert_eq!(ranges, ["D0-D479", "D480-D959", "D960"]);
    }

    #[test]
    fn a_refusal_names_the_words_and_the_fence() {
        let e = fence()
            .writes(960, &Device::new("D", 11990), &[0; 20])
            .expect_err("outside");
        assert_eq!(
            e.to_string(),
            "a write to D11990-D12009 is refused: it lies outside the words the harness may \
             write (D0-D11999, D12008-D12011, D12100-D18431)"
        );
    }

    #[test]
    fn a_sandbox_holds_word_devices_only() {
        for bits in ["Y0-Y17", "M0-M15"] {
            let r = WordRange::parse(bits, &Plain).expect("range");
            let why = sandbox_refuses(&r, &Plain).expect("refused");
            assert!(why.contains("(D, R, W, and SD when named)"), "{why}");
        }
        for words in ["D0-D10", "R5", "SD100-SD167"] {
            let r = WordRange::parse(words, &Plain).expect("range");
            assert_eq!(sandbox_refuses(&r, &Plain), None, "{words}");
        }
    }

    #[rstest]
    #[case("D0-", "not a device name")]
    #[case("D5-D4", "after the last")]
    #[case("D0-R5", "same device")]
    #[case("d0", "not a device name")]
    fn bad_ranges(#[case] text: &str, #[case] message: &str) {
        let e = crate::error_chain::chain(&parse_ranges(text, &Plain).expect_err("bad"));
        assert!(e.contains(message), "{e}");
    }

    proptest::proptest! {
        /// Whatever is asked, a write is built exactly when every word is inside an allowed range.
        #[test]
        fn the_fence_never_lets_a_word_out(
            allowed in proptest::collection::vec((0u32..200, 0u32..50), 0..4),
            head in 0u32..300,
            count in 1usize..80,
        ) {
            let ranges: Vec<WordRange> = allowed.iter().map(|(a, n)| WordRange::new("D", *a, a + n)).collect();
            let fence = WriteFence::new(ranges.clone());
            let inside = (head..head + count as u32).all(|w| ranges.iter().any(|r| r.first <= w && w <= r.last));
            let built = fence.writes(960, &Device::new("D", head), &vec![0; count]);
            proptest::prop_assert_eq!(built.is_ok(), inside);
        }
    }
}
