//! The crate's internals as its own integration tests and benchmarks reach them.
//!
//! Nothing here is part of the supported interface: an emulator or codec author depends on the
//! items at the crate root, which keep their names and meaning across releases; these paths
//! follow the modules inside and may move with them. The tests of this repository use them to
//! hold the simulated CPUs the command line runs against, the sweep's internals and the loaders
//! to what the manuals say, which the public interface has no reason to expose. The bench's
//! white-box tests (its clients, simulated CPUs and backend), the loader's, the corpus's through
//! the backends, and the external backends' that need no binary (the adapters and codecs written
//! with the helpers, the protocol schema) live beside their code instead.

pub mod backend {
    pub mod external {
        pub use crate::backend::external::{ExternalBackend, ExternalErrorKind};
    }
    pub mod bench {
        pub mod manifest {
            pub use crate::backend::bench::manifest::Manifest;
        }
    }
    pub mod modbus {
        pub use crate::backend::modbus::Map;
        pub mod sim {
            pub use crate::backend::modbus::sim::{ModbusSimSettings, ModbusSimulator};
        }
    }
    pub mod slmp {
        pub use crate::backend::slmp::ADDRESSING;
        pub mod frame {
            pub use crate::backend::slmp::frame::command;
        }
        pub mod sim {
            pub use crate::backend::slmp::sim::{FaultRule, SlmpSimSettings, SlmpSimulator};
        }
    }
}
pub mod error_chain {
    pub use crate::error_chain::chain;
}
pub mod execute {
    pub use crate::execute::{execute_all, images, requests, Pace, Progress};
}
pub mod hil {
    pub use crate::hil::{generate, GenerateOptions};
}
pub mod known_draft {
    pub use crate::known_draft::draft;
}
pub mod libtest {
    /// Runs a harness under libtest's arguments `args` (without the program name): libtest's
    /// conclusion, or the lines of why it refused to run anything.
    pub fn conclude(
        harness: crate::Harness,
        args: &[&str],
    ) -> Result<libtest_mimic::Conclusion, Vec<String>> {
        let args = libtest_mimic::Arguments::from_iter(
            std::iter::once("harness").chain(args.iter().copied()),
        );
        harness.conclude(&args).map_err(|refused| refused.0)
    }
}
pub mod load {
    pub use crate::load::{
        load_corpus, load_known, load_profiles, load_project, ENV_CONFIG, ENV_REQUIRE, ENV_SELF,
        FILE_NAME,
    };
}
pub mod model {
    pub mod project {
        pub use crate::model::project::{ExternalSettings, Launch};
    }
}
pub mod plan {
    pub use crate::plan::Input;
}
pub mod report {
    pub use crate::report::{Event, Reporter};
    pub mod progress {
        pub use crate::report::progress::ProgressReporter;
    }
}
pub mod session {
    pub use crate::session::{BackendSource, Session, SetupError};
}
pub mod sweep {
    pub use crate::sweep::{emit, render, Results, Settings, Sweep};
    pub mod generate {
        pub use crate::sweep::generate::Generator;
    }
    pub mod group {
        pub use crate::sweep::group::{labels, Groups};
    }
    pub mod input {
        pub use crate::sweep::input::{Data, Point};
    }
    pub mod shrink {
        pub use crate::sweep::shrink::candidates;
    }
    pub mod target {
        pub use crate::sweep::target::{Cases, Target};
    }
}
