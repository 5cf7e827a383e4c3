//! A real MELSEC CPU as a backend, over SLMP (binary, TCP).

pub mod client;
pub mod fence;
pub mod frame;
pub mod mailbox;
