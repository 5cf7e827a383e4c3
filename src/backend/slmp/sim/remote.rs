//! The generated program's behaviour on the memory of another SLMP server: a third-party
//! simulated CPU that holds device memory but runs no program (aslmp's simulated FX5U and
//! R04CPU). Each scan reads the mailbox (and, in the scan that executes a case, the words the
//! cases write) into a copy, runs the same scan as the simulated CPU on it, and writes back the
//! words the scan changed. The live backend then talks to the third-party server, in its code
//! and with its limits, exactly as to a CPU; only the program is this harness's.

use std::collections::BTreeMap;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::thread::JoinHandle;

use super::{program, SlmpSim, SlmpSimSettings};
use crate::backend::bench::error::LiveError;
use crate::backend::bench::fence::{parse_ranges, WordRange, WriteFence};
use crate::backend::bench::mailbox::{self, off, state};
use crate::backend::bench::sim::{scan, Audit, Program};
use crate::backend::slmp::client::{Client, ClientSettings};
use crate::backend::Backend;
use crate::device::Device;
use crate::error_chain::chain;
use crate::model::profile::Profile;

/// The program running on a remote server's memory; dropping it stops it.
pub(crate) struct RemoteProgram {
    shared: Arc<Program<SlmpSim>>,
    thread: Option<JoinHandle<()>>,
}

impl RemoteProgram {
    /// Starts scanning the memory of the server `client` reaches. The settings' port, faults
    /// and protocol options do not apply: the server is someone else's.
    pub(crate) fn start(
        settings: SlmpSimSettings,
        profile: Arc<Profile>,
        model: Arc<dyn Backend>,
        client: ClientSettings,
    ) -> Result<RemoteProgram, LiveError> {
        let shared = program(settings, profile, model)?;
        let writes = parse_ranges(
            &shared.settings.manifest.writes.join(","),
            &super::super::ADDRESSING,
        )
        .map_err(|e| LiveError::within("the manifest's `writes`", e))?;
        // Every word of the copy is the program's to write, as a CPU's own memory is.
        let fence = WriteFence::new(
            (shared.lock().words.iter())
                .map(|(code, w)| WordRange::new(code, 0, w.len().saturating_sub(1) as u32))
                .collect(),
        );
        // A CPU in RUN has scanned before anyone can connect to it.
        let mut client = Client::new(client);
        remote_scan(&shared, &mut client, &writes, &fence)?;
        let s = shared.clone();
        let thread = std::thread::spawn(move || {
            while !s.stop.load(Ordering::SeqCst) {
                if let Err(why) = remote_scan(&s, &mut client, &writes, &fence) {
                    s.lock().audit.anomalies.push(chain(&why));
                }
                std::thread::sleep(s.settings.scan);
            }
        });
        Ok(RemoteProgram {
            shared,
            thread: Some(thread),
        })
    }

    pub(crate) fn audit(&self) -> Audit {
        self.shared.lock().audit.clone()
    }
}

impl Drop for RemoteProgram {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// One scan: memory in, the program, changed words out.
fn remote_scan(
    shared: &Program<SlmpSim>,
    client: &mut Client,
    writes: &[WordRange],
    fence: &WriteFence,
) -> Result<(), LiveError> {
    let mut cpu = shared.lock();
    let mb = &shared.mailbox;
    let mut reads = vec![mailbox::range(mb)];
    let words = client.read_words(mb, mailbox::WORDS)?;
    let word = |o: u32| words.get(o as usize).copied().unwrap_or(0);
    // The scan that runs the selected rung reads what the PC set for the case.
    if word(off::TRIGGER) != word(off::ACK) && word(off::STATE) == state::EXECUTING {
        reads.extend(writes.iter().cloned());
    }
    for range in &reads {
        let head = Device::new(&range.code, range.first);
        let read = client.read_words(&head, range.len())?;
        for (i, w) in read.into_iter().enumerate() {
            cpu.set_word(&Device::new(&range.code, range.first + i as u32), w);
        }
    }
    let before: BTreeMap<String, Vec<u16>> = cpu.words.clone();
    scan(shared, &mut cpu);
    let limits = client.settings().limits;
    let mut out = Vec::new();
    for (code, after) in &cpu.words {
        let Some(was) = before.get(code) else {
            continue;
        };
        for (first, run) in changed_runs(was, after) {
            out.push((Device::new(code, first), run.to_vec()));
        }
    }
    // A CPU's scan lands at once; written word by word, the acknowledgement goes last, so that
    // a PC that sees it also sees everything else the scan wrote.
    let ack = mailbox::at(mb, off::ACK);
    let (last, first): (Vec<_>, Vec<_>) = split_off(out, &ack)
        .into_iter()
        .partition(|(d, _)| ack.is(d.code(), d.index));
    for (head, words) in first.iter().chain(&last) {
        let built = fence.writes(limits.batch_words, head, words)?;
        for w in built {
            client.write(&w)?;
        }
    }
    Ok(())
}

/// The runs with `word` cut out of the one that holds it, as a run of its own.
fn split_off(runs: Vec<(Device, Vec<u16>)>, word: &Device) -> Vec<(Device, Vec<u16>)> {
    let mut out = Vec::with_capacity(runs.len() + 2);
    for (head, words) in runs {
        let end = head.index + words.len() as u32;
        if head.code() != word.code() || word.index < head.index || word.index >= end {
            out.push((head, words));
            continue;
        }
        let at = (word.index - head.index) as usize;
        if at > 0 {
            out.push((head.clone(), words[..at].to_vec()));
        }
        out.push((head.with_index(word.index), vec![words[at]]));
        if at + 1 < words.len() {
            out.push((head.with_index(word.index + 1), words[at + 1..].to_vec()));
        }
    }
    out
}

/// The runs of words that differ, as (first index, the new words).
fn changed_runs<'a>(was: &[u16], now: &'a [u16]) -> Vec<(u32, &'a [u16])> {
    let mut runs = Vec::new();
    let mut i = 0;
    while i < now.len() {
        if was.get(i) == Some(&now[i]) {
            i += 1;
            continue;
        }
        let start = i;
        while i < now.len() && was.get(i) != Some(&now[i]) {
            i += 1;
        }
        runs.push((start as u32, &now[start..i]));
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_changed_runs_are_written_back() {
        let runs = changed_runs(&[1, 2, 3, 4, 5], &[1, 9, 9, 4, 6]);
        assert_eq!(runs, vec![(1, &[9, 9][..]), (4, &[6][..])]);
        assert!(changed_runs(&[1, 2], &[1, 2]).is_empty());
        let d = |i| Device::new("D", i);
        let split = split_off(vec![(d(8), vec![1, 2, 3]), (d(20), vec![4])], &d(9));
        assert_eq!(
            split,
            vec![
                (d(8), vec![1]),
                (d(9), vec![2]),
                (d(10), vec![3]),
                (d(20), vec![4])
            ]
        );
    }
}
