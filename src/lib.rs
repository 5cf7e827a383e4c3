//! plc-conformance: a differential conformance harness for PLC instructions.
//!
//! Data flows one way, one module per stage, none importing from a later one:
//!
//! - [`spec`]: the on-disk formats (vector files, cross-vendor files, profiles, the project file,
//!   known-differences files), shape only;
//! - [`load`]: turns them into the validated [`model`] (corpus, profiles, project backends,
//!   known differences), reporting every problem with `file:line` and key;
//! - [`plan`]: pairs every case with every backend, variant and instruction (or cross-vendor
//!   lowering) into [`plan::Trial`]s, deciding what is skipped or cannot fail;
//! - [`execute`]: runs trials on their [`backend`]s under both fills, batched per backend;
//! - [`judge`]: turns observations into one [`judge::Verdict`] and applies known differences;
//! - [`report`]: reporters fed by events render text, JSON, JUnit, HTML and matrices.
//!
//! [`runner`] drives the stages for a project, [`sweep`] runs generated inputs through them and
//! groups and shrinks what the backends disagree on, [`libtest`] maps them onto libtest trials
//! for `cargo test` (and for emulators written in Rust), and [`cli`] is the command line;
//! [`interrupt`] makes SIGINT and SIGTERM end a run with what it has and no backend running.
//! [`device`], [`value`], [`memory`] and [`text`] are shared leaves.

pub mod backend;
pub mod cli;
pub mod device;
pub mod execute;
pub mod hil;
pub mod interrupt;
pub mod judge;
pub mod known_draft;
pub mod libtest;
pub mod load;
pub mod memory;
pub mod model;
pub mod plan;
pub mod record;
pub mod report;
pub mod runner;
pub mod session;
pub mod spec;
pub mod sweep;
pub mod text;
pub mod value;
