//! A simulated CPU's program: the generated test program's behaviour run with a reference
//! model on a CPU's memory, for a link's simulated CPU (a server on 127.0.0.1 speaking the
//! link's protocol) to serve, so that a bench backend can be tested end to end without hardware
//! and be made to fail in each way a real port fails.
//!
//! A scan thread takes the memory lock once per scan, so requests interleave between scans as
//! they do with END processing, and runs the program as generated: the signature and scan
//! counter every scan; on a new trigger, an error reset (the reset flag's rising edge clears the
//! error flag and registers at the end of the scan), then one scan with the selected rung
//! enabled, the error flag and registers captured in that scan and the error register again one
//! scan later, then the acknowledgement. Every rung is evaluated every scan with its own enable,
//! and a pulse form (`...P`) executes only on its enable's rising edge, which is what makes the
//! same pulse rung fire again on the next case.
//!
//! Everything a server received is audited: the requests, and every written word that lies
//! outside the manifest's `writes` and the mailbox's PC words (a stray write the tests fail on).

mod cpu;
mod fault;
mod scan;
mod server;

#[cfg(test)]
pub(crate) use cpu::Audit;
pub(crate) use cpu::Cpu;
pub(crate) use fault::FaultAction;
pub use fault::FaultRule;
#[cfg(test)]
pub(crate) use scan::scan;
pub(crate) use scan::Program;
pub(crate) use scan::SimSettings;
pub(crate) use server::Running;
