//! plc-conformance: a differential conformance harness for PLC instructions.
//!
//! Data flows one way: [`load`] reads vector files and vendor profiles into a validated
//! [`model::Corpus`]; [`plan`] pairs every case with every backend variant that should run it;
//! each [`backend::Backend`] executes a case on a [`memory::Image`]; [`compare`] judges the
//! outcome against the expectation; [`report`] renders the verdicts.
//!
//! Beside that main line: [`neutral`] asks every vendor the same cross-vendor question through
//! its own instruction and lifts the answers back to comparable values; [`matrix`] arranges
//! results as cases x backends with rows grouped by behaviour; [`baseline`] keeps a run and
//! compares a later one with it; [`backend::external`] runs implementations in other processes
//! over the documented protocol; [`session`] ties a project's data and backends together.

pub mod backend;
pub mod baseline;
pub mod cli;
pub mod compare;
pub mod device;
pub mod load;
pub mod matrix;
pub mod memory;
pub mod model;
pub mod neutral;
pub mod plan;
pub mod profile;
pub mod report;
pub mod session;
pub mod spec;
pub mod value;
